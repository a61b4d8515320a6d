"""Exact distances between line segments, and between the segments of a closed polygon.

Used by the curve-unfolding filter for its clearance d_MD (Brunton et al. 2009, Sec. 3.1) and
for testing planar polygons for simplicity; works in 2D and 3D.

The pairwise distances of a loop and of its moved segments (:func:`segment_distance_matrix`,
:func:`segment_distance_rows`, called thousands of times by the annealing) are numba kernels
that make the operations of the numpy formulas (:func:`segment_distances`, the bounding-sphere
bound) in the same order, sums of squares added left to right as numpy's row sums add them,
without FMA contraction: the same bits, without the (a, b, d) temporaries. The bounds go a row
of pairs at a time, in loops that compile to vector instructions; the exact distances pair by pair.
tests/geometry/test_segments.py checks them against the numpy formulas.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["segment_distances", "nonadjacent_mask", "segment_distance_rows", "segment_distance_matrix",
           "min_segment_distance", "is_simple_polygon", "keeps_clearance", "polygon_edges_touch", "polygon_edges_touch_numpy"]


def segment_distances(A0, A1, B0, B1):
    """Exact distance between segments [A0, A1] and [B0, B1], elementwise with broadcasting.

    Closest points by the dot-product formulation (Ladd and Kavraki, cited in Sec. 3.1;
    Ericson, Real-Time Collision Detection 5.1.9): the unconstrained parameters of the
    closest points of the two carrier lines are clamped to the segments in the right order.
    Degenerate (point) segments are handled.

    Parameters
    ----------
    A0, A1, B0, B1 : (..., d) float64
        Segment end points, d = 2 or 3, broadcast against each other.

    Returns
    -------
    dist : (...) float64
    """
    d1 = A1 - A0
    d2 = B1 - B0
    r = A0 - B0
    a = (d1 * d1).sum(axis=-1)
    e = (d2 * d2).sum(axis=-1)
    b = (d1 * d2).sum(axis=-1)
    c = (d1 * r).sum(axis=-1)
    f = (d2 * r).sum(axis=-1)
    denom = a * e - b * b
    # (Nearly) parallel or point segments: any s works, take 0. Safe divisors avoid warnings.
    general = denom > 1e-14 * a * e
    s = np.where(general, (b * f - c * e) / np.where(general, denom, 1.0), 0.0)
    s = np.minimum(np.maximum(s, 0.0), 1.0)
    t = (b * s + f) / np.where(e > 0.0, e, 1.0)
    a_safe = np.where(a > 0.0, a, 1.0)
    s_at_b0 = np.minimum(np.maximum(-c / a_safe, 0.0), 1.0)  # closest to B0 (also when B is a point)
    s = np.where((t < 0.0) | (e <= 0.0), s_at_b0,
                 np.where(t > 1.0, np.minimum(np.maximum((b - c) / a_safe, 0.0), 1.0), s))
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    diff = r + d1 * s[..., None] - d2 * t[..., None]
    return np.sqrt((diff * diff).sum(axis=-1))


def nonadjacent_mask(m):
    """Pairs of loop segments that share no vertex.

    Segment i joins p_i and p_{(i+1) mod m}.

    Returns
    -------
    mask : (m, m) bool, symmetric, False on the diagonal and for consecutive segments.
    """
    i = np.arange(m)
    gap = np.abs(i[:, None] - i[None, :])
    return (gap > 1) & (gap < m - 1)


def segment_distance_rows(A0, A1, B0, B1, allowed, near):
    """Distances from segments [A0, A1] to segments [B0, B1], exact where it can matter.

    A pair whose bounding spheres are more than ``near`` apart gets the lower bound
    |c_a - c_b| - r_a - r_b (> near) instead of its exact distance; minima below ``near``,
    and hence every comparison with a smaller threshold, are exact. Cost: one vectorised
    bound for all pairs, exact distances (:func:`segment_distances`) for the near ones.

    Parameters
    ----------
    A0, A1 : (a, d) float64
    B0, B1 : (b, d) float64
    allowed : (a, b) bool  pairs to measure (others are +inf)
    near : float

    Returns
    -------
    rows : (a, b) float64
    """
    A0, A1, B0, B1 = (np.ascontiguousarray(X, np.float64) for X in (A0, A1, B0, B1))
    return _distance_rows(A0, A1, B0, B1, np.ascontiguousarray(allowed, np.bool_), float(near), False)


@njit(cache=True)
def _square_sum(X, i, Y, j):
    """|X[i] - Y[j]|^2, the squares added left to right as numpy's row sum adds them."""
    t = X[i, 0] - Y[j, 0]
    s = t * t
    for k in range(1, X.shape[1]):
        t = X[i, k] - Y[j, k]
        s += t * t
    return s


