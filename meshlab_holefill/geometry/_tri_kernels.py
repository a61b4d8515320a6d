"""Compiled kernels of the triangle-triangle queries (numba): the broad phase and the narrow phase.

`intersections.intersecting_pairs` used to test candidate pairs with numpy expressions over
(k, 3, 3) arrays, a hundred temporaries per call, after a cKDTree search for the candidates;
together they took most of the crossing checks' time. Here each pair is tested by scalar code
that does, element by element, the same IEEE operations in the same order as that numpy code
(no fastmath, no contraction to FMA; row norms add the squares left to right as numpy's
add.reduce does, row dots in numpy's einsum order, see `_dot`), so every predicate, tolerance and
boolean answer is the same bit for bit. tests/geometry/test_tri_kernels.py checks the whole query,
the candidate pairs and the pair verdicts against that numpy code, kept as the reference in
tests/intersections_numpy.py. The one transcendental step, the arctan2 of a shared-edge fold,
stays in numpy (its SIMD arctan2 may differ from libm's in the last bits): `narrow_codes`
returns its two arguments.

`box_pairs` replaces the cKDTree search by a uniform grid of the face boxes and keeps the same
pairs: boxes overlap (query boxes grown by tol) *and* centroids lie within the radius-bin bound
the tree search used (squared distance summed as cKDTree sums it, against the squared bound).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["face_bounds", "common_box", "weld_labels", "radius_ratios", "boxes_meeting", "candidate_pairs", "box_pairs", "narrow_codes", "NO", "HIT", "FOLD",
           "RADIUS_BINS"]

NO, HIT, FOLD = 0, 1, 2  # narrow_codes: no contact, contact, shared edge whose fold angle decides
RADIUS_BINS = 16  # candidate_pairs: faces binned by radius in factors of 4 below the largest


# ---------------------------------------------------------------- broad phase

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
        A, B, C = _row(V, F, f, 0), _row(V, F, f, 1), _row(V, F, f, 2)
        for k in range(3):
            lo[p, k] = _npmin(_npmin(A[k], B[k]), C[k])
            hi[p, k] = _npmax(_npmax(A[k], B[k]), C[k])
            c[p, k] = ((A[k] + B[k]) + C[k]) / 3.0
        m = (c[p, 0], c[p, 1], c[p, 2])
        r[p] = _npmax(_npmax(_norm(_sub(A, m)), _norm(_sub(B, m))), _norm(_sub(C, m)))
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
            lo[k] = _npmin(lo[k], lo_q[i, k])
            hi[k] = _npmax(hi[k], hi_q[i, k])
        for j in range(lo_a.shape[0]):
            lo[k] = _npmin(lo[k], lo_a[j, k])
            hi[k] = _npmax(hi[k], hi_a[j, k])
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
        top = _npmax(x, top)
    for x in ra:
        top = _npmax(x, top)
    out = np.empty(rq.shape[0] + ra.shape[0])
    for p in range(rq.shape[0]):
        out[p] = _npmax(rq[p], 1e-300) / top
    for p in range(ra.shape[0]):
        out[rq.shape[0] + p] = _npmax(ra[p], 1e-300) / top
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
            lo[k] = _npmin(lo[k], lo_q[i, k])
            hi[k] = _npmax(hi[k], hi_q[i, k])
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


# ---------------------------------------------------------------- vector helpers (3-tuples)

@njit(cache=True)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def _scale(a, t):
    return (a[0] * t, a[1] * t, a[2] * t)


@njit(cache=True)
def _div(a, t):
    return (a[0] / t, a[1] / t, a[2] / t)


@njit(cache=True)
def _dot(a, b):
    """np.einsum("ij,ij->i") (and "kij,kj->ki") on rows of three, bit for bit.

    numpy's einsum sums two lanes at a time (SIMD, from a zero accumulator): lane 0 gets products
    0 and 2, lane 1 product 1, and the lanes are added last. tests/geometry/test_tri_kernels.py
    checks this against np.einsum.
    """
    return ((a[0] * b[0] + 0.0) + a[2] * b[2]) + (a[1] * b[1] + 0.0)


@njit(cache=True)
def _norm(a):
    s = 0.0  # np.linalg.norm(axis=1): sqrt of add.reduce of the squares
    s += a[0] * a[0]
    s += a[1] * a[1]
    s += a[2] * a[2]
    return math.sqrt(s)


@njit(cache=True)
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _unit(a):
    ln = _norm(a)
    return _div(a, ln if ln > 0 else 1.0)


@njit(cache=True)
def _npmax(a, b):
    """np.maximum: NaN if either is NaN (ties of +-0 may differ in sign only, which no caller sees)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


