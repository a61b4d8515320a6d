"""The advancing front's step loop, compiled (numba): Steps 2-6 of Xu et al. 2013, Sec. 3.2.

:func:`run_front` drives one run of :mod:`.advancing_front` from its initial state to the
closed patch: the heap of front angles (Step 2), the angle rules (Step 3), the merges
(Step 4), the checks of :mod:`._front_kernels` and the obstacles, the update of the fronts
(Step 5, cyclic linked lists of nodes in arrays, a vertex on two fronts after a split) and the
last-resort fan of a small front (Step 6). Every floating-point operation is that of the
Python reference (the bookkeeping it replaces, kept as the tests' oracle
``tests/algorithms/xu2013/xu2013_front_oracle.py``) in
the same order, squares of Python's ``x ** 2`` through ``pow`` (``two``), so both take the same
steps and give the same vertices bit for bit.

The state lives in arrays: per vertex its position ``P``, reference normal ``N``, sizing
value ``S`` and the newest of its nodes ``vhead`` (older ones chained by ``nvnext``); per node
its vertex, neighbours, front label, alive flag, version, angle and angle plane; the list of
alive nodes; the faces; the heap of (angle, node, version) entries, stale ones skipped when
popped; per front label its size (0: closed). The edges made (``ekeys``) and the directed
front edges (``fkeys``, with the normal of the triangle behind in ``fvals``, NaN where unknown)
are open-addressing hash tables of vertex pairs (:func:`_find`, :func:`_insert`). Scalars sit
in the int array ``C`` (indices below) and ``max_edge`` in ``Fs[0]``.

A compiled function that receives a tuple of arrays takes and drops a reference on each of
them (atomic operations) unless numba's reference-count pruning proves the pair redundant; with
26 arrays in the state that cost several times a step's arithmetic. The pruning fails once the
function frees an array of its own or takes one from a tuple (or a row view or a slice, which
branches) after a branch. So the step functions allocate nothing (their per-step arrays are the scratch arrays of
:func:`new_scratch`), take the arrays they use from the tuples first, read coordinates as
scalars, and the helpers they call in their loops take arrays, not the tuples.

Compiling the loop (once: ``cache=True`` keeps it on disk) takes about a minute of CPU on the
benchmark machine, against about 10 s for the per-step kernels alone; loading it from the
cache takes about 0.25 s per process (:func:`.advancing_front.warm_up`).
"""
from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from ._front_kernels import (merge_target, min_point_triangle_distance, near_any, obstacle_candidates,
                             step_geometry_valid, triangles_cross_faces)

# Indices into the counters C.
N_VERT, N_NODES, N_ALIVE, N_FACES, N_HEAP, N_BLOCKED, NEXT_LABEL = 0, 1, 2, 3, 4, 5, 6
STEPS, RULE1, RULE2, RULE3, MERGES, SPLITS, REJECTED, OBSTACLE_TESTS = 7, 8, 9, 10, 11, 12, 13, 14
MAX_FRONT, KEPT_BLOCKED, FAN_CLOSURES, RELEASED_NEAR = 15, 16, 17, 18
E_USED, F_USED = 19, 20  # slots used (live or deleted) in the edge tables
N_COUNTERS = 21
# Outcomes of run_front.
CLOSED, TOO_MANY_FACES, GREW, STUCK, LEFT_BALL = 0, 1, 2, 3, 4

# Slots of the hash tables of vertex pairs: never used, deleted.
EMPTY, DELETED = -1, -2


# --------------------------------------------------------------------------- small vector helpers
@njit(cache=True)
def _unit(a0, a1, a2):
    n = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    if n > 0.0:
        return a0 / n, a1 / n, a2 / n
    return a0, a1, a2


@njit(cache=True)
def _direction_angle(r0, r1, r2, d0, d1, d2, m0, m1, m2):
    c0, c1, c2 = r1 * d2 - r2 * d1, r2 * d0 - r0 * d2, r0 * d1 - r1 * d0
    t = math.atan2(m0 * c0 + m1 * c1 + m2 * c2,
                   (r0 * d0 + r1 * d1 + r2 * d2) - (r0 * m0 + r1 * m1 + r2 * m2) * (d0 * m0 + d1 * m1 + d2 * m2))
    return t + 2.0 * math.pi if t < 0.0 else t


