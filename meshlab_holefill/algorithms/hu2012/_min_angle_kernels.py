"""Compiled minimum-angle triangulation (numba): the loop of :class:`.min_angle_triangulation._Ears`.

The per-ear work of Sec. III.B (Eq. 2 angles, the normal test, the hole-sector and ear
conditions) is a few dozen float operations, which in Python cost far more in interpreter
and small-array overhead than in arithmetic. :func:`min_angle_faces` runs the same loop on
the same floats:

* the scalar steps (Eq. 2 angle, hole sector) do the IEEE operations of the Python code in the
  same order; Python's ``x ** 2`` is libm's ``pow``, which is not always ``x * x``, so the kernel
  calls ``math.pow`` with the exponent passed in at run time (a constant 2.0 is turned into a
  product by the compiler);
* the steps the Python code makes with numpy's BLAS dot products (the normal test and the ear
  condition of ``_ear_holds_a_vertex``) may round differently in the last bits. Their only use
  is a comparison with a threshold, so the kernel decides each comparison only when its value
  lies clearly (relative margin ``MARGIN``, a thousand times the rounding error of a
  three-term dot product) on one side; otherwise it stops with ``UNSURE`` and the caller
  runs the Python code, so the faces are those of the Python code in every case.

tests/algorithms/hu2012/test_min_angle_kernels.py checks the kernel against the Python code.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["min_angle_faces", "OK", "UNSURE", "FAILED", "MARGIN"]

OK, UNSURE, FAILED = 0, 1, 2  # FAILED: the Python code raises (no valid ear, last triangle)
MARGIN = 1e-12


@njit(cache=True)
def _vertex_angle(P, N, p, v, n, two):
    """_vertex_angle of the Python code: (Eq. 2 angle of ear v, |u x w|)."""
    u0, u1, u2 = P[p, 0] - P[v, 0], P[p, 1] - P[v, 1], P[p, 2] - P[v, 2]
    w0, w1, w2 = P[n, 0] - P[v, 0], P[n, 1] - P[v, 1], P[n, 2] - P[v, 2]
    c0, c1, c2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
    area2 = math.sqrt(math.pow(c0, two) + math.pow(c1, two) + math.pow(c2, two))
    theta = math.atan2(area2, u0 * w0 + u1 * w1 + u2 * w2)
    convex = -(c0 * N[v, 0] + c1 * N[v, 1] + c2 * N[v, 2]) >= 0
    return (theta if convex else 2 * math.pi - theta), area2


@njit(cache=True)
def _sector_phi(apex, u0, u1, u2, w0, w1, w2, P, t):
    d0, d1, d2 = P[t, 0] - P[apex, 0], P[t, 1] - P[apex, 1], P[t, 2] - P[apex, 2]
    return math.atan2(d0 * w0 + d1 * w1 + d2 * w2, d0 * u0 + d1 * u1 + d2 * u2) % (2 * math.pi)


@njit(cache=True)
def _in_sector(P, N, apex, prev_i, next_i, target, two, margin=1e-9):
    """_in_sector of the Python code, on loop indices."""
    nl = max(math.sqrt(math.pow(N[apex, 0], two) + math.pow(N[apex, 1], two) + math.pow(N[apex, 2], two)), 1e-300)
    n0, n1, n2 = N[apex, 0] / nl, N[apex, 1] / nl, N[apex, 2] / nl
    u0, u1, u2 = P[next_i, 0] - P[apex, 0], P[next_i, 1] - P[apex, 1], P[next_i, 2] - P[apex, 2]
    un = u0 * n0 + u1 * n1 + u2 * n2
    u0, u1, u2 = u0 - un * n0, u1 - un * n1, u2 - un * n2
    ul = max(math.sqrt(math.pow(u0, two) + math.pow(u1, two) + math.pow(u2, two)), 1e-300)
    u0, u1, u2 = u0 / ul, u1 / ul, u2 / ul
    w0, w1, w2 = n1 * u2 - n2 * u1, n2 * u0 - n0 * u2, n0 * u1 - n1 * u0
    phi = _sector_phi(apex, u0, u1, u2, w0, w1, w2, P, target)
    return margin < phi < _sector_phi(apex, u0, u1, u2, w0, w1, w2, P, prev_i) - margin


@njit(cache=True)
def _side(value, magnitude, tol):
    """1 when value >= tol clearly, 0 when clearly below, -1 when within the margin."""
    slack = MARGIN * (magnitude + abs(tol))
    if value - tol > slack:
        return 1
    if tol - value > slack:
        return 0
    return -1


@njit(cache=True)
def _ear_holds_a_vertex(P, p, v, n, active):
    """_ear_holds_a_vertex of the Python code: 1 (a vertex in the ear), 0 (none), -1 (unsure)."""
    a0, a1, a2 = P[p, 0], P[p, 1], P[p, 2]
    e0, e1, e2 = P[v, 0] - a0, P[v, 1] - a1, P[v, 2] - a2  # B - A
    f0, f1, f2 = P[n, 0] - a0, P[n, 1] - a1, P[n, 2] - a2  # C - A
    t0, t1, t2 = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
    sq = (t0 * t0 + t1 * t1) + t2 * t2
    if sq == 0.0:
        return 0
    if sq < 1e-280:  # squares near underflow: leave it to the Python code
        return -1
    area2 = math.sqrt(sq)
    t0, t1, t2 = t0 / area2, t1 / area2, t2 / area2
    g0, g1, g2 = P[n, 0] - P[v, 0], P[n, 1] - P[v, 1], P[n, 2] - P[v, 2]  # C - B
    longest = max((e0 * e0 + e1 * e1) + e2 * e2, max((g0 * g0 + g1 * g1) + g2 * g2, (f0 * f0 + f1 * f1) + f2 * f2))
    reach = 0.5 * math.sqrt(longest)
    corners = (p, v, n)
    unsure = False
    for q in range(P.shape[0]):
        if not active[q] or q == p or q == v or q == n:
            continue
        d0, d1, d2 = P[q, 0] - a0, P[q, 1] - a1, P[q, 2] - a2
        height = (d0 * t0 + d1 * t1) + d2 * t2
        near = _side(reach, abs(d0) + abs(d1) + abs(d2) + reach, abs(height))  # |height| <= reach
        if near == 0:
            continue
        x0, x1, x2 = P[q, 0] - height * t0, P[q, 1] - height * t1, P[q, 2] - height * t2
        inside = 1
        for s in range(3):
            X, Y = corners[(s + 1) % 3], corners[(s + 2) % 3]  # sides B->C, C->A, A->B
            y0, y1, y2 = P[Y, 0] - P[X, 0], P[Y, 1] - P[X, 1], P[Y, 2] - P[X, 2]
            m0, m1, m2 = t1 * y2 - t2 * y1, t2 * y0 - t0 * y2, t0 * y1 - t1 * y0
            r0, r1, r2 = x0 - P[X, 0], x1 - P[X, 1], x2 - P[X, 2]
            value = ((r0 * m0 + r1 * m1) + r2 * m2) / area2
            # |r.m| plus what an error in height (of the order of |d|) can change it by
            magnitude = (abs(r0 * m0) + abs(r1 * m1) + abs(r2 * m2)
                         + (abs(d0) + abs(d1) + abs(d2) + abs(height)) * (abs(m0) + abs(m1) + abs(m2))) / area2
            side = _side(value, magnitude, -1e-9)
            if side == 0:
                inside = 0
                break
            if side < 0:
                inside = -1
        if inside == 1 and near == 1:
            return 1
        if inside != 0:
            unsure = True
    return -1 if unsure else 0


@njit(cache=True)
def _is_forbidden(keys, a, b, k):
    key = min(a, b) * k + max(a, b)
    i = np.searchsorted(keys, key)
    return i < keys.shape[0] and keys[i] == key


@njit(cache=True)
def _evaluate(P, N, v, prv, nxt, angle, cuttable, agree, verdict, keys, cos_sigma, area_tol, two):
    """_Ears.evaluate; False when the normal test is too close to call."""
    p, n = prv[v], nxt[v]
    k = P.shape[0]
    angle[v], area2 = _vertex_angle(P, N, p, v, n, two)
    cuttable[v] = area2 > area_tol and not _is_forbidden(keys, p, n, k)
    dot = (N[p, 0] * N[n, 0] + N[p, 1] * N[n, 1]) + N[p, 2] * N[n, 2]
    side = _side(dot, abs(N[p, 0] * N[n, 0]) + abs(N[p, 1] * N[n, 1]) + abs(N[p, 2] * N[n, 2]), cos_sigma)
    agree[v] = side == 1
    verdict[v] = -1
    return side >= 0


@njit(cache=True)
def _proper(P, N, v, prv, nxt, active, verdict, two):
    """_Ears.proper, cached in ``verdict`` (-1 unknown, 0, 1); -2 when unsure."""
    if verdict[v] < 0:
        p, n = prv[v], nxt[v]
        ok = _in_sector(P, N, p, prv[p], v, n, two) and _in_sector(P, N, n, v, nxt[n], p, two)
        if ok:
            holds = _ear_holds_a_vertex(P, p, v, n, active)
            if holds < 0:
                return -2
            ok = holds == 0
        verdict[v] = 1 if ok else 0
    return verdict[v]


@njit(cache=True)
def _pick(P, N, prv, nxt, active, angle, cuttable, agree, verdict, two):
    """_Ears.pick: the vertex to cut, -1 when none is left, -2 when unsure."""
    k = P.shape[0]
    tried = np.zeros(k, np.bool_)
    for tier in range(2):
        tried[:] = False
        while True:  # candidates by increasing angle, ties by index (the stable sort of the Python code)
            best = -1
            for u in range(k):
                if active[u] and cuttable[u] and (tier == 1 or agree[u]) and not tried[u]:
                    if math.isnan(angle[u]):
                        return -2
                    if best < 0 or angle[u] < angle[best]:
                        best = u
            if best < 0:
                break
            verdict_u = _proper(P, N, best, prv, nxt, active, verdict, two)
            if verdict_u == -2:
                return -2
            if verdict_u == 1:
                return best
            tried[best] = True
    best = -1
    for u in range(k):
        if active[u] and cuttable[u] and (best < 0 or angle[u] < angle[best]):
            best = u
    return best


@njit(cache=True)
def min_angle_faces(P, N, cos_sigma, keys, area_tol, two):
    """Faces of the modified minimum-angle triangulation, as ``min_angle_triangulation`` makes them.

    Parameters
    ----------
    P, N : (k, 3) float64  loop points and normals (k >= 3)
    cos_sigma : float  cosine of the normal-angle threshold
    keys : (f,) int64 sorted  forbidden edges as min * k + max
    area_tol : float  ears with |u x w| at most this are not cut
    two : float  2.0, passed at run time (see the module docstring)

    Returns
    -------
    faces : (k - 2, 3) int64
    status : OK, UNSURE (run the Python code) or FAILED (the Python code raises)
    """
    k = P.shape[0]
    faces = np.zeros((k - 2, 3), np.int64)
    prv = np.empty(k, np.int64)
    nxt = np.empty(k, np.int64)
    for i in range(k):
        prv[i], nxt[i] = (i - 1) % k, (i + 1) % k
    active = np.ones(k, np.bool_)
    angle = np.full(k, np.inf)
    cuttable = np.zeros(k, np.bool_)
    agree = np.zeros(k, np.bool_)
    verdict = np.full(k, -1, np.int8)
    for v in range(k):
        if not _evaluate(P, N, v, prv, nxt, angle, cuttable, agree, verdict, keys, cos_sigma, area_tol, two):
            return faces, UNSURE
    for f in range(k - 3):
        v = _pick(P, N, prv, nxt, active, angle, cuttable, agree, verdict, two)
        if v == -2:
            return faces, UNSURE
        if v < 0:
            return faces, FAILED
        p, n = prv[v], nxt[v]
        nxt[p], prv[n] = n, p
        active[v] = False
        for u in (prv[p], p, n, nxt[n]):
            if not _evaluate(P, N, u, prv, nxt, angle, cuttable, agree, verdict, keys, cos_sigma, area_tol, two):
                return faces, UNSURE
        faces[f, 0], faces[f, 1], faces[f, 2] = p, v, n
    a = 0
    while not active[a]:
        a += 1
    b = nxt[a]
    c = nxt[b]
    if _is_forbidden(keys, a, b, k) or _is_forbidden(keys, b, c, k) or _is_forbidden(keys, c, a, k):
        return faces, FAILED
    faces[k - 3, 0], faces[k - 3, 1], faces[k - 3, 2] = a, b, c
    return faces, OK
