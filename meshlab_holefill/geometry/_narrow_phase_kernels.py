"""Compiled narrow phase of the triangle-triangle queries (numba): the verdict on each candidate pair.

`intersections.intersecting_pairs` used to test the candidate pairs (:mod:`._broad_phase_kernels`)
with numpy expressions over (k, 3, 3) arrays, a hundred temporaries per call; with the search
for the candidates they took most of the crossing checks' time. Here each pair is tested by
scalar code that does, element by element, the same IEEE operations in the same order as that
numpy code (no fastmath, no contraction to FMA; row norms add the squares left to right as
numpy's add.reduce does, row dots in numpy's einsum order, see :mod:`._vector_kernels`), so every
predicate, tolerance and boolean answer is the same bit for bit. tests/geometry/test_tri_kernels.py
checks the pair verdicts and the whole query against that numpy code, kept as the reference in
tests/intersections_numpy.py. The one transcendental step, the arctan2 of a shared-edge fold,
stays in numpy (its SIMD arctan2 may differ from libm's in the last bits): `narrow_codes`
returns its two arguments.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._vector_kernels import add3, cross3, div3, dot3, face_corner, norm3, npmax, npmin, scale3, sub3, unit3

__all__ = ["narrow_codes", "NO", "HIT", "FOLD"]

NO, HIT, FOLD = 0, 1, 2  # narrow_codes: no contact, contact, shared edge whose fold angle decides


@njit(cache=True)
def _unit_normal(t0, t1, t2, tol):
    """intersections._unit_normal for one triangle: (normal, degenerate)."""
    n = cross3(sub3(t1, t0), sub3(t2, t0))
    ln = norm3(n)
    longest = npmax(npmax(norm3(sub3(t0, t1)), norm3(sub3(t1, t2))), norm3(sub3(t2, t0)))
    deg = ln <= tol * longest
    return div3(n, 1.0 if deg else ln), deg


@njit(cache=True)
def _heights(t0, n, s0, s1, s2):
    """Signed heights of triangle s's corners above the plane of t (corner t0, normal n): the dots both
    intersections._beyond_plane and the slab of intersections._clip take."""
    return dot3(sub3(s0, t0), n), dot3(sub3(s1, t0), n), dot3(sub3(s2, t0), n)


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
        t0 = npmax(t0, c0 / (1.0 if den == 0 else den))
    elif c0 >= 0 and c1 < 0:
        den = c0 - c1
        t1 = npmin(t1, c0 / (1.0 if den == 0 else den))
    return ok, t0, t1


@njit(cache=True)
def _clip_frame(T0, T1, T2, nt):
    """The target's clipping directions, as intersections._clip computes them for every edge:
    edge normals in the plane ms and corner bisectors us, 18 numbers as a flat tuple."""
    m0, m1, m2 = (unit3(cross3(nt, sub3(T1, T0))), unit3(cross3(nt, sub3(T2, T1))),
                  unit3(cross3(nt, sub3(T0, T2))))
    u0 = unit3(add3(unit3(sub3(T1, T0)), unit3(sub3(T2, T0))))
    u1 = unit3(add3(unit3(sub3(T2, T1)), unit3(sub3(T0, T1))))
    u2 = unit3(add3(unit3(sub3(T0, T2)), unit3(sub3(T1, T2))))
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
            n, deg[t] = _unit_normal(face_corner(V, F, f, 0), face_corner(V, F, f, 1), face_corner(V, F, f, 2), tol)
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
            c0, c1 = dot3(sub3(P0, a), direction) + grow, dot3(sub3(P1, a), direction) + grow
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
    c0, c1 = dot3(sub3(P0, a), d) + grow, dot3(sub3(P1, a), d) + grow
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
        D = sub3(P1, P0)
        f0 = norm3(sub3(add3(P0, scale3(D, t0)), S))
        f1 = norm3(sub3(add3(P0, scale3(D, t1)), S))
        if npmax(f0, f1) > tol:
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
        A0, A1, A2 = face_corner(V, F, i, 0), face_corner(V, F, i, 1), face_corner(V, F, i, 2)
        B0, B1, B2 = face_corner(V, F, j, 0), face_corner(V, F, j, 1), face_corner(V, F, j, 2)
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
                e = unit3(sub3(Q, P))
                ua, ub = sub3(A[o1], P), sub3(B[o2], P)
                ua = sub3(ua, scale3(e, dot3(ua, e)))
                ub = sub3(ub, scale3(e, dot3(ub, e)))
                code[p] = FOLD
                fy[p] = norm3(cross3(ua, ub))
                fx[p] = dot3(ua, ub)
        else:
            one = nsh == 1
            s = 0 if sh1[0] else (1 if sh1[1] else (2 if sh1[2] else 0))  # argmax of sh1
            s2 = 0 if sh2[0] else (1 if sh2[1] else (2 if sh2[2] else 0))
            S = A0 if s == 0 else (A1 if s == 1 else A2)
            if (_edges_meet(A0, A1, A2, B0, B1, B2, dA, frame, done, sj, n2, sh1, deg1, deg2, one, S, s2, tol)
                    or _edges_meet(B0, B1, B2, A0, A1, A2, dB, frame, done, si, n1, sh2, deg2, deg1, one, S, s, tol)):
                code[p] = HIT
    return code, fy, fx