@njit(cache=True)
def front_angle(P, N, v, p, q, min_sin, min_cos):
    """Front angle at vertex v between its neighbours p and q, and its plane's normal.

    The operations of ``_front_predicates.front_angle``, on the coordinates of P (n, 3) and the
    reference normal N[v] read as scalars (a row view takes and drops a reference on the array).
    """
    a0, a1, a2 = P[q, 0] - P[v, 0], P[q, 1] - P[v, 1], P[q, 2] - P[v, 2]
    b0, b1, b2 = P[p, 0] - P[v, 0], P[p, 1] - P[v, 1], P[p, 2] - P[v, 2]
    c0, c1, c2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    s = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    la = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    lb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
    r0, r1, r2 = N[v, 0], N[v, 1], N[v, 2]
    if la == 0.0 or lb == 0.0:
        return 0.0, r0, r1, r2
    cos_ref = c0 * r0 + c1 * r1 + c2 * r2
    if s > min_sin * la * lb and abs(cos_ref) >= min_cos * s:
        sign = 1.0 if cos_ref >= 0.0 else -1.0
        f = sign / s
        m0, m1, m2 = c0 * f, c1 * f, c2 * f
        theta = math.atan2(sign * s, a0 * b0 + a1 * b1 + a2 * b2)
    else:
        m0, m1, m2 = r0, r1, r2
        theta = _direction_angle(a0, a1, a2, b0, b1, b2, m0, m1, m2)
    if theta < 0.0:
        theta += 2.0 * math.pi
    return theta, m0, m1, m2


# --------------------------------------------------------------------------- heap of front angles
@njit(cache=True)
def _before(ht, hn, hv, i, j):
    """Heap entry i before entry j, as Python compares the tuples (theta, node, version)."""
    if ht[i] != ht[j]:
        return ht[i] < ht[j]
    if hn[i] != hn[j]:
        return hn[i] < hn[j]
    return hv[i] < hv[j]


@njit(cache=True)
def _swap(ht, hn, hv, i, j):
    ht[i], ht[j] = ht[j], ht[i]
    hn[i], hn[j] = hn[j], hn[i]
    hv[i], hv[j] = hv[j], hv[i]


@njit(cache=True)
def heap_push(ht, hn, hv, C, theta, node, version):
    """Push (theta, node, version); the arrays must have room (see :func:`_grow_state`)."""
    i = C[N_HEAP]
    C[N_HEAP] += 1
    ht[i], hn[i], hv[i] = theta, node, version
    while i > 0:
        parent = (i - 1) // 2
        if not _before(ht, hn, hv, i, parent):
            break
        _swap(ht, hn, hv, i, parent)
        i = parent


@njit(cache=True)
def heap_pop(ht, hn, hv, C):
    """Remove the smallest entry; its node and version."""
    node, version = hn[0], hv[0]
    n = C[N_HEAP] - 1
    C[N_HEAP] = n
    ht[0], hn[0], hv[0] = ht[n], hn[n], hv[n]
    i = 0
    while True:
        left, right, best = 2 * i + 1, 2 * i + 2, i
        if left < n and _before(ht, hn, hv, left, best):
            best = left
        if right < n and _before(ht, hn, hv, right, best):
            best = right
        if best == i:
            break
        _swap(ht, hn, hv, i, best)
        i = best
    return node, version




# --------------------------------------------------------------------------- hash tables of vertex pairs
@njit(cache=True)
def _slot(key, mask):
    """Home slot of a key (Fibonacci hashing)."""
    return np.int64((np.uint64(key) * np.uint64(11400714819323198485)) >> np.uint64(32)) & mask


@njit(cache=True)
def _find(keys, a, b):
    """Slot of the pair (a, b) in the table ``keys`` (linear probing), or -1; pairs with a negative id are never in it."""
    if a < 0 or b < 0:
        return -1
    key = (a << 32) | b
    mask = keys.shape[0] - 1
    i = _slot(key, mask)
    while keys[i] != EMPTY:
        if keys[i] == key:
            return i
        i = (i + 1) & mask
    return -1


@njit(cache=True)
def _insert(keys, a, b, C, used):
    """Slot of the pair (a, b) >= 0, added if absent (C[used] counts the slots taken); the table must have room."""
    key = (a << 32) | b
    mask = keys.shape[0] - 1
    i = _slot(key, mask)
    free = -1
    while keys[i] != EMPTY:
        if keys[i] == key:
            return i
        if keys[i] == DELETED and free < 0:
            free = i
        i = (i + 1) & mask
    if free < 0:
        free = i
        C[used] += 1
    keys[free] = key
    return free


