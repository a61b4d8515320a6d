"""Compiled incidence sets of the quality pass (numba): the faces at each vertex, in CPython's set order.

The numpy quality pass keeps the faces at each vertex in Python sets, and the order in
which a set yields them is that of the slots of CPython's hash table (an int hashes to
itself, so mostly ascending modulo the table size, but collisions, deleted entries and
resizes move faces about). That order reaches the results: it orders the triangles of a
vertex's star, whose cross products and energies are summed in it, and the faces of an
edge, whose normals make a collapse's vertex normal. These kernels keep each vertex's
faces in a table run the way CPython 3.11's ``setobject.c`` runs a set of non-negative
ints (linear probes of 9 slots then perturbed jumps, deleted slots left as dummies and
reused by an insertion that passes one, a resize to the smallest power of two above 4 x
used when 3 / 5 of the slots are taken, ``set(s)`` rebuilt as ``set_merge`` builds it), so
the same faces come out in the same order. tests/algorithms/xie_zou2013/test_incidence_kernels.py
checks the orders against Python sets under random insertions, removals and copies.

Layout: ``tab`` (n, 4) int64 holds each vertex's table as (start in ``pool``, mask, fill,
used); ``pool`` (p,) int64 the slots (``EMPTY``, ``DUMMY`` or a face), grown when a new
table does not fit (the kernels that may grow it return it); ``sizes[TOP]`` the pool's used
length.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["EMPTY", "DUMMY", "TOP", "new_incidence", "set_add", "set_discard", "set_items", "set_contains",
           "empty_set", "copied_sets"]

EMPTY, DUMMY = -1, -2
START, MASK, FILL, USED = 0, 1, 2, 3
TOP = 2  # sizes[TOP]: the pool's used length (sizes[0], sizes[1] are the patch's vertex and face counts)
_MIN_SIZE = 8  # PySet_MINSIZE
_LINEAR_PROBES = 9
_PERTURB_SHIFT = 5


@njit(cache=True)
def _allocate(pool, sizes, size):
    """(pool, start): ``size`` EMPTY slots at the pool's end, the pool grown if they do not fit."""
    top = sizes[TOP]
    if top + size > pool.shape[0]:
        grown = np.empty(max(2 * pool.shape[0], top + size), np.int64)
        for i in range(top):  # a loop: slice assignment costs compile time
            grown[i] = pool[i]
        pool = grown
    for i in range(top, top + size):
        pool[i] = EMPTY
    sizes[TOP] = top + size
    return pool, top


@njit(cache=True)
def _insert_clean(pool, start, mask, key):
    """setobject.c's set_insert_clean: key into the first EMPTY slot of its probe sequence."""
    perturb = key
    i = key & mask
    while True:
        if pool[start + i] == EMPTY:
            pool[start + i] = key
            return
        if i + _LINEAR_PROBES <= mask:
            for j in range(1, _LINEAR_PROBES + 1):
                if pool[start + i + j] == EMPTY:
                    pool[start + i + j] = key
                    return
        perturb >>= _PERTURB_SHIFT
        i = (i * 5 + 1 + perturb) & mask


@njit(cache=True)
def _resize(pool, tab, sizes, v, minused):
    """setobject.c's set_table_resize of vertex v's table to the smallest power of two above minused."""
    size = _MIN_SIZE
    while size <= minused:
        size <<= 1
    old, old_mask = tab[v, START], tab[v, MASK]
    if size == _MIN_SIZE and old_mask == _MIN_SIZE - 1 and tab[v, FILL] == tab[v, USED]:
        return pool  # the small table without dummies: left as it is
    pool, start = _allocate(pool, sizes, size)
    for e in range(old_mask + 1):  # in slot order, the dummies dropped
        key = pool[old + e]
        if key >= 0:
            _insert_clean(pool, start, size - 1, key)
    tab[v, START], tab[v, MASK], tab[v, FILL] = start, size - 1, tab[v, USED]
    return pool


@njit(cache=True)
def empty_set(pool, tab, sizes, v):
    """Vertex v's faces := set(): a new small table; returns the pool."""
    pool, start = _allocate(pool, sizes, _MIN_SIZE)
    tab[v, START], tab[v, MASK], tab[v, FILL], tab[v, USED] = start, _MIN_SIZE - 1, 0, 0
    return pool


