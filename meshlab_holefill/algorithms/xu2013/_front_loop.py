"""The advancing front's step loop, compiled (numba): Steps 2-6 of Xu et al. 2013, Sec. 3.2.

:func:`run_front` drives one run of :mod:`.advancing_front` from its initial state
(:func:`initial_state`, Step 1) to the closed patch: the node of smallest front angle from the
heap (Step 2), the step there (:mod:`._front_step`: the angle rules, the merges, the checks of
:mod:`._front_kernels` and the obstacles, the update of the fronts; Steps 3-5), the refused
nodes put back on the heap when a step may have changed their verdict, and the last-resort fan
of a small front (Step 6). The state, its pair tables and its heap are :mod:`._front_state`'s.
Every floating-point operation is that of the Python reference (the bookkeeping it replaces,
kept as the tests' oracle ``tests/algorithms/xu2013/xu2013_front_oracle.py``) in the same
order, squares of Python's ``x ** 2`` through ``pow`` (``two``), so both take the same steps
and give the same vertices bit for bit.

:func:`run_front` follows :mod:`._front_step`'s rules on numba's reference counts: it tries the
rules of a step itself rather than in a function taking the tuples, and replaces the state
tuple only when its arrays must grow.

Compiling the loop with the step and state functions it calls (once: ``cache=True`` keeps it on
disk) takes about a minute of CPU on the benchmark machine, against about 10 s for the per-step
kernels alone; loading it from the cache takes about 0.25 s per process
(:func:`.advancing_front.warm_up`).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._front_kernels import near_any
from ._front_state import (DELETED, E_USED, F_USED, FAN_CLOSURES, KEPT_BLOCKED, MAX_FRONT, MERGES, N_ALIVE,
                           N_BLOCKED, N_COUNTERS, N_FACES, N_HEAP, N_NODES, N_VERT, NEXT_LABEL, REJECTED,
                           RELEASED_NEAR, SPLITS, STEPS, FrontArrays, _add_edge, _copy_rows, _empty_table, _find,
                           _has_edge, _has_room, _insert, _kill_node, _with_room, heap_pop, heap_push)
from ._front_step import _apply, _build, _clear_of_obstacles, _face_unit_normal, _rules, _update_node, _valid

# Outcomes of run_front.
CLOSED, TOO_MANY_FACES, GREW, STUCK, LEFT_BALL = 0, 1, 2, 3, 4


# --------------------------------------------------------------------------- the next node, the refused ones
@njit(cache=True)
def _pop(st):
    """The alive node with the smallest front angle (stale heap entries skipped), or -1."""
    while st.C[N_HEAP] > 0:
        node, version = heap_pop(st.ht, st.hn, st.hv, st.C)
        if st.nalive[node] and st.nversion[node] == version:
            return node
    return -1


@njit(cache=True)
def _release_blocked(st):
    """Put the nodes refused since the last change back on the heap (a change may unblock them)."""
    for t in range(st.C[N_BLOCKED]):
        b = st.blocked[t]
        if st.nalive[b]:
            heap_push(st.ht, st.hn, st.hv, st.C, st.ntheta[b], b, st.nversion[b])
    st.C[N_BLOCKED] = 0


@njit(cache=True)
def _release_blocked_near(st, pr, sc, f0, f1):
    """Put back on the heap the refused nodes within reach of the step's new faces f0..f1.

    See ``advancing_front`` (module docstring): a step whose triangles have no vertex within
    3 max_edge + (1 + merge_factor) S_max + longest_edge of a refused node's vertex leaves
    that node's verdict as it was.
    """
    P, faces, Fs, C, blocked, nalive, nvert = st.P, st.faces, st.Fs, st.C, st.blocked, st.nalive, st.nvert
    ntheta, nversion, ht, hn, hv, points = st.ntheta, st.nversion, st.ht, st.hn, st.hv, sc.points
    n_points = 3 * (f1 - f0)  # repeated vertices do not change which nodes are near
    for f in range(f0, f1):
        for j in range(3):
            x, y = faces[f, j], faces[f, (j + 1) % 3]
            d = math.sqrt((P[x, 0] - P[y, 0]) * (P[x, 0] - P[y, 0]) + (P[x, 1] - P[y, 1]) * (P[x, 1] - P[y, 1])
                          + (P[x, 2] - P[y, 2]) * (P[x, 2] - P[y, 2]))
            if d > Fs[0]:
                Fs[0] = d
            t = 3 * (f - f0) + j
            points[t, 0], points[t, 1], points[t, 2] = P[x, 0], P[x, 1], P[x, 2]
    reach = 3.0 * Fs[0] + (1.0 + pr.merge_factor) * pr.S_max + pr.longest_edge
    if C[RELEASED_NEAR] == 0:
        C[RELEASED_NEAR] = 1 + C[FAN_CLOSURES]  # key order of the stats: after a fan closure or before
    n = C[N_BLOCKED]
    if n == 0:
        return
    kept = 0
    for t in range(n):
        b = blocked[t]
        if not nalive[b]:
            continue
        v = nvert[b]
        if near_any(P[v, 0], P[v, 1], P[v, 2], points[:n_points], reach * reach, pr.two):
            heap_push(ht, hn, hv, C, ntheta[b], b, nversion[b])
        else:
            blocked[kept] = b
            kept += 1
    C[KEPT_BLOCKED] += kept
    C[N_BLOCKED] = kept


# --------------------------------------------------------------------------- the last resort (Step 6)
@njit(cache=True)
def _close_small_front(st):
    """Last resort when every step is rejected: close a front of at most 6 vertices by a fan.

    Fronts in order of size, then label; the first fan (from each vertex in turn) whose
    chords are no existing edge and whose triangles face the way of the reference normal at
    the fan's centre. See ``advancing_front._close_small_front`` (the reference).
    """
    C, fsize, P, N = st.C, st.fsize, st.P, st.N
    for size in range(3, 7):
        for label in range(C[NEXT_LABEL]):
            if fsize[label] != size:
                continue
            start = 0
            while not (st.nalive[start] and st.nfront[start] == label):
                start += 1
            cycle = np.empty(size, np.int64)
            cycle[0] = start
            for j in range(1, size):
                cycle[j] = st.nnext[cycle[j - 1]]
            ring = np.empty(size, np.int64)
            for shift in range(size):
                for j in range(size):
                    ring[j] = st.nvert[cycle[(shift + j) % size]]
                ok = True
                for j in range(2, size - 1):
                    if _has_edge(st.ekeys, ring[0], ring[j]):
                        ok = False
                for j in range(1, size - 1):
                    a, b, c = ring[0], ring[j], ring[j + 1]
                    e0, e1, e2 = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1], P[b, 2] - P[a, 2]
                    g0, g1, g2 = P[c, 0] - P[a, 0], P[c, 1] - P[a, 1], P[c, 2] - P[a, 2]
                    n0, n1, n2 = e1 * g2 - e2 * g1, e2 * g0 - e0 * g2, e0 * g1 - e1 * g0
                    if ok and n0 * N[a, 0] + n1 * N[a, 1] + n2 * N[a, 2] <= 0.0:
                        ok = False
                if not ok:
                    continue
                for j in range(1, size - 1):
                    f = C[N_FACES]
                    C[N_FACES] += 1
                    st.faces[f, 0], st.faces[f, 1], st.faces[f, 2] = ring[0], ring[j], ring[j + 1]
                    for i in range(3):
                        x, y = st.faces[f, i], st.faces[f, (i + 1) % 3]
                        _add_edge(st.ekeys, C, x, y)
                for j in range(size):
                    slot = _find(st.fkeys, ring[j], ring[(j + 1) % size])
                    if slot >= 0:
                        st.fkeys[slot] = DELETED
                for j in range(size):
                    _kill_node(st, cycle[j])
                fsize[label] = 0
                C[FAN_CLOSURES] += 1
                _release_blocked(st)
                return True
    return False


# --------------------------------------------------------------------------- the run
@njit(cache=True)
def initial_state(points, normals, S, forbidden, border_faces, OV, pr):
    """The state of Step 1: the boundary as the one front, its edges, the normals behind them, the angles.

    ``normals`` (k, 3) the reference normals, ``S`` (k,) the sizing values, ``forbidden``
    (p, 2) vertex pairs already joined, ``border_faces`` (b, 3) the faces of ``OV`` behind
    the boundary edges (their normals seed the fold test).
    """
    k = points.shape[0]
    cap_v, cap_n = 4 * k + 64, 4 * k + 64
    C = np.zeros(N_COUNTERS, np.int64)
    ekeys = _empty_table(k + forbidden.shape[0])
    fkeys = _empty_table(k)
    fvals = np.full((fkeys.shape[0], 3), np.nan)
    for i in range(k):
        j = (i + 1) % k
        _insert(ekeys, min(i, j), max(i, j), C, E_USED)
        _insert(fkeys, i, j, C, F_USED)
    for t in range(forbidden.shape[0]):
        a, b = forbidden[t, 0], forbidden[t, 1]
        _insert(ekeys, min(a, b), max(a, b), C, E_USED)
    for t in range(border_faces.shape[0]):
        f = border_faces[t]
        for j in range(3):
            a, b = f[j], f[(j + 1) % 3]
            slot = _find(fkeys, b, a)
            if slot >= 0 and a < k and b < k:
                fvals[slot, 0], fvals[slot, 1], fvals[slot, 2] = _face_unit_normal(OV, f[0], f[1], f[2])
    P = np.empty((cap_v, 3))
    _copy_rows(P, points)
    N = np.empty((cap_v, 3))
    _copy_rows(N, normals)
    Sv = np.empty(cap_v)
    for i in range(k):
        Sv[i] = S[i]
    vhead = np.full(cap_v, -1, np.int64)
    nvert = np.empty(cap_n, np.int64)
    nprev = np.empty(cap_n, np.int64)
    nnext = np.empty(cap_n, np.int64)
    for i in range(k):
        nprev[i], nnext[i] = (i - 1) % k, (i + 1) % k
    nfront = np.zeros(cap_n, np.int64)
    nalive = np.zeros(cap_n, np.bool_)
    alive = np.empty(cap_n, np.int64)
    for i in range(k):
        vhead[i], nvert[i], nalive[i], alive[i] = i, i, True, i
    fsize = np.zeros(16, np.int64)
    fsize[0] = k
    C[N_VERT], C[N_NODES], C[N_ALIVE], C[NEXT_LABEL] = k, k, k, 1
    st = FrontArrays(P, N, Sv, vhead, nvert, nprev, nnext, nfront, nalive, np.zeros(cap_n, np.int64),
                     np.zeros(cap_n), np.zeros((cap_n, 3)), np.full(cap_n, -1, np.int64), alive, alive.copy(),
                     np.empty((2 * k + 64, 3), np.int64), np.empty(8 * k + 64), np.empty(8 * k + 64, np.int64),
                     np.empty(8 * k + 64, np.int64), fsize, np.empty(k + 16, np.int64), ekeys, fkeys, fvals, C,
                     np.array([pr.longest_edge]))
    for i in range(k):
        _update_node(st, pr, i)
    return st


@njit(cache=True)
def run_front(st, pr, ob, sc):
    """Steps 2-6 until every front is closed (Sec. 3.2); (outcome, front vertices, final state).

    Outcomes: CLOSED; TOO_MANY_FACES (more than ``pr.max_faces`` triangles); GREW (the fronts
    hold more than ``pr.limit`` vertices: they left the hole); LEFT_BALL (a new vertex lies
    farther than sqrt(``pr.ball_r2``) from (``pr.ball_x``, ``pr.ball_y``, ``pr.ball_z``): the
    front left the hole; the count is that vertex's index); STUCK (no step possible and no small
    front to close by a fan). The front-vertex count is the one the outcome refers to.
    """
    C = st.C
    checked = C[N_VERT]  # vertices before this one are inside the ball
    while True:
        size, fronts = 0, 0
        for label in range(C[NEXT_LABEL]):
            if st.fsize[label] > 0:
                size += st.fsize[label]
                fronts += 1
        if fronts == 0:
            return CLOSED, 0, st
        while checked < C[N_VERT]:
            dx, dy, dz = st.P[checked, 0] - pr.ball_x, st.P[checked, 1] - pr.ball_y, st.P[checked, 2] - pr.ball_z
            if dx * dx + dy * dy + dz * dz > pr.ball_r2:
                return LEFT_BALL, checked, st
            checked += 1
        if C[N_FACES] > pr.max_faces:
            return TOO_MANY_FACES, size, st
        C[MAX_FRONT] = max(C[MAX_FRONT], size)
        if size > pr.limit:
            return GREW, size, st
        if not _has_room(st):
            st = _with_room(st)  # only then: returning the tuple takes a reference on each array
        node = _pop(st)
        if node < 0:
            if _close_small_front(st):
                continue
            return STUCK, size, st
        n_faces, n_topology = C[N_FACES], C[MERGES] + C[SPLITS]
        # The angle rule at the node or its first valid fallback, here rather than in a function
        # of its own: a call passing the three tuples costs a reference on each of their arrays.
        first, last = _rules(st, pr, node)
        applied = False
        for rule in range(first, last - 1, -1):
            ok, nf, n_seq = _build(st, pr, sc, node, rule)
            if ok and _valid(st, pr, sc, node, nf) and (
                    not ob.has or _clear_of_obstacles(st, pr, ob, sc, nf, pr.hover * st.S[st.nvert[node]])):
                _apply(st, pr, sc, node, rule, nf, n_seq)
                applied = True
                break
        if applied:
            C[STEPS] += 1
            if C[MERGES] + C[SPLITS] != n_topology:
                _release_blocked(st)  # a split relabels a whole front: any refusal may change
            else:
                _release_blocked_near(st, pr, sc, n_faces, C[N_FACES])
        else:
            C[REJECTED] += 1
            st.blocked[C[N_BLOCKED]] = node
            C[N_BLOCKED] += 1