@njit(cache=True)
def _rehashed(keys, vals, live_factor):
    """The table (keys, vals) rebuilt without deleted slots, with live_factor times its live pairs of room; its used count."""
    live = 0
    for i in range(keys.shape[0]):
        live += keys[i] >= 0
    cap = 64
    while cap < live_factor * (live + 64):
        cap *= 2
    new_keys = np.full(cap, EMPTY, np.int64)
    new_vals = np.empty((cap,) + vals.shape[1:], vals.dtype)
    mask = cap - 1
    for i in range(keys.shape[0]):
        if keys[i] >= 0:
            j = _slot(keys[i], mask)
            while new_keys[j] != EMPTY:
                j = (j + 1) & mask
            new_keys[j] = keys[i]
            for c in range(vals.shape[1]):  # a loop, not a row setitem (cheaper to compile)
                new_vals[j, c] = vals[i, c]
    return new_keys, new_vals, live


@njit(cache=True)
def _empty_table(n):
    cap = 64
    while cap < 4 * (n + 64):
        cap *= 2
    return np.full(cap, EMPTY, np.int64)


@njit(cache=True)
def _has_edge(ekeys, a, b):
    return _find(ekeys, min(a, b), max(a, b)) >= 0


@njit(cache=True)
def _add_edge(ekeys, C, a, b):
    _insert(ekeys, min(a, b), max(a, b), C, E_USED)


# --------------------------------------------------------------------------- the state
FrontArrays = namedtuple("FrontArrays", [
    "P", "N", "S", "vhead",  # per vertex
    "nvert", "nprev", "nnext", "nfront", "nalive", "nversion", "ntheta", "nplane", "nvnext",  # per node
    "alive", "alive_at",  # alive nodes (any order), node i at alive_at[i]
    "faces", "ht", "hn", "hv", "fsize", "blocked", "ekeys", "fkeys", "fvals", "C", "Fs"])
FrontParams = namedtuple("FrontParams", [
    "k", "merge_factor", "merge_ear_max", "S_max", "longest_edge", "cell", "max_faces", "limit", "min_sin",
    "min_cos", "one_max", "two_max", "fallback_one_max", "angle_margin", "fold_min_cos", "hover", "two",
    "ball_x", "ball_y", "ball_z", "ball_r2"])
# The surrounding mesh (FrontObstacles' arrays); ``has`` False: none.
FrontObstacleArrays = namedtuple("FrontObstacleArrays", [
    "has", "V", "F", "base", "dims", "keys", "starts", "cell_faces", "lo", "hi", "stamp", "out"])
# Per-step scratch: faces of a step (temporary ids -1, -2 for new vertices), their positions and
# presence, the front sequence replacing v, a position; the checks' directed edges (da, db), new
# edges and their nodes on the front, normals behind the faces' edges, query box (lo, hi) and
# corners; the update's vertex ids, node chain, nodes to update, face normals, release points.
Scratch = namedtuple("Scratch", ["faces", "new_pos", "has_new", "sequence", "pos", "da", "db", "new_edges",
                                 "edge_nodes", "behind", "lo", "hi", "corners", "ids", "chain", "dirty", "normals",
                                 "points"])


def new_scratch():
    """The per-step scratch arrays of :func:`run_front`, sized for a step of at most 3 faces."""
    return Scratch(np.zeros((3, 3), np.int64), np.zeros((2, 3)), np.zeros(2, np.bool_), np.zeros(2, np.int64),
                   np.zeros(3), np.zeros(9, np.int64), np.zeros(9, np.int64), np.zeros((9, 2), np.int64),
                   np.zeros((9, 2), np.int64), np.zeros((3, 3, 3)), np.zeros(3), np.zeros(3), np.zeros((3, 3, 3)),
                   np.zeros(2, np.int64), np.zeros(4, np.int64), np.zeros(12, np.int64), np.zeros((3, 3)),
                   np.zeros((9, 3)))


@njit(cache=True)
def _grown(a, n):
    """``a`` with room for index n (capacity doubled as needed), or ``a`` itself."""
    if n < a.shape[0]:
        return a
    size = a.shape[0]
    while size <= n:
        size *= 2
    b = np.empty((size,) + a.shape[1:], a.dtype)
    # Element loops over flat views, not a slice assignment: the broadcasting setitem costs
    # seconds of compile time per array type, a loop almost nothing.
    flat_a, flat_b = a.reshape(-1), b.reshape(-1)
    for i in range(flat_a.shape[0]):
        flat_b[i] = flat_a[i]
    return b


