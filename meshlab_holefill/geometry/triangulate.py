"""Constrained Delaunay triangulation of a simple planar polygon (wrapping Shewchuk's Triangle)."""
from __future__ import annotations

import numpy as np
import triangle

from ..errors import HoleFillError

__all__ = ["polygon_signed_area", "polygon_perimeter", "triangulate_polygon"]


def polygon_signed_area(Q):
    """Signed area of a closed 2D polygon (positive when counter-clockwise), Q : (k, 2)."""
    x, y = Q[:, 0], Q[:, 1]
    return 0.5 * float(np.dot(x, _next_rows(y)) - np.dot(_next_rows(x), y))


def polygon_perimeter(P):
    """Length of a closed polygon, P : (m, d)."""
    P = np.asarray(P, np.float64)
    return float(np.linalg.norm(_next_rows(P) - P, axis=1).sum())


def _next_rows(P):
    """``np.roll(P, -1, axis=0)``: row i + 1 at row i, the first row last (without roll's axis handling,
    its main cost on the small polygons of a hole)."""
    return np.concatenate((P[1:], P[:1]))


def triangulate_polygon(Q, max_area=None, min_angle=None, extra_points=None, steiner_on_boundary=False):
    """Constrained Delaunay triangulation of the simple polygon Q, every polygon edge kept.

    Without ``max_area``/``min_angle`` no Steiner point is inserted (Triangle switches
    ``p`` and ``Y``); with them Triangle refines the interior (Chew/Ruppert), still without
    points on the boundary unless ``steiner_on_boundary``.

    Parameters
    ----------
    Q : (k, 2) float64
        Polygon vertices in order (either orientation); must be simple.
    max_area : float, optional
        Upper bound on triangle area (switch ``a``).
    min_angle : float, optional
        Lower bound on angles in degrees (switch ``q``; Triangle guarantees up to ~33 deg).
    extra_points : (p, 2) float64, optional
        Interior points to insert as vertices (e.g. predicted points).
    steiner_on_boundary : bool

    Returns
    -------
    points : (k + s, 2) float64
        The polygon vertices first, unchanged and in order, then interior points.
    faces : (t, 3) int64
        Oriented like Q: counter-clockwise faces for a counter-clockwise Q, clockwise for a
        clockwise one, so that lifting to 3D keeps the loop's patch orientation.

    Raises
    ------
    HoleFillError
        When two input points coincide (Triangle would crash), or Triangle fails or changes
        the boundary (self-intersecting polygon).
    """
    Q = np.asarray(Q, np.float64)
    k = len(Q)
    pts = Q if extra_points is None or len(extra_points) == 0 else np.concatenate([Q, extra_points])
    segments = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    opts = "pQ"
    if not steiner_on_boundary:
        opts += "Y"
    if min_angle is not None:
        opts += f"q{float(min_angle):.6f}"
    if max_area is not None:
        # Triangle reads the switch's digits and '.' only: an exponent ("1e-06") would be cut
        # to its mantissa, so the bound is written positionally.
        opts += "a" + np.format_float_positional(float(max_area), trim="-")
    if _has_repeated_rows(pts):
        # Triangle crashes (segmentation fault) on repeated input points.
        raise HoleFillError("constrained triangulation: the polygon has two vertices at the same position "
                            "(an unwelded border vertex? try meshing_remove_duplicate_vertices)")
    try:
        out = triangle.triangulate({"vertices": pts, "segments": segments}, opts)
    except Exception as exc:  # Triangle reports problems as generic errors
        raise HoleFillError(f"constrained triangulation failed: {exc}") from exc
    P = out.get("vertices")
    T = out.get("triangles")
    if P is None or T is None or len(T) == 0:
        raise HoleFillError("constrained triangulation produced no triangles")
    if len(P) < len(pts) or not np.array_equal(P[:len(pts)], pts):
        raise HoleFillError("constrained triangulation changed the boundary (polygon not simple?)")
    T = np.asarray(T, np.int64)
    # 'p' without 'c' already drops the outside; Triangle emits counter-clockwise faces.
    A = P[T]
    signed = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    ccw_polygon = polygon_signed_area(Q) > 0
    flip = (signed > 0) != ccw_polygon
    T[flip] = T[flip][:, [0, 2, 1]]
    if max_area is None and min_angle is None and len(P) != len(pts):
        raise HoleFillError("polygon is not simple: the triangulation had to add crossing points")
    if not steiner_on_boundary:
        E = np.concatenate([T[:, [0, 1]], T[:, [1, 2]], T[:, [2, 0]]])
        have = set((np.minimum(E[:, 0], E[:, 1]) * len(P) + np.maximum(E[:, 0], E[:, 1])).tolist())
        need = np.minimum(segments[:, 0], segments[:, 1]) * len(P) + np.maximum(segments[:, 0], segments[:, 1])
        if not all(key in have for key in need.tolist()):
            raise HoleFillError("constrained triangulation lost a polygon edge (polygon not simple?)")
    return np.asarray(P, np.float64), T


def _has_repeated_rows(points):
    """Whether two rows of ``points`` (n, 2) are equal, as ``len(np.unique(points, axis=0)) < n`` tells
    (coordinates compared as numbers: 0.0 equals -0.0, NaN equals nothing), without its structured sort."""
    order = np.lexsort((points[:, 1], points[:, 0]))
    ordered = points[order]
    return bool((ordered[1:] == ordered[:-1]).all(axis=1).any())