@njit(cache=True)
def _npmin(a, b):
    """np.minimum: NaN if either is NaN (ties of +-0 may differ in sign only, which no caller sees)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a <= b else b


@njit(cache=True)
def _row(V, F, f, k):
    v = F[f, k]
    return (V[v, 0], V[v, 1], V[v, 2])


# ---------------------------------------------------------------- narrow phase

@njit(cache=True)
def _unit_normal(t0, t1, t2, tol):
    """intersections._unit_normal for one triangle: (normal, degenerate)."""
    n = _cross(_sub(t1, t0), _sub(t2, t0))
    ln = _norm(n)
    longest = _npmax(_npmax(_norm(_sub(t0, t1)), _norm(_sub(t1, t2))), _norm(_sub(t2, t0)))
    deg = ln <= tol * longest
    return _div(n, 1.0 if deg else ln), deg


@njit(cache=True)
def _heights(t0, n, s0, s1, s2):
    """Signed heights of triangle s's corners above the plane of t (corner t0, normal n): the dots both
    intersections._beyond_plane and the slab of intersections._clip take."""
    return _dot(_sub(s0, t0), n), _dot(_sub(s1, t0), n), _dot(_sub(s2, t0), n)


@njit(cache=True)
def _beyond(d, deg, tol):
    """intersections._beyond_plane: triangle s lies wholly more than tol to one side of t's plane,
    from s's :func:`_heights` ``d`` above it."""
    if deg:
        return False
    d0, d1, d2 = d
    return (d0 > tol and d1 > tol and d2 > tol) or (d0 < -tol and d1 < -tol and d2 < -tol)


@njit(cache=True)
def _step(c0, c1, ok, t0, t1):
    """One Liang-Barsky constraint of intersections._clip (inside where c0 + t (c1 - c0) >= 0)."""
    ok = ok and (c0 >= 0 or c1 >= 0)
    # the division only where a bound moves: most constraints hold at both ends
    if c0 < 0 and c1 >= 0:
        den = c0 - c1
        t0 = _npmax(t0, c0 / (1.0 if den == 0 else den))
    elif c0 >= 0 and c1 < 0:
        den = c0 - c1
        t1 = _npmin(t1, c0 / (1.0 if den == 0 else den))
    return ok, t0, t1


@njit(cache=True)
def _clip_frame(T0, T1, T2, nt):
    """The target's clipping directions, as intersections._clip computes them for every edge:
    edge normals in the plane ms and corner bisectors us, 18 numbers as a flat tuple."""
    m0, m1, m2 = (_unit(_cross(nt, _sub(T1, T0))), _unit(_cross(nt, _sub(T2, T1))),
                  _unit(_cross(nt, _sub(T0, T2))))
    u0 = _unit(_add(_unit(_sub(T1, T0)), _unit(_sub(T2, T0))))
    u1 = _unit(_add(_unit(_sub(T2, T1)), _unit(_sub(T0, T1))))
    u2 = _unit(_add(_unit(_sub(T0, T2)), _unit(_sub(T1, T2))))
    return m0 + m1 + m2 + u0 + u1 + u2


@njit(cache=True)
def _face_normals(V, F, I, J, tol):
    """Per face met in the pairs (I, J): unit normal and degeneracy, computed once per face
    instead of once per pair (a face of a patch tested against itself is in ~20 pairs).

    Returns slot (len(F),) int64 (-1 for faces in no pair), N (s, 3), deg (s,) bool.
    """
    slot = np.full(F.shape[0], -1, np.int64)
    s = 0
    for p in range(I.shape[0]):
        for f in (I[p], J[p]):
            if slot[f] < 0:
                slot[f] = s
                s += 1
    N, deg = np.empty((s, 3)), np.empty(s, np.bool_)
    for f in range(F.shape[0]):
        t = slot[f]
        if t >= 0:
            n, deg[t] = _unit_normal(_row(V, F, f, 0), _row(V, F, f, 1), _row(V, F, f, 2), tol)
            N[t, 0], N[t, 1], N[t, 2] = n
    return slot, N, deg


@njit(cache=True, inline='always')
def _ensure_frame(frame, done, t, T0, T1, T2, nt):
    """Fill row t of `frame` with the clipping frame of T0T1T2 on its first use."""
    if not done[t]:
        fr = _clip_frame(T0, T1, T2, nt)
        for k in range(18):
            frame[t, k] = fr[k]
        done[t] = True