@njit(cache=True)
def _copy_rows(dst, src):
    """``dst[:len(src)] = src`` for (n, 3) arrays, as a loop (cheaper to compile than the slice setitem)."""
    for i in range(src.shape[0]):
        dst[i, 0], dst[i, 1], dst[i, 2] = src[i, 0], src[i, 1], src[i, 2]


@njit(cache=True)
def _has_room(st):
    """Has the state room for one more step: 2 vertices, 2 nodes, 4 faces, a split's label, the heap's
    pushes, 12 pairs in each hash table (kept at most half full)?"""
    C, n_vert, n_nodes, n_faces, n_heap = st.C, st.P.shape[0], st.nvert.shape[0], st.faces.shape[0], st.ht.shape[0]
    n_labels, n_blocked = st.fsize.shape[0], st.blocked.shape[0]
    n_ekeys, n_fkeys = st.ekeys.shape[0], st.fkeys.shape[0]
    return (C[N_VERT] + 2 < n_vert and C[N_NODES] + 2 < n_nodes and C[N_FACES] + 4 < n_faces
            and C[N_HEAP] + C[N_BLOCKED] + 32 < n_heap and C[NEXT_LABEL] + 2 < n_labels
            and C[N_BLOCKED] + 1 < n_blocked and 2 * (C[E_USED] + 16) < n_ekeys and 2 * (C[F_USED] + 16) < n_fkeys)


@njit(cache=True)
def _with_room(st):
    """The state grown to have room for one more step (see :func:`_has_room`)."""
    C = st.C
    nv, nn = C[N_VERT] + 2, C[N_NODES] + 2
    nh = C[N_HEAP] + C[N_BLOCKED] + 32
    fsize = _grown(st.fsize, C[NEXT_LABEL] + 2)
    for i in range(st.fsize.shape[0], fsize.shape[0]):
        fsize[i] = 0
    ekeys, fkeys, fvals = st.ekeys, st.fkeys, st.fvals
    if 2 * (C[E_USED] + 16) >= ekeys.shape[0]:
        ekeys, _, C[E_USED] = _rehashed(ekeys, np.empty((ekeys.shape[0], 0)), 4)
    if 2 * (C[F_USED] + 16) >= fkeys.shape[0]:
        fkeys, fvals, C[F_USED] = _rehashed(fkeys, fvals, 4)
    return FrontArrays(_grown(st.P, nv), _grown(st.N, nv), _grown(st.S, nv), _grown(st.vhead, nv),
                       _grown(st.nvert, nn), _grown(st.nprev, nn), _grown(st.nnext, nn), _grown(st.nfront, nn),
                       _grown(st.nalive, nn), _grown(st.nversion, nn), _grown(st.ntheta, nn), _grown(st.nplane, nn),
                       _grown(st.nvnext, nn), _grown(st.alive, nn), _grown(st.alive_at, nn),
                       _grown(st.faces, C[N_FACES] + 4), _grown(st.ht, nh), _grown(st.hn, nh), _grown(st.hv, nh),
                       fsize, _grown(st.blocked, C[N_BLOCKED] + 1), ekeys, fkeys, fvals, C, st.Fs)


@njit(cache=True)
def _add_vertex(st, x0, x1, x2, n0, n1, n2, size):
    i = st.C[N_VERT]
    st.C[N_VERT] += 1
    st.P[i, 0], st.P[i, 1], st.P[i, 2] = x0, x1, x2
    st.N[i, 0], st.N[i, 1], st.N[i, 2] = n0, n1, n2
    st.S[i] = size
    st.vhead[i] = -1
    return i


@njit(cache=True)
def _new_node(st, vertex, label):
    C = st.C
    i = C[N_NODES]
    C[N_NODES] += 1
    st.nvert[i], st.nprev[i], st.nnext[i], st.nfront[i] = vertex, -1, -1, label
    st.nalive[i], st.nversion[i], st.ntheta[i] = True, 0, 0.0
    st.nplane[i, 0], st.nplane[i, 1], st.nplane[i, 2] = 0.0, 0.0, 0.0
    st.alive[C[N_ALIVE]] = i
    st.alive_at[i] = C[N_ALIVE]
    C[N_ALIVE] += 1
    st.nvnext[i] = st.vhead[vertex]
    st.vhead[vertex] = i
    return i


@njit(cache=True)
def _kill_node(st, i):
    _kill(st.nalive, st.nversion, st.alive, st.alive_at, st.C, i)


