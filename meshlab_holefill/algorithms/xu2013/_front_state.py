"""The advancing front's state, compiled (numba): its arrays, pair tables, heap and nodes.

The storage that :mod:`._front_step` (one step) and :mod:`._front_loop` (the run) work on.
The state lives in arrays: per vertex its position ``P``, reference normal ``N``, sizing value
``S`` and the newest of its nodes ``vhead`` (older ones chained by ``nvnext``); per node its
vertex, neighbours, front label, alive flag, version, angle and angle plane; the list of alive
nodes; the faces; the heap of (angle, node, version) entries, stale ones skipped when popped;
per front label its size (0: closed). The edges made (``ekeys``) and the directed front edges
(``fkeys``, with the normal of the triangle behind in ``fvals``, NaN where unknown) are
open-addressing hash tables of vertex pairs (:func:`_find`, :func:`_insert`). Scalars sit in
the int array ``C`` (indices below) and ``max_edge`` in ``Fs[0]``.

The arrays grow between steps, by doubling (:func:`_has_room`, :func:`_with_room`), never
during one. The node helpers the step calls inside its loops take arrays, not the
:class:`FrontArrays` tuple (:func:`_kill` beside :func:`_kill_node`, :func:`_link`,
:func:`_node_on_front`): see :mod:`._front_step` on numba's reference counts.
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np
from numba import njit

# Indices into the counters C.
N_VERT, N_NODES, N_ALIVE, N_FACES, N_HEAP, N_BLOCKED, NEXT_LABEL = 0, 1, 2, 3, 4, 5, 6
STEPS, RULE1, RULE2, RULE3, MERGES, SPLITS, REJECTED, OBSTACLE_TESTS = 7, 8, 9, 10, 11, 12, 13, 14
MAX_FRONT, KEPT_BLOCKED, FAN_CLOSURES, RELEASED_NEAR = 15, 16, 17, 18
E_USED, F_USED = 19, 20  # slots used (live or deleted) in the edge tables
N_COUNTERS = 21

# Slots of the hash tables of vertex pairs: never used, deleted.
EMPTY, DELETED = -1, -2


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
    """Push (theta, node, version); the arrays must have room (see :func:`_with_room`)."""
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


# --------------------------------------------------------------------------- the state and its growth
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


# --------------------------------------------------------------------------- vertices and nodes
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