@njit(cache=True)
def _frame_row(frame, t, k):
    return (frame[t, 3 * k], frame[t, 3 * k + 1], frame[t, 3 * k + 2])


@njit(cache=True, inline='always')
def _slab(h0, h1, tol):
    """The slab's two constraints of intersections._clip for a segment with heights h0, h1: (ok, t0, t1).

    ``ok`` is False when both ends lie more than tol to one side, the usual verdict for two
    faces of a patch that share a vertex; the target's edge constraints are then not needed.
    """
    ok, t0, t1 = True, 0.0, 1.0
    if not (tol - h0 >= 0 or tol - h1 >= 0) or not (tol + h0 >= 0 or tol + h1 >= 0):
        return False, t0, t1
    ok, t0, t1 = _step(tol - h0, tol - h1, ok, t0, t1)
    ok, t0, t1 = _step(tol + h0, tol + h1, ok, t0, t1)
    return ok, t0, t1


@njit(cache=True, inline='always')
def _clip_edges(P0, P1, Tt, frame, ft, grow, ok, t0, t1):
    """The rest of intersections._clip after :func:`_slab`: per target edge its edge normal's and
    its bisector's constraint (frame row ft), in its order, stopping at the first one negative
    (or NaN) at both ends, which leaves ``ok`` False whatever the others give."""
    for e in range(3):
        a = Tt[e]
        for direction in (_frame_row(frame, ft, e), _frame_row(frame, ft, 3 + e)):
            c0, c1 = _dot(_sub(P0, a), direction) + grow, _dot(_sub(P1, a), direction) + grow
            if not (c0 >= 0 or c1 >= 0):
                return False, t0, t1
            ok, t0, t1 = _step(c0, c1, ok, t0, t1)
    return ok, t0, t1


@njit(cache=True, inline='always')
def _inside_corner(P0, P1, Tt, frame, ft, grow, c):
    """False when segment P0P1 lies wholly behind the bisector constraint of target corner c, one of
    the constraints :func:`_clip_edges` tests (same operands, same operations): it then rejects the
    segment too, whatever the order. Faces sharing only the vertex at corner c lie around it, so
    the edge opposite it nearly always fails this one first (narrow phase of the largest
    benchmark patch: 4.3 -> 4.1 ms)."""
    d = _frame_row(frame, ft, 3 + c)
    a = Tt[c]
    c0, c1 = _dot(_sub(P0, a), d) + grow, _dot(_sub(P1, a), d) + grow
    return c0 >= 0 or c1 >= 0


@njit(cache=True, inline='always')
def _edges_meet(S0, S1, S2, T0, T1, T2, d, frame, done, ft, nt, shs, degs, degt, one, S, ct, tol):
    """intersections._edges_meet for one pair: some edge of triangle S0S1S2 meets T0T1T2
    (unit normal nt; its clipping frame is row ft of `frame`, filled on first use, see
    :func:`_ensure_frame`; d: S's :func:`_heights` above T; ct: T's corner at the shared vertex
    when ``one``, whose bisector is tried first, see :func:`_inside_corner`).

    Inlined with the helpers it calls into :func:`narrow_codes` (numba's inliner: the same
    operations, without the calls and their tuple arguments: 4.1 -> 3.0 ms on that patch)."""
    if degt:
        return False
    Ts = (S0, S1, S2)
    Tt = (T0, T1, T2)
    for k in range(3):
        incident = shs[k] or shs[(k + 1) % 3]
        if one and incident and not degs:
            continue
        P0, P1 = Ts[k], Ts[(k + 1) % 3]
        ok, t0, t1 = _slab(d[k], d[(k + 1) % 3], tol)
        # the edge constraints only narrow [t0, t1] (or give up): an empty one stays empty
        if not (ok and t0 <= t1):
            continue
        _ensure_frame(frame, done, ft, T0, T1, T2, nt)
        grow = 0.0 if (one and degs) else tol
        if one and not _inside_corner(P0, P1, Tt, frame, ft, grow, ct):
            continue
        ok, t0, t1 = _clip_edges(P0, P1, Tt, frame, ft, grow, ok, t0, t1)
        if not (ok and t0 <= t1):
            continue
        if not one:
            return True
        D = _sub(P1, P0)
        f0 = _norm(_sub(_add(P0, _scale(D, t0)), S))
        f1 = _norm(_sub(_add(P0, _scale(D, t1)), S))
        if _npmax(f0, f1) > tol:
            return True
    return False