@njit(cache=True)
def _kill(nalive, nversion, alive, alive_at, C, i):
    """:func:`_kill_node` on the arrays it changes."""
    if nalive[i]:
        nalive[i] = False
        # Swap-remove from the alive list.
        at, last = alive_at[i], alive[C[N_ALIVE] - 1]
        alive[at] = last
        alive_at[last] = at
        C[N_ALIVE] -= 1
    nversion[i] += 1


@njit(cache=True)
def _link(nprev, nnext, a, b):
    nnext[a] = b
    nprev[b] = a


@njit(cache=True)
def _node_on_front(vhead, nvnext, nalive, nfront, u, label, skip):
    """An alive node of vertex u on front ``label`` other than ``skip``, or -1.

    A vertex has at most one node on a front except for the moment between a merge and the
    split it causes (on the benchmark's holes never more than one candidate either way).
    """
    x = vhead[u]
    while x >= 0:
        if x != skip and nalive[x] and nfront[x] == label:
            return x
        x = nvnext[x]
    return -1


@njit(cache=True)
def _update_node(st, pr, i):
    """Front angle of node i (Sec. 3.2, Step 2), its version advanced and pushed on the heap."""
    P, N, nvert, nprev, nnext = st.P, st.N, st.nvert, st.nprev, st.nnext
    ntheta, nplane, nversion, ht, hn, hv, C = st.ntheta, st.nplane, st.nversion, st.ht, st.hn, st.hv, st.C
    theta, m0, m1, m2 = front_angle(P, N, nvert[i], nvert[nprev[i]], nvert[nnext[i]], pr.min_sin, pr.min_cos)
    ntheta[i] = theta
    nplane[i, 0], nplane[i, 1], nplane[i, 2] = m0, m1, m2
    nversion[i] += 1
    heap_push(ht, hn, hv, C, theta, i, nversion[i])


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


@njit(cache=True)
def _kill_run(st, x, count):
    """Kill ``count`` nodes of a front, from node x on along ``nnext`` (a cycle too short to keep)."""
    for _ in range(count):
        nx = st.nnext[x]
        _kill_node(st, x)
        x = nx


@njit(cache=True)
def _split(st, w, u):
    """Split the front through nodes w and u of one vertex into two cycles; drop cycles of <= 2 nodes.

    Returns the four nodes whose neighbours changed.
    """
    C, nnext, fsize = st.C, st.nnext, st.fsize
    C[SPLITS] += 1
    label = st.nfront[w]
    wn, un = nnext[w], nnext[u]
    _link(st.nprev, nnext, w, un)
    _link(st.nprev, nnext, u, wn)
    # Walk both cycles in lockstep: the shorter one is found in O(its length).
    a, b, la, lb = nnext[w], nnext[u], 1, 1
    while a != w and b != u:
        a, b, la, lb = nnext[a], nnext[b], la + 1, lb + 1
    if a == w:
        short, short_len, long_start = w, la, u
    else:
        short, short_len, long_start = u, lb, w
    long_len = fsize[label] - short_len
    if short_len <= 2:
        _kill_run(st, short, short_len)
    else:
        new_label = C[NEXT_LABEL]
        C[NEXT_LABEL] += 1
        x = short
        for _ in range(short_len):
            st.nfront[x] = new_label
            x = nnext[x]
        fsize[new_label] = short_len
    fsize[label] = long_len
    if long_len <= 2:
        _kill_run(st, long_start, long_len)
        fsize[label] = 0
    return w, u, wn, un


@njit(cache=True)
def _face_unit_normal(P, a, b, c):
    e0, e1, e2 = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1], P[b, 2] - P[a, 2]
    g0, g1, g2 = P[c, 0] - P[a, 0], P[c, 1] - P[a, 1], P[c, 2] - P[a, 2]
    return _unit(e1 * g2 - e2 * g1, e2 * g0 - e0 * g2, e0 * g1 - e1 * g0)