@njit(cache=True)
def _clamp01(x):
    return min(max(x, 0.0), 1.0)


@njit(cache=True)
def _segment_distance(A0, A1, B0, B1, i, j):
    """:func:`segment_distances` of segments A[i] and B[j], the same operations in the same order."""
    d = A0.shape[1]
    a = e = b = c = f = 0.0
    for k in range(d):
        d1, d2, r = A1[i, k] - A0[i, k], B1[j, k] - B0[j, k], A0[i, k] - B0[j, k]
        if k == 0:
            a, e, b, c, f = d1 * d1, d2 * d2, d1 * d2, d1 * r, d2 * r
        else:
            a += d1 * d1
            e += d2 * d2
            b += d1 * d2
            c += d1 * r
            f += d2 * r
    denom = a * e - b * b
    s = (b * f - c * e) / denom if denom > 1e-14 * a * e else 0.0
    s = _clamp01(s)
    t = (b * s + f) / (e if e > 0.0 else 1.0)
    a_safe = a if a > 0.0 else 1.0
    if t < 0.0 or e <= 0.0:
        s = _clamp01(-c / a_safe)
    elif t > 1.0:
        s = _clamp01((b - c) / a_safe)
    t = _clamp01(t)
    total = 0.0
    for k in range(d):
        diff = (A0[i, k] - B0[j, k]) + (A1[i, k] - A0[i, k]) * s - (B1[j, k] - B0[j, k]) * t
        total = diff * diff if k == 0 else total + diff * diff
    return math.sqrt(total)


@njit(cache=True)
def _distance_rows(A0, A1, B0, B1, allowed, near, exact):
    """Compiled :func:`segment_distance_rows`: the bound of every pair, the exact distance of near ones.

    With ``exact`` every allowed pair gets its exact distance and the others +inf (``near`` unused).
    """
    na, nb = A0.shape[0], B0.shape[0]
    ca, cb = 0.5 * (A0 + A1), 0.5 * (B0 + B1)
    ra = np.empty(na)
    rb = np.empty(nb)
    for i in range(na):
        ra[i] = 0.5 * math.sqrt(_square_sum(A1, i, A0, i))
    for j in range(nb):
        rb[j] = 0.5 * math.sqrt(_square_sum(B1, j, B0, j))
    rows = np.empty((na, nb))
    if exact:
        for i in range(na):
            for j in range(nb):
                rows[i, j] = _segment_distance(A0, A1, B0, B1, i, j) if allowed[i, j] else np.inf
        return rows
    cb_columns = np.ascontiguousarray(cb.T)
    for i in range(na):
        row = rows[i]
        _bound_row(ca, i, cb_columns, ra[i], rb, row)
        for j in range(nb):
            if not allowed[i, j]:
                row[j] = np.inf
            if row[j] <= near:  # a pair left out too where near is +inf, as the numpy formulas have it
                row[j] = _segment_distance(A0, A1, B0, B1, i, j)
    return rows