@njit(cache=True)
def narrow_codes(V, F, canon, I, J, in_q, in_a, tol):
    """For global face pairs (I, J): NO, HIT or FOLD per pair, and the fold's arctan2 arguments.

    The pair filter, plane rejection and narrow test of intersections.intersecting_pairs (mirrored
    pairs, self-pairs and pairs one face's slab separates give NO). A FOLD pair (a shared edge
    between non-degenerate faces) intersects iff np.arctan2(fy, fx) < fold_angle.
    """
    k = I.shape[0]
    code = np.zeros(k, np.int8)
    fy = np.zeros(k)
    fx = np.zeros(k)
    slot, N, DEG = _face_normals(V, F, I, J, tol)
    frame = np.empty((N.shape[0], 18))  # clipping frames, computed when a pair first needs one
    done = np.zeros(N.shape[0], np.bool_)
    for p in range(k):
        i, j = I[p], J[p]
        # (i, j) and (j, i) are both generated when both faces are in both sets
        if i == j or (i > j and in_q[j] and in_a[i]):
            continue
        A0, A1, A2 = _row(V, F, i, 0), _row(V, F, i, 1), _row(V, F, i, 2)
        B0, B1, B2 = _row(V, F, j, 0), _row(V, F, j, 1), _row(V, F, j, 2)
        si, sj = slot[i], slot[j]
        n1, deg1 = (N[si, 0], N[si, 1], N[si, 2]), DEG[si]
        n2, deg2 = (N[sj, 0], N[sj, 1], N[sj, 2]), DEG[sj]
        dB = _heights(A0, n1, B0, B1, B2)
        if _beyond(dB, deg1, tol):
            continue
        dA = _heights(B0, n2, A0, A1, A2)
        if _beyond(dA, deg2, tol):
            continue
        C1 = (canon[F[i, 0]], canon[F[i, 1]], canon[F[i, 2]])
        C2 = (canon[F[j, 0]], canon[F[j, 1]], canon[F[j, 2]])
        sh1 = (C1[0] == C2[0] or C1[0] == C2[1] or C1[0] == C2[2],
               C1[1] == C2[0] or C1[1] == C2[1] or C1[1] == C2[2],
               C1[2] == C2[0] or C1[2] == C2[1] or C1[2] == C2[2])
        sh2 = (C2[0] == C1[0] or C2[0] == C1[1] or C2[0] == C1[2],
               C2[1] == C1[0] or C2[1] == C1[1] or C2[1] == C1[2],
               C2[2] == C1[0] or C2[2] == C1[1] or C2[2] == C1[2])
        nsh = min(int(sh1[0]) + int(sh1[1]) + int(sh1[2]), int(sh2[0]) + int(sh2[1]) + int(sh2[2]))
        good = not deg1 and not deg2
        if nsh >= 3:
            if good:
                code[p] = HIT
        elif nsh == 2:
            if good:
                # intersections._folded: opening angle around the shared edge
                A, B = (A0, A1, A2), (B0, B1, B2)
                o1 = 0 if not sh1[0] else (1 if not sh1[1] else (2 if not sh1[2] else 0))
                o2 = 0 if not sh2[0] else (1 if not sh2[1] else (2 if not sh2[2] else 0))
                P, Q = A[(o1 + 1) % 3], A[(o1 + 2) % 3]
                e = _unit(_sub(Q, P))
                ua, ub = _sub(A[o1], P), _sub(B[o2], P)
                ua = _sub(ua, _scale(e, _dot(ua, e)))
                ub = _sub(ub, _scale(e, _dot(ub, e)))
                code[p] = FOLD
                fy[p] = _norm(_cross(ua, ub))
                fx[p] = _dot(ua, ub)
        else:
            one = nsh == 1
            s = 0 if sh1[0] else (1 if sh1[1] else (2 if sh1[2] else 0))  # argmax of sh1
            s2 = 0 if sh2[0] else (1 if sh2[1] else (2 if sh2[2] else 0))
            S = A0 if s == 0 else (A1 if s == 1 else A2)
            if (_edges_meet(A0, A1, A2, B0, B1, B2, dA, frame, done, sj, n2, sh1, deg1, deg2, one, S, s2, tol)
                    or _edges_meet(B0, B1, B2, A0, A1, A2, dB, frame, done, si, n1, sh2, deg2, deg1, one, S, s, tol)):
                code[p] = HIT
    return code, fy, fx