@njit(cache=True)
def _apply(st, pr, sc, node, rule, nf, n_seq):
    """Step 5: add the step's vertices and faces, update the front edges and the front (splits included)."""
    C, S, N = st.C, st.S, st.N
    label = st.nfront[node]
    v = st.nvert[node]
    prev, nxt = st.nprev[node], st.nnext[node]
    p, q = st.nvert[prev], st.nvert[nxt]
    ids = sc.ids
    ids[0], ids[1] = 0, 0
    n_ids = 0
    if sc.has_new[0] or sc.has_new[1]:
        size = (S[v] + S[p] + S[q]) / 3.0
        n0, n1, n2 = _unit(N[v, 0] + N[p, 0] + N[q, 0], N[v, 1] + N[p, 1] + N[q, 1], N[v, 2] + N[p, 2] + N[q, 2])
        for t in range(2):  # temporary ids -1, then -2
            if sc.has_new[t]:
                X = sc.new_pos[t]
                ids[t] = _add_vertex(st, X[0], X[1], X[2], n0, n1, n2, size)
                n_ids += 1
    f0 = C[N_FACES]
    for f in range(nf):
        for j in range(3):
            x = sc.faces[f, j]
            st.faces[f0 + f, j] = ids[-x - 1] if x < 0 else x
    C[N_FACES] += nf
    for t in range(n_seq):
        x = sc.sequence[t]
        sc.sequence[t] = ids[-x - 1] if x < 0 else x
    _update_front_edges(st, sc, f0, nf)
    C[RULE1 + rule - 1] += 1
    C[MERGES] += n_seq - n_ids
    # Linked-list surgery: p -> sequence -> q replaces p -> v -> q.
    _kill(st.nalive, st.nversion, st.alive, st.alive_at, C, node)
    chain = sc.chain  # n_seq + 2 nodes
    chain[0], chain[n_seq + 1] = prev, nxt
    for t in range(n_seq):
        chain[t + 1] = _new_node(st, sc.sequence[t], label)
    for t in range(n_seq + 1):
        _link(st.nprev, st.nnext, chain[t], chain[t + 1])
    st.fsize[label] += n_seq - 1
    if st.fsize[label] <= 2:
        # The last triangle of this front consumed all its edges.
        for x in (prev, nxt):
            if st.nalive[x]:
                _kill(st.nalive, st.nversion, st.alive, st.alive_at, C, x)
        st.fsize[label] = 0
        return
    dirty = sc.dirty  # up to n_seq + 2 + 4 n_seq nodes
    for t in range(n_seq + 2):
        dirty[t] = chain[t]
    n_dirty = n_seq + 2
    # A merged vertex is now twice on its front: split the front there.
    for t in range(1, n_seq + 1):
        w = chain[t]
        if not st.nalive[w]:
            continue
        other = _node_on_front(st.vhead, st.nvnext, st.nalive, st.nfront, st.nvert[w], st.nfront[w], w)
        if other >= 0:
            dirty[n_dirty], dirty[n_dirty + 1], dirty[n_dirty + 2], dirty[n_dirty + 3] = _split(st, w, other)
            n_dirty += 4
    for t in range(n_dirty):
        x = dirty[t]
        seen = False
        for j in range(t):
            seen = seen or dirty[j] == x
        if not seen and st.nalive[x]:
            _update_node(st, pr, x)


@njit(cache=True)
def _update_front_edges(st, sc, f0, nf):
    """Record the edges of faces f0..f0+nf; consume the front edges they cover, add the others reversed."""
    faces, P, ekeys, fkeys, fvals, C = st.faces, st.P, st.ekeys, st.fkeys, st.fvals, st.C
    da, db, normals = sc.da, sc.db, sc.normals
    for f in range(nf):
        a, b, c = faces[f0 + f, 0], faces[f0 + f, 1], faces[f0 + f, 2]
        normals[f, 0], normals[f, 1], normals[f, 2] = _face_unit_normal(P, a, b, c)
        for j in range(3):
            da[3 * f + j], db[3 * f + j] = faces[f0 + f, j], faces[f0 + f, (j + 1) % 3]
    for i in range(3 * nf):
        a, b = da[i], db[i]
        _add_edge(ekeys, C, a, b)
        slot = _find(fkeys, a, b)
        if slot >= 0:
            fkeys[slot] = DELETED
        else:
            reverse_in_step = False
            for j in range(3 * nf):
                if da[j] == b and db[j] == a:
                    reverse_in_step = True
            if not reverse_in_step:
                f = i // 3
                slot = _insert(fkeys, b, a, C, F_USED)
                fvals[slot, 0], fvals[slot, 1], fvals[slot, 2] = normals[f, 0], normals[f, 1], normals[f, 2]


