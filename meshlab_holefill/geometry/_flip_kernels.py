"""Compiled rounds of :func:`.flips.relax_edges` (numba) for the circumsphere and unfolded-angle tests.

One round of the numpy code (interior edges, the swap test, the new-edge test, orientation,
duplicate and fixed edges, then an independent set of the allowed swaps) is some sixty small
array operations; on the few hundred edges of a patch their overhead is most of the
refinement's time. :func:`swap_candidates` and :func:`apply_swaps` do the same round element
by element: the same IEEE operations in the same order (row cross products, norms and einsum
dots as in :mod:`._vector_kernels`), so every integer answer is the numpy code's, with one
exception handled by deferring: the numpy code's ``arctan2`` is numpy's SIMD routine, which
may differ from libm's in the last bits. The angle sums it feeds are only compared with
pi (1 + 1e-9); when a sum lies within ``ANGLE_MARGIN`` (thousands of times that difference)
of it, :func:`swap_candidates` answers ``UNSURE`` and the caller runs the round in numpy.
tests/geometry/test_flips.py checks whole relaxations against the numpy rounds.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._vector_kernels import cross3, dot3, norm3, npmin, sub3

# The kernels of the compiled rounds (pair_angle_parts serves flips.min_angle_scores, the scored rounds).
__all__ = ["swap_candidates", "apply_swaps", "fixed_keys", "NO_EDGES", "NO_FAILING", "CANDIDATES", "UNSURE", "ANGLE_MARGIN"]

NO_EDGES, NO_FAILING, CANDIDATES, UNSURE = 0, 1, 2, 3
ANGLE_MARGIN = 1e-12


@njit(cache=True)
def _row(V, i):
    return (V[i, 0], V[i, 1], V[i, 2])


@njit(cache=True)
def _angle_parts(V, p, q, r):
    """(|u x w|, u . w) of the angle at p of the triangle (p, q, r), as flips._angle_at computes them."""
    P = _row(V, p)
    u, w = sub3(_row(V, q), P), sub3(_row(V, r), P)
    return norm3(cross3(u, w)), dot3(u, w)


@njit(cache=True)
def _angle_sum_exceeds(V, p1, q1, r1, p2, q2, r2):
    """1 / 0 when angle(p1; q1, r1) + angle(p2; q2, r2) > pi (1 + 1e-9) clearly holds / fails, -1 if too close.

    Most sums are far from the limit, and the sign of sin(alpha + beta) (no arctan2) tells
    which side they are on: below -1e-6 the sum lies in (pi + 1e-6, 2 pi), above 1e-6 in
    (1e-6, pi - 1e-6), both angles being in [0, pi]; its rounding error is of order 1e-15.
    Other sums are computed by arctan2 as the numpy code does.
    """
    s1, c1 = _angle_parts(V, p1, q1, r1)
    s2, c2 = _angle_parts(V, p2, q2, r2)
    sine = s1 * c2 + c1 * s2
    scale = math.sqrt(s1 * s1 + c1 * c1) * math.sqrt(s2 * s2 + c2 * c2)
    if sine < -1e-6 * scale:
        return 1
    if sine > 1e-6 * scale:
        return 0
    s = math.atan2(s1, c1) + math.atan2(s2, c2)
    limit = np.pi * (1 + 1e-9)
    if not abs(s - limit) > ANGLE_MARGIN:  # NaN too: the numpy code's two tests treat it differently
        return -1
    return 1 if s > limit else 0


@njit(cache=True)
def _circumsphere(V, p, q, r):
    """flips.circumcenters of the triangle (p, q, r) for one row: (centre, radius), inf for a degenerate one."""
    A = _row(V, p)
    u, w = sub3(_row(V, q), A), sub3(_row(V, r), A)
    uxw = cross3(u, w)
    denom = 2.0 * dot3(uxw, uxw)
    uu, ww = dot3(u, u), dot3(w, w)
    num = cross3((uu * w[0] - ww * u[0], uu * w[1] - ww * u[1], uu * w[2] - ww * u[2]), uxw)
    if not denom > 0:
        return A, np.inf
    offset = (num[0] / denom, num[1] / denom, num[2] / denom)
    return (A[0] + offset[0], A[1] + offset[1], A[2] + offset[2]), norm3(offset)


@njit(cache=True)
def _sphere_distance(V, p, q, r, x):
    """(|x - centre|, radius (1 - 1e-9)) for the circumsphere of (p, q, r): flips' tests compare the two
    (strictly inside: ``<``; the new-edge test's outside: ``>=``; both False for NaN, as in numpy)."""
    centre, radius = _circumsphere(V, p, q, r)
    return norm3(sub3(_row(V, x), centre)), radius * (1 - 1e-9)


@njit(cache=True)
def _swap_tests(V, a, b, c, d, sphere):
    """(edge fails the test, new edge passes it) for edge (a, b) with opposite corners c, d:
    1 / 0 each, -1 when an angle sum is too close to decide (the circumsphere tests always decide)."""
    if sphere:
        d1, r1 = _sphere_distance(V, a, b, c, d)
        d2, r2 = _sphere_distance(V, b, a, d, c)
        if not (d1 < r1 or d2 < r2):
            return 0, 0
        d3, r3 = _sphere_distance(V, a, d, c, b)
        d4, r4 = _sphere_distance(V, b, c, d, a)
        return 1, 1 if d3 >= r3 and d4 >= r4 else 0
    inside = _angle_sum_exceeds(V, c, a, b, d, a, b)
    if inside != 1:
        return inside, 0
    passes = _angle_sum_exceeds(V, a, d, c, b, c, d)
    return 1, -1 if passes < 0 else 1 - passes


@njit(cache=True)
def _keeps_orientation(V, a, b, c, d):
    """flips._keeps_orientation with normal_cos = 0 for one edge."""
    A, B, C, D = _row(V, a), _row(V, b), _row(V, c), _row(V, d)
    o1 = cross3(sub3(B, A), sub3(C, A))
    o2 = cross3(sub3(A, B), sub3(D, B))
    old = (o1[0] + o2[0], o1[1] + o2[1], o1[2] + o2[2])
    n1 = cross3(sub3(D, A), sub3(C, A))
    n2 = cross3(sub3(C, B), sub3(D, B))
    return dot3(n1, old) > 0 and dot3(n2, old) > 0


@njit(cache=True)
def _contains(sorted_keys, key):
    i = np.searchsorted(sorted_keys, key)
    return i < sorted_keys.shape[0] and sorted_keys[i] == key


@njit(cache=True)
def _outgoing(F, n):
    """Half-edges grouped by their first vertex: h = 3 f + j (F[f, j] -> F[f, (j + 1) % 3]) for
    start[a] <= r < start[a + 1] in ascending h, with tip[r] the end vertex of half[r]; ok=False
    when an index is out of range or a directed edge repeats (the numpy code's order of such
    edges is its own)."""
    m = F.shape[0]
    start = np.zeros(n + 1, np.int64)
    half = np.empty(3 * m, np.int64)
    tip = np.empty(3 * m, np.int64)
    for f in range(m):
        for j in range(3):
            a = F[f, j]
            if a < 0 or a >= n:
                return start, half, tip, False
            start[a + 1] += 1
    for a in range(n):
        start[a + 1] += start[a]
    fill = start[:-1].copy()
    for f in range(m):
        for j in range(3):
            a, b = F[f, j], F[f, (j + 1) % 3]
            if b < 0 or b >= n:
                return start, half, tip, False
            r = fill[a]
            for t in range(start[a], r):
                if tip[t] == b:
                    return start, half, tip, False
            half[r], tip[r] = 3 * f + j, b
            fill[a] = r + 1
    return start, half, tip, True


@njit(cache=True)
def _find(start, half, tip, a, b):
    """The half-edge a -> b, or -1."""
    for r in range(start[a], start[a + 1]):
        if tip[r] == b:
            return half[r]
    return -1


@njit(cache=True)
def _interior_edges(F, n):
    """topology.interior_edges: (he, tw) half-edge indices of each interior edge (he ascending),
    the half-edge table, and ok=False when the numpy code must decide (see :func:`_outgoing`)."""
    m = F.shape[0]
    start, half, tip, fine = _outgoing(F, n)
    he = np.empty(3 * m, np.int64)
    tw = np.empty(3 * m, np.int64)
    if not fine:
        return he[:0], tw[:0], start, half, tip, False
    e = 0
    for f in range(m):
        for j in range(3):
            a, b = F[f, j], F[f, (j + 1) % 3]
            if a < b:
                t = _find(start, half, tip, b, a)
                if t >= 0:
                    he[e], tw[e] = 3 * f + j, t
                    e += 1
    return he[:e], tw[:e], start, half, tip, True


@njit(cache=True)
def swap_candidates(V, F, fixed, sphere):
    """One round of relax_edges (criterion "angles", or "sphere" if ``sphere``; normal_cos 0) up to
    the ``allowed`` hook.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int64
    fixed : (p,) int64 sorted unique keys min * n + max of the fixed edges
    sphere : bool  the circumsphere test instead of the unfolded-angle test

    Returns
    -------
    status : NO_EDGES, NO_FAILING (the numpy code stops), CANDIDATES, or UNSURE (run numpy)
    abcd : (e, 4) int64  each interior edge (a, b) and its opposite corners c (in f1), d (in f2)
    f1f2 : (e, 2) int64  the faces holding a -> b and b -> a
    ok : (e,) bool       edges to swap before the ``allowed`` hook
    new_key : (e,) int64 min(c, d) * n + max(c, d)
    """
    n = V.shape[0]
    he, tw, start, half, tip, fine = _interior_edges(F, n)
    e = he.shape[0]
    abcd = np.empty((e, 4), np.int64)
    f1f2 = np.empty((e, 2), np.int64)
    ok = np.zeros(e, np.bool_)
    new_key = np.empty(e, np.int64)
    if not fine:
        return UNSURE, abcd, f1f2, ok, new_key
    if e == 0:
        return NO_EDGES, abcd, f1f2, ok, new_key
    failing = 0
    for i in range(e):
        f1, c1, f2, c2 = he[i] // 3, he[i] % 3, tw[i] // 3, tw[i] % 3
        a, b, c, d = F[f1, c1], F[f1, (c1 + 1) % 3], F[f1, (c1 + 2) % 3], F[f2, (c2 + 2) % 3]
        abcd[i, 0], abcd[i, 1], abcd[i, 2], abcd[i, 3] = a, b, c, d
        f1f2[i, 0], f1f2[i, 1] = f1, f2
        new_key[i] = min(c, d) * n + max(c, d)
        inside, passes = _swap_tests(V, a, b, c, d, sphere)
        if inside < 0 or passes < 0:
            return UNSURE, abcd, f1f2, ok, new_key
        if inside == 1:
            failing += 1
            ok[i] = passes == 1 and _keeps_orientation(V, a, b, c, d) and c != d
    if failing == 0:
        return NO_FAILING, abcd, f1f2, ok, new_key
    for i in range(e):
        if ok[i]:
            a, b, c, d = abcd[i, 0], abcd[i, 1], abcd[i, 2], abcd[i, 3]
            old_key = min(a, b) * n + max(a, b)
            exists = _find(start, half, tip, c, d) >= 0 or _find(start, half, tip, d, c) >= 0
            ok[i] = not exists and not _contains(fixed, old_key) and not _contains(fixed, new_key[i])
    return CANDIDATES, abcd, f1f2, ok, new_key


@njit(cache=True)
def apply_swaps(F, cand, abcd, f1f2, new_key):
    """flips._independent_swaps (unscored: priority = edge index) and the swap of the chosen edges.

    F is changed in place (:func:`choose_swaps`, then each chosen edge (a, b) becomes (c, d));
    returns the number of swaps.
    """
    chosen = choose_swaps(cand, f1f2, new_key, F.shape[0])
    for x in chosen:
        swap_faces(F, abcd[x, 0], abcd[x, 1], abcd[x, 2], abcd[x, 3], f1f2[x, 0], f1f2[x, 1])
    return chosen.shape[0]


@njit(cache=True)
def swap_faces(F, a, b, c, d, f1, f2):
    """Faces f1 = (a, b, c), f2 = (b, a, d) become (a, d, c), (b, c, d)."""
    F[f1, 0], F[f1, 1], F[f1, 2] = a, d, c
    F[f2, 0], F[f2, 1], F[f2, 2] = b, c, d


@njit(cache=True)
def choose_swaps(cand, f1f2, new_key, m):
    """The candidates flips._independent_swaps picks (unscored: priority = candidate index), in its order.

    Up to four claiming passes; in each, a candidate wins when it has the highest index among
    the remaining candidates at both its faces. Of chosen swaps making the same new edge the first
    chosen is kept.

    Parameters
    ----------
    cand : (s,) int64 ascending indices into f1f2 and new_key
    f1f2 : (e, 2) int64, new_key : (e,) int64
    m : int  face count

    Returns
    -------
    (t,) int64 the chosen candidates, no two sharing a face or a new edge
    """
    taken = np.zeros(m, np.bool_)
    claim = np.empty(m, np.int64)
    chosen = np.empty(cand.shape[0], np.int64)
    count = 0
    rest = cand.copy()
    for _ in range(4):
        keep = np.empty(rest.shape[0], np.int64)
        r = 0
        for x in rest:
            if not taken[f1f2[x, 0]] and not taken[f1f2[x, 1]]:
                keep[r] = x
                r += 1
        rest = keep[:r]
        if r == 0:
            break
        for x in rest:
            claim[f1f2[x, 0]] = -1
            claim[f1f2[x, 1]] = -1
        for x in rest:
            claim[f1f2[x, 0]] = max(claim[f1f2[x, 0]], x)
            claim[f1f2[x, 1]] = max(claim[f1f2[x, 1]], x)
        won_start = count
        for x in rest:
            if claim[f1f2[x, 0]] == x and claim[f1f2[x, 1]] == x:
                chosen[count] = x
                count += 1
        for i in range(won_start, count):
            taken[f1f2[chosen[i], 0]] = True
            taken[f1f2[chosen[i], 1]] = True
    made = 0
    seen = np.empty(count, np.int64)
    for i in range(count):
        x = chosen[i]
        if _seen_before(seen, made, new_key[x]):
            continue
        seen[made] = new_key[x]
        chosen[made] = x
        made += 1
    return chosen[:made]


@njit(cache=True)
def _seen_before(seen, count, key):
    for i in range(count):
        if seen[i] == key:
            return True
    return False


@njit(cache=True)
def pair_angle_parts(V, faces):
    """(|u x w|, u . w) of every corner of the faces ``faces`` (t, s, 3), as quality.corner_angles computes them.

    Corner k of a face (i0, i1, i2) is the angle at F[k] between u = V[F[k + 1]] - V[F[k]] and
    w = V[F[k + 2]] - V[F[k]] (indices mod 3): the arguments of corner_angles' arctan2, bit for
    bit (row cross product, norm and einsum dot of :mod:`._vector_kernels`). The arctan2 stays
    numpy's (see the module docstring), applied to the returned arrays.

    Returns
    -------
    sines, cosines : (t, s, 3) float64
    """
    t, s, _ = faces.shape
    sines = np.empty((t, s, 3))
    cosines = np.empty((t, s, 3))
    for a in range(t):
        for i in range(s):
            for k in range(3):
                sines[a, i, k], cosines[a, i, k] = _angle_parts(V, faces[a, i, k], faces[a, i, (k + 1) % 3],
                                                                faces[a, i, (k + 2) % 3])
    return sines, cosines


@njit(cache=True)
def fixed_keys(E, n):
    """Sorted distinct keys min * n + max of the edges E (e, 2) int64, (k,) int64.

    ``unique_ints(undirected_keys(E, n))`` in one call, the fixed-edge table of the relaxations
    (:func:`..flips.relax_edges`, hu2012's compiled rounds): a refinement relaxes a few hundred
    times, each time with the keys for its current vertex count, and numpy's calls cost more
    than the sort of a hole's few dozen edges.
    """
    keys = np.empty(E.shape[0], np.int64)
    for r in range(E.shape[0]):
        keys[r] = min(E[r, 0], E[r, 1]) * n + max(E[r, 0], E[r, 1])
    keys.sort()
    k = 0
    for r in range(keys.shape[0]):
        if r == 0 or keys[r] != keys[k - 1]:
            keys[k] = keys[r]
            k += 1
    return keys[:k].copy()


@njit(cache=True)
def min_angle_round_faces(V, F):
    """The start of a ``criterion="min_angle"`` round of :func:`..flips.relax_edges`: the edge table and scored faces.

    Returns
    -------
    fine : bool  False when the numpy code must build the edge table (see :func:`_interior_edges`)
    he, tw : (e,) int64  each interior edge's half-edge a -> b and its twin, as :func:`_interior_edges`
    start, half, tip : the half-edge table (:func:`_find` looks an edge up in it)
    faces : (4, e, 3) int64  each edge's faces F[f1], F[f2] and the swapped pair (a, d, c), (b, c, d)
    sines, cosines : (4, e, 3) float64  the corners' arctan2 arguments (:func:`pair_angle_parts`)
    """
    n = V.shape[0]
    he, tw, start, half, tip, fine = _interior_edges(F, n)
    e = he.shape[0]
    faces = np.empty((4, e, 3), np.int64)
    if not fine:
        return False, he, tw, start, half, tip, faces, np.empty((4, e, 3)), np.empty((4, e, 3))
    for i in range(e):
        f1, c1, f2, c2 = he[i] // 3, he[i] % 3, tw[i] // 3, tw[i] % 3
        a, b, c, d = F[f1, c1], F[f1, (c1 + 1) % 3], F[f1, (c1 + 2) % 3], F[f2, (c2 + 2) % 3]
        for j in range(3):
            faces[0, i, j], faces[1, i, j] = F[f1, j], F[f2, j]
        faces[2, i, 0], faces[2, i, 1], faces[2, i, 2] = a, d, c
        faces[3, i, 0], faces[3, i, 1], faces[3, i, 2] = b, c, d
    sines, cosines = pair_angle_parts(V, faces)
    return True, he, tw, start, half, tip, faces, sines, cosines


@njit(cache=True)
def _unit(n):
    """geometry.quality.face_normals' row division: n / |n|, zero when |n| is not > 0."""
    ln = norm3(n)
    if ln > 0:
        return (n[0] / ln, n[1] / ln, n[2] / ln)
    return (0.0, 0.0, 0.0)


@njit(cache=True)
def min_angle_round_swaps(V, F, he, tw, start, half, tip, faces, angles, fixed, normal_cos):
    """The rest of a ``criterion="min_angle"`` round of :func:`..flips.relax_edges` (no ``allowed``), F changed in place.

    The numpy round's choices in order: each pair's smallest angle (pairwise minima of the
    corners' ``angles``), the edges gaining more than 1e-9 ranked by a stable sort of the gain
    (largest first), the swaps whose new triangles stay within ``normal_cos`` of the old pair's
    normal (``flips._keeps_orientation``), keep c and d distinct, create no edge of F and touch no
    ``fixed`` key, one claiming pass, then the first of each new edge in priority order.

    Returns
    -------
    status : NO_FAILING (nothing swapped: the numpy loop stops), CANDIDATES (swapped), or UNSURE
        (an angle is NaN, where the numpy code takes another minimum: run the round in numpy)
    swaps : int
    """
    e = he.shape[0]
    n = V.shape[0]
    smallest = np.empty((4, e))
    for t in range(4):
        for i in range(e):
            x, y, z = angles[t, i, 0], angles[t, i, 1], angles[t, i, 2]
            if x != x or y != y or z != z:
                return UNSURE, 0
            smallest[t, i] = npmin(npmin(x, y), z)
    old = np.empty(e)
    new = np.empty(e)
    for i in range(e):
        old[i] = npmin(smallest[0, i], smallest[1, i])
        new[i] = npmin(smallest[2, i], smallest[3, i])
    failing = np.flatnonzero(new > old + 1e-9)
    if failing.shape[0] == 0:
        return NO_FAILING, 0
    gain = new - old
    priority = np.zeros(e, np.int64)
    order = np.argsort(-gain[failing], kind="mergesort")
    for rank in range(order.shape[0]):
        priority[failing[order[rank]]] = failing.shape[0] - rank
    cand = np.empty(failing.shape[0], np.int64)
    count = 0
    for i in failing:
        a, d, c, b = faces[2, i, 0], faces[2, i, 1], faces[2, i, 2], faces[3, i, 0]  # (a, d, c), (b, c, d)
        pa = (V[a, 0], V[a, 1], V[a, 2])
        pb = (V[b, 0], V[b, 1], V[b, 2])
        pc = (V[c, 0], V[c, 1], V[c, 2])
        pd = (V[d, 0], V[d, 1], V[d, 2])
        n_old1, n_old2 = cross3(sub3(pb, pa), sub3(pc, pa)), cross3(sub3(pa, pb), sub3(pd, pb))
        old_n = (n_old1[0] + n_old2[0], n_old1[1] + n_old2[1], n_old1[2] + n_old2[2])
        n1, n2 = cross3(sub3(pd, pa), sub3(pc, pa)), cross3(sub3(pc, pb), sub3(pd, pb))
        if normal_cos == 0.0:
            keeps = dot3(n1, old_n) > 0 and dot3(n2, old_n) > 0
        else:
            ln = norm3(old_n)
            ln = ln if ln != ln or ln > 1e-300 else 1e-300  # np.maximum(norm, 1e-300), NaN kept
            unit_old = (old_n[0] / ln, old_n[1] / ln, old_n[2] / ln)
            keeps = dot3(_unit(n1), unit_old) > normal_cos and dot3(_unit(n2), unit_old) > normal_cos
        if not keeps or c == d:
            continue
        if _find(start, half, tip, c, d) >= 0 or _find(start, half, tip, d, c) >= 0:
            continue
        key = min(c, d) * n + max(c, d)
        if fixed.shape[0] and (sorted_contains(fixed, min(a, b) * n + max(a, b)) or sorted_contains(fixed, key)):
            continue
        cand[count] = i
        count += 1
    if count == 0:
        return NO_FAILING, 0
    cand = cand[:count]
    new_key = np.empty(e, np.int64)
    for i in range(e):
        new_key[i] = min(faces[2, i, 2], faces[2, i, 1]) * n + max(faces[2, i, 2], faces[2, i, 1])
    swaps = apply_scored_swaps(F, he // 3, tw // 3, cand, priority, new_key, faces[2], faces[3])
    return CANDIDATES, swaps


@njit(cache=True)
def apply_scored_swaps(F, f1, f2, cand, priority, new_key, new1, new2):
    """``flips._independent_swaps`` of a scored criterion, then the swaps, F changed in place; the swaps made.

    One claiming pass (each face goes to its candidate of highest ``priority``), the winners in
    priority order (stable), of those creating the same edge (``new_key``) the first; edge i's
    faces f1[i], f2[i] become new1[i], new2[i]. ``cand`` lists candidate edges in edge order.
    """
    claim = np.full(F.shape[0], -1, np.int64)
    for i in cand:
        claim[f1[i]] = max(claim[f1[i]], priority[i])
        claim[f2[i]] = max(claim[f2[i]], priority[i])
    won = np.empty(cand.shape[0], np.int64)
    count = 0
    for i in cand:
        if claim[f1[i]] == priority[i] and claim[f2[i]] == priority[i]:
            won[count] = i
            count += 1
    won = won[:count]
    won = won[np.argsort(-priority[won], kind="mergesort")]
    keys = new_key[won]
    swaps = 0
    previous = -1
    for t in np.argsort(keys, kind="mergesort"):  # np.unique(return_index=True): each new edge's first
        if keys[t] == previous:
            continue
        previous = keys[t]
        for j in range(3):
            F[f1[won[t]], j] = new1[won[t], j]
            F[f2[won[t]], j] = new2[won[t], j]
        swaps += 1
    return swaps


@njit(cache=True)
def sorted_contains(keys, value):
    """Whether the sorted array ``keys`` holds ``value``."""
    i = np.searchsorted(keys, value)
    return i < keys.shape[0] and keys[i] == value
