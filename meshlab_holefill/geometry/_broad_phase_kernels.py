"""Compiled broad phase of the triangle-triangle queries (numba): the face pairs worth the narrow test.

`intersections.intersecting_pairs` used to find its candidate pairs by a cKDTree search on the
face centroids, after numpy expressions over the (n, 3, 3) array of the faces' corners for their
boxes, centroids and radii; with the narrow test (:mod:`._narrow_phase_kernels`) they took most
of the crossing checks' time. :func:`box_pairs` replaces the cKDTree search by a uniform grid of
the face boxes and keeps the same pairs: boxes overlap (query boxes grown by tol) *and*
centroids lie within the radius-bin bound the tree search used (squared distance summed as
cKDTree sums it, against the squared bound). The per-face boxes, centroids and radii
(:func:`face_bounds`), the common box the default tolerance is taken from (:func:`common_box`)
and the ratios the radius bins are read from (:func:`radius_ratios`) do numpy's operations in
numpy's order (see :mod:`._vector_kernels`), so the tolerance, the bins and the bounds are the
same bits and so are the pairs. :func:`weld_labels` gives the vertex labels by which the narrow
phase tells shared vertices. tests/geometry/test_tri_kernels.py checks the candidate pairs
against the numpy code kept as the reference in tests/intersections_numpy.py.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._vector_kernels import face_corner, norm3, npmax, npmin, sub3

__all__ = ["face_bounds", "common_box", "weld_labels", "radius_ratios", "boxes_meeting", "candidate_pairs", "box_pairs",
           "RADIUS_BINS"]

RADIUS_BINS = 16  # candidate_pairs: faces binned by radius in factors of 4 below the largest


@njit(cache=True)
def face_bounds(V, F, faces):
    """Per face of `faces`: box corners lo, hi (n, 3), centroid c (n, 3) and bounding-sphere radius
    r (n,) about c, read from V and F directly.

    The values of T.min(1), T.max(1), T.mean(1) and np.linalg.norm(T - c[:, None], axis=2).max(1)
    for T = V[F[faces]], bit for bit (the mean adds the corners left to right, then divides by 3),
    without the (n, 3, 3) array and the numpy temporaries, which cost more than the grid search
    on the few-thousand-face sets of the crossing checks.
    """
    n = faces.shape[0]
    lo, hi, c = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    r = np.empty(n)
    for p in range(n):
        f = faces[p]
        A, B, C = face_corner(V, F, f, 0), face_corner(V, F, f, 1), face_corner(V, F, f, 2)
        for k in range(3):
            lo[p, k] = npmin(npmin(A[k], B[k]), C[k])
            hi[p, k] = npmax(npmax(A[k], B[k]), C[k])
            c[p, k] = ((A[k] + B[k]) + C[k]) / 3.0
        m = (c[p, 0], c[p, 1], c[p, 2])
        r[p] = npmax(npmax(norm3(sub3(A, m)), norm3(sub3(B, m))), norm3(sub3(C, m)))
    return lo, hi, c, r


@njit(cache=True)
def common_box(lo_q, hi_q, lo_a, hi_a):
    """Corners lo, hi (3,) of the box of all boxes [lo_q, hi_q] and [lo_a, hi_a], and the largest
    coordinate magnitude far among them (meaningless when a corner is NaN, whose box has no extent).

    The values of np.minimum(lo_q.min(0), lo_a.min(0)) and np.maximum(hi_q.max(0), hi_a.max(0))
    (NaN propagating; a zero may differ in sign only), without numpy's strided reductions, which
    cost more than the rest of the default tolerance on a ring of a few thousand faces.
    """
    lo, hi = np.empty(3), np.empty(3)
    far = 0.0
    for k in range(3):
        lo[k], hi[k] = lo_q[0, k], hi_q[0, k]
        for i in range(1, lo_q.shape[0]):
            lo[k] = npmin(lo[k], lo_q[i, k])
            hi[k] = npmax(hi[k], hi_q[i, k])
        for j in range(lo_a.shape[0]):
            lo[k] = npmin(lo[k], lo_a[j, k])
            hi[k] = npmax(hi[k], hi_a[j, k])
        far = max(far, abs(lo[k]), abs(hi[k]))
    return lo, hi, far


@njit(cache=True)
def weld_labels(V, F, faces):
    """Per vertex of V, a label that two vertices of `faces` share iff their coordinates are equal, (n,) int64.

    Equality is ``==`` per coordinate (so -0.0 welds to 0.0 and a NaN coordinate welds to
    nothing); a vertex's label is the smallest vertex index with its coordinates, and vertices
    outside `faces` get 0. An open-addressing table of coordinate hashes instead of a
    lexicographic sort of the rows: only the equality of labels matters to the narrow phase.
    """
    n = V.shape[0]
    label = np.zeros(n, np.int64)
    used = np.zeros(n, np.bool_)
    count = 0
    for p in range(faces.shape[0]):
        for k in range(3):
            v = F[faces[p], k]
            if not used[v]:
                used[v] = True
                count += 1
    size = 16
    while size < 2 * count:
        size *= 2
    table = np.full(size, -1, np.int64)
    for v in range(n):
        if not used[v]:
            continue
        # + 0.0 turns -0.0 into 0.0, so that equal coordinates hash alike
        slot = hash((V[v, 0] + 0.0, V[v, 1] + 0.0, V[v, 2] + 0.0)) & (size - 1)
        while True:
            w = table[slot]
            if w < 0:
                table[slot] = v
                label[v] = v
                break
            if V[w, 0] == V[v, 0] and V[w, 1] == V[v, 1] and V[w, 2] == V[v, 2]:
                label[v] = w
                break
            slot = (slot + 1) & (size - 1)
    return label


@njit(cache=True)
def radius_ratios(rq, ra):
    """Each radius of rq then ra over the largest, (nq + na,): the argument of the radius bins' logarithm.

    np.maximum(np.concatenate([rq, ra]), 1e-300) / max(rq.max(), ra.max(), tiny), bit for bit
    where no radius is NaN; a NaN radius makes every ratio NaN (the bins refuse them either way).
    """
    top = np.finfo(np.float64).tiny
    for x in rq:
        top = npmax(x, top)
    for x in ra:
        top = npmax(x, top)
    out = np.empty(rq.shape[0] + ra.shape[0])
    for p in range(rq.shape[0]):
        out[p] = npmax(rq[p], 1e-300) / top
    for p in range(ra.shape[0]):
        out[rq.shape[0] + p] = npmax(ra[p], 1e-300) / top
    return out


@njit(cache=True)
def _grow(buf, n):
    out = np.empty(2 * buf.shape[0] + 16, np.int64)
    for k in range(n):  # a loop: slice assignment costs seconds of compile time
        out[k] = buf[k]
    return out


@njit(cache=True)
def _cell(x, origin, cell, dim):
    c = int(math.floor((x - origin) / cell))
    return min(max(c, 0), dim - 1)


@njit(cache=True)
def box_pairs(lo_q, hi_q, lo_a, hi_a, cq, ca, bin_q, bin_a, ub2, origin, cell, dims, gq, ga, in_q, in_a):
    """Local index pairs (iq, ja): boxes [lo_q, hi_q] and [lo_a, hi_a] overlap on every axis
    and the squared centroid distance is <= ub2[bin_q[iq], bin_a[ja]].

    Pairs the narrow phase drops anyway are left out: with global face indices gi = gq[iq],
    gj = ga[ja], a face with itself and, when both faces are in both sets (in_q, in_a by global
    index), the mirrored pair gi > gj (for a patch against itself, half of all pairs).

    A uniform grid (cells of size `cell` from `origin`, dims (3,) cells per axis): the `against`
    boxes are listed in every cell they touch, and each query box tests the boxes listed in the
    cells it touches, each once. Two boxes that overlap share a point, hence a cell (the cell
    index is monotonic in the coordinate, and clamping to the grid keeps it so). Pairs come in
    no particular order.
    """
    nq, na = lo_q.shape[0], lo_a.shape[0]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    start = np.zeros(d0 * d1 * d2 + 1, np.int64)
    rng = np.empty((na, 6), np.int64)
    for j in range(na):
        for k in range(3):
            rng[j, k] = _cell(lo_a[j, k], origin[k], cell, dims[k])
            rng[j, 3 + k] = _cell(hi_a[j, k], origin[k], cell, dims[k])
        for x in range(rng[j, 0], rng[j, 3] + 1):
            for y in range(rng[j, 1], rng[j, 4] + 1):
                for z in range(rng[j, 2], rng[j, 5] + 1):
                    start[(x * d1 + y) * d2 + z + 1] += 1
    for c in range(d0 * d1 * d2):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    items = np.empty(start[-1], np.int64)
    for j in range(na):
        for x in range(rng[j, 0], rng[j, 3] + 1):
            for y in range(rng[j, 1], rng[j, 4] + 1):
                for z in range(rng[j, 2], rng[j, 5] + 1):
                    c = (x * d1 + y) * d2 + z
                    items[fill[c]] = j
                    fill[c] += 1
    seen = np.full(na, -1, np.int64)  # last query face that tested each against face
    out_i = np.empty(max(16, 8 * (nq + na)), np.int64)
    out_j = np.empty(out_i.shape[0], np.int64)
    n = 0
    for i in range(nq):
        x0, x1 = _cell(lo_q[i, 0], origin[0], cell, d0), _cell(hi_q[i, 0], origin[0], cell, d0)
        y0, y1 = _cell(lo_q[i, 1], origin[1], cell, d1), _cell(hi_q[i, 1], origin[1], cell, d1)
        z0, z1 = _cell(lo_q[i, 2], origin[2], cell, d2), _cell(hi_q[i, 2], origin[2], cell, d2)
        for x in range(x0, x1 + 1):
            for y in range(y0, y1 + 1):
                for z in range(z0, z1 + 1):
                    c = (x * d1 + y) * d2 + z
                    for r in range(start[c], start[c + 1]):
                        j = items[r]
                        if seen[j] == i:
                            continue
                        seen[j] = i
                        gi, gj = gq[i], ga[j]
                        if gi == gj or (gi > gj and in_q[gj] and in_a[gi]):
                            continue
                        if _pair_ok(i, j, lo_q, hi_q, lo_a, hi_a, cq, ca, bin_q, bin_a, ub2):
                            if n == out_i.shape[0]:
                                out_i, out_j = _grow(out_i, n), _grow(out_j, n)
                            out_i[n], out_j[n] = i, j
                            n += 1
    return out_i[:n].copy(), out_j[:n].copy()


@njit(cache=True)
def boxes_meeting(lo_q, hi_q, lo_a, hi_a, tol):
    """Positions of the boxes [lo_a, hi_a] that meet the box of all [lo_q, hi_q] grown by tol, (k,) int64.

    The union box of the query boxes is their row-wise min and max (NaN propagating, as
    ``lo_q.min(0)`` does), so a NaN coordinate leaves no box meeting it.
    """
    lo, hi = np.empty(3), np.empty(3)
    for k in range(3):
        lo[k], hi[k] = lo_q[0, k], hi_q[0, k]
        for i in range(1, lo_q.shape[0]):
            lo[k] = npmin(lo[k], lo_q[i, k])
            hi[k] = npmax(hi[k], hi_q[i, k])
        lo[k] -= tol
        hi[k] += tol
    keep = np.empty(lo_a.shape[0], np.int64)
    n = 0
    for j in range(lo_a.shape[0]):
        if (hi_a[j, 0] >= lo[0] and hi_a[j, 1] >= lo[1] and hi_a[j, 2] >= lo[2]
                and lo_a[j, 0] <= hi[0] and lo_a[j, 1] <= hi[1] and lo_a[j, 2] <= hi[2]):
            keep[n] = j
            n += 1
    return keep[:n]


@njit(cache=True)
def candidate_pairs(bounds_q, bounds_a, logs, log4, tol, q, a, n_faces):
    """Global face pairs (i, j) worth the narrow test, and the two sets' marks in_q, in_a (n_faces,) bool.

    ``bounds_q``, ``bounds_a`` are :func:`face_bounds` of the face sets q and a; ``logs`` (nq + na,)
    the logarithms of their :func:`radius_ratios` (NaN for a radius that is not a number), and
    ``log4`` that of 4: a face's radius bin is -clip(floor(log / log4), 1 - RADIUS_BINS, 0), 0 for
    the largest radii to ``RADIUS_BINS - 1``. Each pair of bins bounds the centroid distance by its
    largest radii plus tol, and :func:`box_pairs` keeps the pairs within it whose boxes (query
    boxes grown by tol) overlap, on a grid of cells about the size of a typical face box,
    doubled while there are more than 32 cells per face (the cell size changes the time only; a patch
    is a surface, so most cells stay empty: a cap of 8 per face doubled the cells of the largest
    benchmark patch to twice a typical face box, and its search took 3.7 ms instead of 2.9 ms).
    """
    lo_q, hi_q, cq, rq = bounds_q
    lo_a, hi_a, ca, ra = bounds_a
    nq, na = q.shape[0], a.shape[0]
    in_q, in_a = np.zeros(n_faces, np.bool_), np.zeros(n_faces, np.bool_)
    in_q[q] = True
    in_a[a] = True
    bin_q, bin_a = np.empty(nq, np.int64), np.empty(na, np.int64)
    top_q, top_a = np.full(RADIUS_BINS, -np.inf), np.full(RADIUS_BINS, -np.inf)
    for p in range(nq + na):
        if logs[p] != logs[p]:
            raise ValueError("face radii are not numbers (infinite coordinates)")
        b = int(-min(max(np.floor(logs[p] / log4), 1.0 - RADIUS_BINS), 0.0))
        if p < nq:
            bin_q[p] = b
            top_q[b] = max(top_q[b], rq[p])
        else:
            bin_a[p - nq] = b
            top_a[b] = max(top_a[b], ra[p - nq])
    ub2 = np.empty((RADIUS_BINS, RADIUS_BINS))
    for s in range(RADIUS_BINS):
        for t in range(RADIUS_BINS):
            ub = top_q[s] + top_a[t] + tol
            ub2[s, t] = ub * ub
    origin, span = np.empty(3), np.empty(3)
    for k in range(3):
        origin[k] = lo_a[:, k].min()
        span[k] = hi_a[:, k].max() - origin[k]
    extent = np.empty(na)
    for j in range(na):
        extent[j] = max(hi_a[j, 0] - lo_a[j, 0], hi_a[j, 1] - lo_a[j, 1], hi_a[j, 2] - lo_a[j, 2])
    cell = max(np.median(extent), span.max() / 4096, np.finfo(np.float64).tiny)
    while np.prod(np.floor(span / cell) + 1) > 32 * na + 64:
        cell *= 2
    dims = (np.floor(span / cell) + 1).astype(np.int64)
    iq, ja = box_pairs(lo_q - tol, hi_q + tol, lo_a, hi_a, cq, ca, bin_q, bin_a, ub2, origin, cell, dims, q, a,
                       in_q, in_a)
    return q[iq], a[ja], in_q, in_a


@njit(cache=True)
def _pair_ok(i, j, lo_q, hi_q, lo_a, hi_a, cq, ca, bin_q, bin_a, ub2):
    for k in range(3):
        if not (lo_q[i, k] <= hi_a[j, k] and lo_a[j, k] <= hi_q[i, k]):
            return False
    s = 0.0  # cKDTree's squared Euclidean distance: 0.0, then += d * d per coordinate
    for k in range(3):
        d = cq[i, k] - ca[j, k]
        s += d * d
    return s <= ub2[bin_q[i], bin_a[j]]