@njit(cache=True)
def _build(st, pr, sc, node, rule):
    """Triangles of one rule at ``node`` (Sec. 3.2, Step 3, Fig. 3) with merged vertices (Step 4).

    Writes the faces to ``sc`` (new vertices as temporary ids -1, -2) and returns (ok, number
    of faces, length of the sequence replacing v on the front); not ok when a new vertex falls
    next to one of v's neighbours, a merge would make an ear of too wide an angle, or both new
    vertices merge with one vertex.
    """
    # The arrays taken from the tuples first, coordinates read as scalars: see the module docstring.
    P, S, nvert, nprev, nnext, nfront = st.P, st.S, st.nvert, st.nprev, st.nnext, st.nfront
    ntheta, nplane, alive, C = st.ntheta, st.nplane, st.alive, st.C
    F, has_new, new_pos, pos, sequence = sc.faces, sc.has_new, sc.new_pos, sc.pos, sc.sequence
    v = nvert[node]
    p = nvert[nprev[node]]
    q = nvert[nnext[node]]
    has_new[0], has_new[1] = False, False
    if rule == 1:
        F[0, 0], F[0, 1], F[0, 2] = p, v, q
        return True, 1, 0
    theta, m0, m1, m2 = ntheta[node], nplane[node, 0], nplane[node, 1], nplane[node, 2]
    V0, V1, V2 = P[v, 0], P[v, 1], P[v, 2]
    length = (S[v] + S[p] + S[q]) / 3.0
    a0, a1, a2 = P[q, 0] - V0, P[q, 1] - V1, P[q, 2] - V2
    am = a0 * m0 + a1 * m1 + a2 * m2
    u0, u1, u2 = _unit(a0 - m0 * am, a1 - m1 * am, a2 - m2 * am)
    t0, t1, t2 = m1 * u2 - m2 * u1, m2 * u0 - m0 * u2, m0 * u1 - m1 * u0
    count = rule - 1
    radius = pr.merge_factor * length
    id1, id2 = 0, 0  # the vertices of the new positions j = 1, 2 (temporary ids -1, -2 if new)
    two = pr.two
    for j in range(1, count + 1):
        phi = theta * j / (count + 1)
        c, s = math.cos(phi) * length, math.sin(phi) * length
        pos[0], pos[1], pos[2] = V0 + c * u0 + s * t0, V1 + c * u1 + s * t1, V2 + c * u2 + s * t2
        for u in (p, q):
            if (pos[0] - P[u, 0]) ** two + (pos[1] - P[u, 1]) ** two + (pos[2] - P[u, 2]) ** two < radius * radius:
                return False, 0, 0
        target = merge_target(pos, radius, v, p, q, nfront[node], P, nvert, nfront, alive, C[N_ALIVE], pr.cell, two)
        if target < 0:
            target = -j
            new_pos[j - 1, 0], new_pos[j - 1, 1], new_pos[j - 1, 2] = pos[0], pos[1], pos[2]
            has_new[j - 1] = True
        if j == 1:
            id1 = target
        else:
            id2 = target
    # A merge with the vertex beyond p (or q) makes the triangle at p (or q) an ear that
    # closes p's whole front angle: allowed only where a single triangle fits the angle.
    prev2 = nvert[nprev[nprev[node]]]
    next2 = nvert[nnext[nnext[node]]]
    if (id1 if count == 1 else id2) == prev2 and ntheta[nprev[node]] > pr.merge_ear_max:
        return False, 0, 0
    if id1 == next2 and ntheta[nnext[node]] > pr.merge_ear_max:
        return False, 0, 0
    if rule == 2:
        w = id1
        F[0, 0], F[0, 1], F[0, 2] = v, q, w
        F[1, 0], F[1, 1], F[1, 2] = p, v, w
        sequence[0] = w
        return True, 2, 1
    w1, w2 = id1, id2
    if w1 == w2:
        return False, 0, 0
    F[0, 0], F[0, 1], F[0, 2] = v, q, w1
    F[1, 0], F[1, 1], F[1, 2] = v, w1, w2
    F[2, 0], F[2, 1], F[2, 2] = p, v, w2
    sequence[0], sequence[1] = w2, w1
    return True, 3, 2