@njit(cache=True)
def _bound_row(ca, i, cb_columns, ra_i, rb, row):
    """``row[j]`` = |ca[i] - cb[j]| - ra_i - rb[j] for every j, the operations of :func:`_square_sum` in its order.

    Coordinate by coordinate over the whole row (``cb_columns`` is cb transposed, (d, nb)), so
    that the loops run over contiguous memory and compile to vector instructions, which round
    every operation as the scalar ones do: the same bits, several times faster than pair by pair.
    """
    nb = row.shape[0]
    x = ca[i, 0]
    for j in range(nb):
        t = x - cb_columns[0, j]
        row[j] = t * t
    for k in range(1, ca.shape[1]):
        x = ca[i, k]
        for j in range(nb):
            t = x - cb_columns[k, j]
            row[j] += t * t
    for j in range(nb):
        row[j] = math.sqrt(row[j]) - ra_i - rb[j]


def segment_distance_matrix(P, near=None):
    """Distances between all pairs of non-adjacent loop segments, in one compiled call.

    Parameters
    ----------
    P : (m, d) float64  loop vertices
    near : float, optional
        With a value, pairs farther apart than ``near`` only get a lower bound (> near), see
        :func:`segment_distance_rows`; by default every distance is exact.

    Returns
    -------
    D : (m, m) float64
        D[i, j] = distance between segments i and j; +inf for adjacent pairs and i == j.
    """
    P = np.asarray(P, np.float64)
    m = len(P)
    Q = np.roll(P, -1, axis=0)
    if near is not None:
        return segment_distance_rows(P, Q, P, Q, nonadjacent_mask(m), near)
    Q = np.ascontiguousarray(Q)
    return _distance_rows(P, Q, P, Q, nonadjacent_mask(m), np.inf, True)


def min_segment_distance(P, near=None):
    """d_MD of Sec. 3.1: the smallest distance between two non-adjacent loop segments.

    Parameters
    ----------
    P : (m, d) float64
    near : float, optional  see :func:`segment_distance_matrix` (exact whenever d_MD <= near)

    Returns
    -------
    float  (+inf for m <= 3, where every pair of segments is adjacent)
    """
    if len(P) <= 3:
        return math.inf
    return float(segment_distance_matrix(P, near).min())


def is_simple_polygon(Q, eps, near=None):
    """Whether a closed polygon keeps clearance d_MD > eps between non-adjacent edges (so is simple).

    Parameters
    ----------
    Q : (m, d) float64
        Polygon vertices in order.
    eps : float
        Absolute clearance.
    near : float, optional
        Distances beyond ``near`` (> eps) are only bounded from below (faster, same answer).

    Returns
    -------
    bool  (a triangle has no non-adjacent edges: it must merely not be degenerate)
    """
    Q = np.asarray(Q, np.float64)
    if len(Q) == 3:
        a, b, c = Q[:, :2]
        return abs(float((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))) > eps * eps
    if len(Q) < 3 or Q.ndim != 2 or not np.isfinite(eps):
        return min_segment_distance(Q, near) > eps
    P = np.ascontiguousarray(Q)
    R = np.ascontiguousarray(np.roll(P, -1, axis=0))
    if near is None:
        # Exact wherever it can matter: a pair whose bound exceeds twice eps (plus a margin for the
        # bound's rounding on touching segments) is farther apart than eps.
        near = 2.0 * eps + 1e-9 * float(np.abs(R - P).max())
    return bool(keeps_clearance(P, R, nonadjacent_mask(len(P)), float(near), float(eps)))


@njit(cache=True)
def keeps_clearance(Q, R, allowed, near, eps):
    """Whether every allowed pair of segments [Q_i, R_i], [Q_j, R_j] is more than ``eps`` apart.

    ``segment_distance_rows(Q, R, Q, R, allowed, near).min() > eps`` (``near`` > ``eps``): the
    clearance d_MD > epsilon of Sec. 3.1 on the projected loop, the annealing's stage test,
    stopping at the first pair within ``eps``. A pair whose bound exceeds ``near`` is farther than
    ``eps``; the others get the same exact distance as there (both orders of a pair, as the full
    matrix has them). A NaN distance fails, as the minimum's comparison does.
    """
    m = Q.shape[0]
    c = 0.5 * (Q + R)
    r = np.empty(m)
    for i in range(m):
        r[i] = 0.5 * math.sqrt(_square_sum(R, i, Q, i))
    c_columns = np.ascontiguousarray(c.T)
    bound = np.empty(m)
    for i in range(m):
        _bound_row(c, i, c_columns, r[i], r, bound)
        for j in range(m):
            if not allowed[i, j]:
                continue
            d = _segment_distance(Q, R, Q, R, i, j) if bound[j] <= near else bound[j]
            if not d > eps:
                return False
    return True