@njit(cache=True)
def set_add(pool, tab, sizes, v, key):
    """setobject.c's set_add_entry: face ``key`` (>= 0) into vertex v's set; returns the pool.

    Probing stops at the first EMPTY slot; the key goes into the last dummy passed if any
    (without counting a new filled slot), else into that slot, which may resize the table.
    """
    start, mask = tab[v, START], tab[v, MASK]
    i = key & mask
    perturb = key
    freeslot = -1
    while True:
        probes = _LINEAR_PROBES if i + _LINEAR_PROBES <= mask else 0
        e = i
        while True:
            x = pool[start + e]
            if x == EMPTY:
                if freeslot >= 0:
                    pool[start + freeslot] = key
                    tab[v, USED] += 1
                    return pool
                pool[start + e] = key
                tab[v, FILL] += 1
                tab[v, USED] += 1
                if tab[v, FILL] * 5 < mask * 3:
                    return pool
                used = tab[v, USED]
                return _resize(pool, tab, sizes, v, used * 2 if used > 50000 else used * 4)
            if x == key:
                return pool
            if x == DUMMY:
                freeslot = e
            if probes == 0:
                break
            probes -= 1
            e += 1
        perturb >>= _PERTURB_SHIFT
        i = (i * 5 + 1 + perturb) & mask


@njit(cache=True)
def _lookup(pool, tab, v, key):
    """Slot (pool index) of ``key`` in vertex v's table, -1 if absent (setobject.c's set_lookkey)."""
    start, mask = tab[v, START], tab[v, MASK]
    i = key & mask
    perturb = key
    while True:
        probes = _LINEAR_PROBES if i + _LINEAR_PROBES <= mask else 0
        e = i
        while True:
            x = pool[start + e]
            if x == EMPTY:
                return -1
            if x == key:
                return start + e
            if probes == 0:
                break
            probes -= 1
            e += 1
        perturb >>= _PERTURB_SHIFT
        i = (i * 5 + 1 + perturb) & mask


@njit(cache=True)
def set_discard(pool, tab, v, key):
    """set.discard: the slot of ``key`` becomes a dummy (the table keeps its size and fill)."""
    slot = _lookup(pool, tab, v, key)
    if slot >= 0:
        pool[slot] = DUMMY
        tab[v, USED] -= 1


@njit(cache=True)
def set_contains(pool, tab, v, key):
    return _lookup(pool, tab, v, key) >= 0


@njit(cache=True)
def set_items(pool, tab, v, out):
    """Vertex v's faces into out[:count] in iteration order; returns count (out needs tab[v, USED] rows)."""
    start = tab[v, START]
    count = 0
    for e in range(tab[v, MASK] + 1):
        key = pool[start + e]
        if key >= 0:
            out[count] = key
            count += 1
    return count


@njit(cache=True)
def new_incidence(faces, start, n_vertices, n_capacity):
    """The sets ``set(faces[start[v]:start[v + 1]])`` of vertices 0 .. n_vertices - 1 (ints added in order).

    Returns
    -------
    tab : (n_capacity, 4) int64
    pool : (p,) int64
    sizes : (3,) int64  (n_vertices, 0, pool length used); the caller sets sizes[1]
    """
    tab = np.zeros((n_capacity, 4), np.int64)
    sizes = np.zeros(3, np.int64)
    sizes[0] = n_vertices
    pool = np.empty(max(64, 4 * _MIN_SIZE * n_capacity), np.int64)
    for v in range(n_vertices):
        pool = empty_set(pool, tab, sizes, v)
        for i in range(start[v], start[v + 1]):
            pool = set_add(pool, tab, sizes, v, faces[i])
    return tab, pool, sizes


@njit(cache=True)
def copied_sets(tab, pool, sizes):
    """``[set(s) for s in sets]`` of the first sizes[0] vertices: new (tab, pool, sizes), as set_merge builds a copy.

    A copy starts as a small table, resized first to the smallest power of two above 2 x used
    if 3 / 5 of it would be taken; a source of that size without dummies is copied slot by
    slot, any other has its faces inserted in slot order.
    """
    n = sizes[0]
    tab2 = np.zeros_like(tab)
    sizes2 = sizes.copy()
    sizes2[TOP] = 0
    pool2 = np.empty(max(64, sizes[TOP]), np.int64)
    for v in range(n):
        pool2 = empty_set(pool2, tab2, sizes2, v)
        used = tab[v, USED]
        if used == 0:
            continue
        if used * 5 >= (_MIN_SIZE - 1) * 3:
            pool2 = _resize(pool2, tab2, sizes2, v, used * 2)
        src, src_mask = tab[v, START], tab[v, MASK]
        dst, dst_mask = tab2[v, START], tab2[v, MASK]
        if dst_mask == src_mask and tab[v, FILL] == used:
            for e in range(src_mask + 1):
                pool2[dst + e] = pool[src + e]
        else:
            for e in range(src_mask + 1):
                key = pool[src + e]
                if key >= 0:
                    _insert_clean(pool2, dst, dst_mask, key)
        tab2[v, FILL] = used
        tab2[v, USED] = used
    return tab2, pool2, sizes2