@njit(cache=True)
def _valid(st, pr, sc, node, nf):
    """Topological and geometric checks of one step (``advancing_front``, module docstring), in order.

    No directed edge twice; an existing edge only as a front edge it consumes; each existing
    end of a new edge on this front; then :func:`._front_kernels.step_geometry_valid`. (With
    obstacles :func:`_clear_of_obstacles` follows.)
    """
    nfront, vhead, nvnext, nalive = st.nfront, st.vhead, st.nvnext, st.nalive
    ekeys, fkeys, fvals = st.ekeys, st.fkeys, st.fvals
    faces, da, db, new_edges, edge_nodes, behind = sc.faces, sc.da, sc.db, sc.new_edges, sc.edge_nodes, sc.behind
    label = nfront[node]
    nd = 3 * nf
    for f in range(nf):
        for j in range(3):
            da[3 * f + j], db[3 * f + j] = faces[f, j], faces[f, (j + 1) % 3]
    for i in range(nd):
        for j in range(i):
            if da[i] == da[j] and db[i] == db[j]:
                return False
    ne = 0
    for i in range(nd):
        a, b = da[i], db[i]
        if _find(fkeys, a, b) >= 0:
            continue
        if a >= 0 and b >= 0 and _has_edge(ekeys, a, b):
            return False
        if a > b:
            reverse_in_step = False
            for j in range(nd):
                if da[j] == b and db[j] == a:
                    reverse_in_step = True
            if reverse_in_step:
                continue  # interior edge of the step, kept once
        new_edges[ne, 0], new_edges[ne, 1] = a, b
        ne += 1
    # The node of each existing end of a new edge, on this front (a new edge must leave from
    # inside its front angle there).
    for i in range(ne):
        for j in range(2):
            x = new_edges[i, j]
            edge_nodes[i, j] = -1
            if x >= 0:
                edge_nodes[i, j] = _node_on_front(vhead, nvnext, nalive, nfront, x, label, -1)
                if edge_nodes[i, j] < 0:
                    return False
    for f in range(nf):
        for j in range(3):
            slot = _find(fkeys, faces[f, j], faces[f, (j + 1) % 3])
            for i in range(3):
                behind[f, j, i] = fvals[slot, i] if slot >= 0 else np.nan
    v = st.nvert[node]
    scale = st.S[v]
    return step_geometry_valid(faces, nf, sc.new_pos, behind, st.nplane[node], 1e-10 * scale * scale, pr.fold_min_cos,
                               new_edges, edge_nodes, ne, pr.angle_margin, st.P[v], pr.longest_edge, st.P, st.nvert,
                               st.nnext, st.nplane, st.ntheta, st.alive, st.C[N_ALIVE], pr.cell, pr.two)


@njit(cache=True)
def _clear_of_obstacles(st, pr, ob, sc, nf, clearance):
    """New vertices at least ``clearance`` from the surrounding mesh, new triangles crossing none of its faces.

    The last check of a step (after :func:`_valid`); ``clearance`` is ``hover`` times the sizing value at the node.

    :meth:`._front_obstacles.FrontObstacles.distance` and ``crossed`` on its arrays.
    """
    P, C = st.P, st.C
    new_pos, faces, has_new, lo, hi, T = sc.new_pos, sc.faces, sc.has_new, sc.lo, sc.hi, sc.corners
    V, F, base, dims, keys, starts, cell_faces = ob.V, ob.F, ob.base, ob.dims, ob.keys, ob.starts, ob.cell_faces
    face_lo, face_hi, stamp, out = ob.lo, ob.hi, ob.stamp, ob.out
    for t in range(2):
        if not has_new[t]:
            continue
        X = new_pos[t]
        for i in range(3):
            lo[i], hi[i] = X[i] - clearance, X[i] + clearance
        count = obstacle_candidates(lo, hi, pr.cell, base, dims, keys, starts, cell_faces, face_lo, face_hi, stamp,
                                    out)
        if count and min_point_triangle_distance(X, V, F, out[:count], clearance) < clearance:
            return False
    for f in range(nf):
        for j in range(3):
            x = faces[f, j]
            for i in range(3):
                T[f, j, i] = new_pos[-x - 1, i] if x < 0 else P[x, i]
    for i in range(3):
        lo[i], hi[i] = T[0, 0, i], T[0, 0, i]
        for f in range(nf):
            for j in range(3):
                lo[i], hi[i] = min(lo[i], T[f, j, i]), max(hi[i], T[f, j, i])
    count = obstacle_candidates(lo, hi, pr.cell, base, dims, keys, starts, cell_faces, face_lo, face_hi, stamp, out)
    if count == 0:
        return True
    C[OBSTACLE_TESTS] += 1
    return not triangles_cross_faces(faces[:nf], T[:nf], V, F, out, count, pr.k, 1e-9 * pr.cell)


@njit(cache=True)
def _rules(st, pr, node):
    """The angle rule at ``node`` (Sec. 3.2, Step 3) and the last fallback to try: (first, last), tried downwards."""
    theta, size = st.ntheta[node], st.fsize[st.nfront[node]]
    if size == 3 or theta <= pr.one_max:
        return 1, 1
    if theta <= pr.two_max:
        return 2, 1
    if theta <= pr.fallback_one_max:
        return 3, 1
    return 3, 2


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