def polygon_edges_touch(P):
    """Do two non-adjacent edges of the closed 2D polygon P (k, 2) touch or cross?

    Exact orientation tests on all pairs of edges; touching, and overlap of collinear edges,
    count as crossing, collinear edges apart do not. ``not polygon_edges_touch(P)`` is the
    simplicity test without a clearance (:func:`is_simple_polygon` asks for one). Compiled
    (:func:`_edges_touch`, stopping at the first touching pair), with the operations of
    :func:`polygon_edges_touch_numpy`: the same answer.
    """
    P = np.ascontiguousarray(P, np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        return polygon_edges_touch_numpy(P)
    return bool(_edges_touch(P))


@njit(cache=True)
def _orient(P, p, q, r):
    return (P[q, 0] - P[p, 0]) * (P[r, 1] - P[p, 1]) - (P[q, 1] - P[p, 1]) * (P[r, 0] - P[p, 0])


@njit(cache=True)
def _within(P, p, q, r):
    """Point r within the box of segment p-q (np.minimum and np.maximum: a NaN end holds nothing)."""
    for c in range(2):
        a, b, x = P[p, c], P[q, c], P[r, c]
        if a != a or b != b or not (min(a, b) <= x <= max(a, b)):
            return False
    return True


@njit(cache=True)
def _edges_touch(P):
    k = P.shape[0]
    for i in range(k):
        a, b = i, (i + 1) % k
        for j in range(i + 2, k - 1 if i == 0 else k):  # edges 0 and k - 1 share vertex 0
            c, d = j, (j + 1) % k
            d1, d2, d3, d4 = _orient(P, a, b, c), _orient(P, a, b, d), _orient(P, c, d, a), _orient(P, c, d, b)
            if d1 * d2 < 0 and d3 * d4 < 0:
                return True
            if ((d1 == 0 and _within(P, a, b, c)) or (d2 == 0 and _within(P, a, b, d))
                    or (d3 == 0 and _within(P, c, d, a)) or (d4 == 0 and _within(P, c, d, b))):
                return True
    return False


def polygon_edges_touch_numpy(P, chunk=200_000):
    """:func:`polygon_edges_touch` in numpy, in chunks of ``chunk`` pairs of edges (the reference of the compiled test)."""
    P = np.asarray(P, np.float64)
    k = len(P)
    A, B = P, np.roll(P, -1, axis=0)
    i, j = np.triu_indices(k, 2)
    keep = (j - i) != k - 1  # edges 0 and k-1 share vertex 0
    i, j = i[keep], j[keep]

    def orient(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    def on_segment(p, q, r):
        # r, collinear with p-q, lies within the segment's box
        return np.all((np.minimum(p, q) <= r) & (r <= np.maximum(p, q)), axis=1)

    for lo in range(0, len(i), chunk):
        a, b, c, d = A[i[lo:lo + chunk]], B[i[lo:lo + chunk]], A[j[lo:lo + chunk]], B[j[lo:lo + chunk]]
        d1, d2, d3, d4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
        proper = (d1 * d2 < 0) & (d3 * d4 < 0)
        touch = (((d1 == 0) & on_segment(a, b, c)) | ((d2 == 0) & on_segment(a, b, d))
                 | ((d3 == 0) & on_segment(c, d, a)) | ((d4 == 0) & on_segment(c, d, b)))
        if np.any(proper | touch):
            return True
    return False
