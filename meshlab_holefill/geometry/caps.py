"""Caps of a patch without inner vertices split open, so that smoothing has a vertex to move.

A loop triangulated with its own vertices only (a least-bend triangulation of a small, slit-like
hole) can keep a cap: a triangle whose largest angle is near 180 degrees because one loop vertex
lies almost on the chord joining two others. Where that chord cannot be swapped (the swap would
duplicate an edge the mesh already has) nothing but a new vertex removes the cap, and the sliver
repairs of the filters move inner vertices only.
"""
from __future__ import annotations

import numpy as np

from .quality import corner_angles, triangle_quality
from .topology import interior_edges, undirected_keys

__all__ = ["CAP_ANGLE", "split_caps", "split_loop_caps", "split_quads"]

#: A triangle's largest angle above which it is a cap (120 degrees, as the obtuse-angle splits of smoothing).
CAP_ANGLE = 2.0 * np.pi / 3.0


def split_caps(V, F, floor, fixed_edges=(), candidates=None):
    """Split the chord under each cap of quality below ``floor`` by a vertex inside the quad beside it.

    For a cap (a, b, c), its largest angle at c above :data:`CAP_ANGLE`, on an interior edge
    (a, b) that is not in ``fixed_edges``, with (b, a, d) the triangle across the edge, the two
    triangles become (a, m, c), (m, b, c), (b, m, d), (m, a, d) with m the mean of a, b, c and d:
    the midpoint of (a, b) would leave (a, m, c) and (m, b, c) as flat as the cap, where c lies
    near that midpoint. Each triangle is split once at most (the flattest cap first), and only
    where the four new triangles are each better than the worse of the two they replace. m lies
    inside the tetrahedron (a, b, c, d), off the surface where the quad is not flat: the caller
    checks crossings.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        Patch triangles, consistently oriented.
    floor : float
        Quality 2r/R below which a cap is split.
    fixed_edges : (p, 2) int, optional
        Edges that may not be split (the hole's border is never interior; chords of the mesh).
    candidates : (m,) bool, optional
        The triangles that may count as caps (default: all).

    Returns
    -------
    V : (n + s, 3) float64  with the s new vertices appended
    F : (m + 2 s, 3) int64  the split triangles replaced in place, two new ones per split appended

    Examples
    --------
    A flat cap over the diagonal of a quad: one vertex inside it, four triangles, none flat.

    >>> V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.02, 0], [1, -1, 0]], float)
    >>> F = np.array([[0, 1, 2], [1, 0, 3]])
    >>> V2, F2 = split_caps(V, F, floor=0.3)
    >>> len(V2), len(F2), bool(triangle_quality(V2, F2).min() > triangle_quality(V, F).min())
    (5, 4, True)
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    n = len(V)
    q = triangle_quality(V, F)
    if not np.any(q < floor):
        return V, F
    E, f1, c1, f2, c2 = interior_edges(F, n)
    if len(E) == 0:
        return V, F
    ang = corner_angles(V, F)
    o1, o2 = (c1 + 2) % 3, (c2 + 2) % 3  # the corner opposite the edge in each of its faces
    poor = q < floor if candidates is None else (q < floor) & np.asarray(candidates, bool)
    cap1 = poor[f1] & (ang[f1, o1] > CAP_ANGLE)
    cap2 = poor[f2] & (ang[f2, o2] > CAP_ANGLE)
    chosen = cap1 | cap2
    if len(fixed_edges):
        chosen &= ~np.isin(undirected_keys(E, n), undirected_keys(fixed_edges, n))
    idx = np.flatnonzero(chosen)
    if len(idx) == 0:
        return V, F
    a, b = E[idx, 0], E[idx, 1]
    c, d = F[f1[idx], o1[idx]], F[f2[idx], o2[idx]]
    M = 0.25 * (V[a] + V[b] + V[c] + V[d])
    X = np.concatenate([V, M])
    m = n + np.arange(len(idx))
    new = [np.stack(t, axis=1) for t in ((a, m, c), (m, b, c), (b, m, d), (m, a, d))]
    q_new = np.min([triangle_quality(X, t) for t in new], axis=0)
    cap_quality = np.where(cap1[idx], q[f1[idx]], np.inf)
    cap_quality = np.minimum(cap_quality, np.where(cap2[idx], q[f2[idx]], np.inf))
    replaced = np.minimum(q[f1[idx]], q[f2[idx]])
    used = np.zeros(len(F), bool)
    keep = []
    for i in np.argsort(cap_quality, kind="stable").tolist():  # the flattest cap first
        if q_new[i] <= replaced[i] or used[f1[idx[i]]] or used[f2[idx[i]]]:
            continue
        used[f1[idx[i]]] = used[f2[idx[i]]] = True
        keep.append(i)
    if not keep:
        return V, F
    keep = np.asarray(keep)
    return split_quads(V, F, f1[idx[keep]], f2[idx[keep]], a[keep], b[keep], c[keep], d[keep], M[keep])


def split_quads(V, F, f1, f2, a, b, c, d, points):
    """Split each edge (a, b) between faces f1 = (a, b, c) and f2 = (b, a, d) by a new vertex m.

    m is the edge's row of ``points``; f1 becomes (a, m, c), f2 (b, m, d), and (m, b, c), (m, a, d) are appended: the orientation is
    kept. The edges' faces must be distinct.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int64
    f1, f2, a, b, c, d : (s,) int64
    points : (s, 3) float64

    Returns
    -------
    V : (n + s, 3) float64, F : (m + 2 s, 3) int64
    """
    m = len(V) + np.arange(len(a))
    F = F.copy()
    F[f1] = np.stack([a, m, c], axis=1)
    F[f2] = np.stack([b, m, d], axis=1)
    F = np.concatenate([F, np.stack([m, b, c], axis=1), np.stack([m, a, d], axis=1)])
    return np.concatenate([V, points]), F


def split_loop_caps(V, F, k, floor):
    """:func:`split_caps` on the triangles below ``floor`` whose three corners are loop vertices (index < ``k``).

    No move of a patch's inner vertices reaches such a triangle: a split gives its cap an inner
    vertex the sliver repairs can move.

    Parameters
    ----------
    V : (n, 3) float64  the loop's k points, then the patch's inner vertices
    F : (m, 3) int64
    k : int
    floor : float

    Returns
    -------
    V, F  as :func:`split_caps` (unchanged when there is no such cap)
    """
    F = np.asarray(F, np.int64)
    return split_caps(V, F, floor, candidates=(F < k).all(axis=1))
