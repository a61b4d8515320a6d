"""A hole's loop triangulated so that no triangle bends sharply against its neighbours or the mesh.

The dynamic programme of Barequet and Sharir with Liepa's weight: over all triangulations of
the loop that use its vertices only, the one whose largest dihedral bend (between two of its
triangles sharing an edge, or between a triangle on a loop edge and the mesh face beyond it) is
smallest, ties broken by the least area. Where the border is jagged (a border cut through
triangles, a noisy scan) the mesh faces beside the hole tilt every way, and a triangulation that
looks at the loop alone folds onto them; bending against them is what this one avoids.
O(k^3) time and O(k^2) memory for k loop vertices (0.05-0.2 s at k = 300-500, 1.7 s at k = 1000).
"""
from __future__ import annotations

import numpy as np

from ..errors import HoleFillError
from . import _dihedral_kernels as K

__all__ = ["dihedral_triangulation", "least_bend_splits", "split_triangles"]


def dihedral_triangulation(P, border_normals, forbidden_edges=(), banned=()):
    """Triangulate a loop by the least largest dihedral bend, then the least area.

    Parameters
    ----------
    P : (k, 3) float64
        Loop points in patch orientation (the triangles come out oriented as the loop).
    border_normals : (k, 3) float64
        Unit normal of the mesh face on each loop edge (i, i + 1); a zero row (no usable face there)
        bends nothing.
    forbidden_edges : (p, 2) int
        Pairs of loop indices that may not become edges (already joined by a mesh edge).
    banned : (b, 3) int
        Triangles (i, m, j), i < m < j, that may not be used (for example ones found to cross the mesh).

    Returns
    -------
    F : (k - 2, 3) int64
        Triangles (i, m, j) with i < m < j, in loop indices.

    Raises
    ------
    ValueError
        When P or border_normals is not (k, 3).
    HoleFillError
        When the loop has fewer than 3 vertices or no triangulation avoids the forbidden edges
        and banned triangles.

    References
    ----------
    G. Barequet and M. Sharir, "Filling gaps in the boundary of a polyhedron", Computer Aided
    Geometric Design 12(2), 1995. P. Liepa, "Filling holes in meshes", Eurographics Symposium on
    Geometry Processing, 2003.

    Examples
    --------
    A square hole in the plane z = 0, the mesh beside it flat too: two triangles, both flat.

    >>> P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    >>> dihedral_triangulation(P, np.tile([0.0, 0.0, 1.0], (4, 1))).tolist()
    [[0, 1, 3], [1, 2, 3]]
    """
    split, worst = least_bend_splits(P, border_normals, forbidden_edges, banned)
    if not np.isfinite(worst):
        raise HoleFillError("no triangulation of the loop avoids the mesh's edges and the banned triangles")
    T = split_triangles(split)
    return T[np.lexsort(T.T[::-1])]  # rows in increasing order


def least_bend_splits(P, border_normals, forbidden_edges=(), banned=()):
    """The dynamic programme's table behind :func:`dihedral_triangulation` (same parameters).

    Returns
    -------
    split : (k, k) int64
        The apex m of the best triangulation of each sub-polygon (i .. j), -1 where there is none.
    worst : float
        The best triangulation's largest bend, 1 - cos of its angle (inf when there is none).

    Raises
    ------
    ValueError
        When P or border_normals is not (k, 3).
    HoleFillError
        When the loop has fewer than 3 vertices (no triangulation at all is ``worst`` = inf).
    """
    P = np.ascontiguousarray(P, np.float64)
    k = len(P)
    if k < 3:
        raise HoleFillError("a loop of fewer than 3 vertices cannot be triangulated")
    if P.shape != (k, 3) or np.shape(border_normals) != (k, 3):
        raise ValueError(f"P and border_normals must be ({k}, 3), got {P.shape} and {np.shape(border_normals)}")
    forbidden = np.zeros((k, k), bool)
    pairs = np.asarray(forbidden_edges, np.int64).reshape(-1, 2)
    forbidden[pairs[:, 0], pairs[:, 1]] = forbidden[pairs[:, 1], pairs[:, 0]] = True
    T = np.sort(np.asarray(banned, np.int64).reshape(-1, 3), axis=1)
    codes = np.unique((T[:, 0] * k + T[:, 1]) * k + T[:, 2])
    split, worst = K.best_splits(P, np.ascontiguousarray(border_normals, np.float64), forbidden, codes)
    return split, float(worst)


def split_triangles(split):
    """The triangles of the best triangulation of (0, k - 1), read off the split table.

    Parameters
    ----------
    split : (k, k) int  :func:`least_bend_splits`' table (its whole loop has a triangulation)

    Returns
    -------
    (k - 2, 3) int64
        Triangles (i, m, j), i < m < j, in reading order: from the whole loop inwards, the
        second part of each split first.
    """
    k = len(split)
    faces, stack = [], [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i >= 2:
            m = int(split[i, j])
            faces.append((i, m, j))
            stack += [(i, m), (m, j)]
    return np.array(faces, np.int64).reshape(-1, 3)
