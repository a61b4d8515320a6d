"""Compiled operations of the quality pass (numba): swaps, moves, collapses and splits of the poor faces.

:func:`improve_round` is ``_improve_round`` of the numpy quality pass
(:mod:`._quality_pass_numpy`) and :func:`improve_face` its ``_improve_face``, on flat arrays:
the patch's vertices V (capacity, 3), faces F (capacity, 3) and their ``alive`` marks, with
``sizes`` (vertex count, face count, pool length) and the faces at each vertex in the
tables of :mod:`._incidence_kernels`, which yield them in the order of the numpy pass's
Python sets. Every operation reads and writes what the numpy one does, in the same order,
with the geometry of :mod:`._quality_pass_kernels`, so the patch comes out the same bits.

The pass's constants travel in one tuple (:func:`._patch_kernels.context`). The functions that
may add to a vertex's faces return the pool, which a table's growth may replace.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._incidence_kernels import empty_set, set_add, set_discard
from ._patch_kernels import (_blocked, _copy_row, _corner_of, _corners, _edge_faces, _face_normal, _face_quality,
                             _faces_of, _forbidden, _has_edge, _link_condition, _loop_edge, _other, _pymax,
                             _replace_face, _sorted_unique, _vertex_normal)
from ._quality_pass_kernels import _triangle_terms, compass_search, gemv_row, min_of, pairwise_mean, valid
from ...geometry._vector_kernels import cross3, norm3, npmax, npmin, sub3

__all__ = ["improve_round", "improve_face", "SWAPS", "MOVES", "COLLAPSES", "SPLITS", "NOTHING"]

SWAPS, MOVES, COLLAPSES, SPLITS, NOTHING = 0, 1, 2, 3, -1


@njit(cache=True, error_model="numpy")
def try_swap(V, F, tab, pool, sizes, a, b, ctx):
    """_Patch.try_swap of edge (a, b): (pool, swapped)."""
    k, gain = ctx[0], ctx[2]
    if _loop_edge(a, b, k):
        return pool, False
    fs = _edge_faces(pool, tab, F, a, b)
    if fs.shape[0] != 2:
        return pool, False
    f1, f2 = fs[0], fs[1]
    i = 0 if F[f1, 0] == a else (1 if F[f1, 1] == a else 2)
    if F[f1, (i + 1) % 3] != b:  # orient: f1 holds a -> b
        f1, f2 = f2, f1
        i = 0 if F[f1, 0] == a else (1 if F[f1, 1] == a else 2)
    c = F[f1, (i + 2) % 3]
    d = _other(F, f2, a, b)
    if c == d or _has_edge(pool, tab, F, c, d) or _forbidden(ctx, c, d):
        return pool, False
    if ctx[8].shape[0] and (_blocked(ctx, a, c, d) or _blocked(ctx, b, c, d)):
        return pool, False
    q_old = npmin(_face_quality(V, F, f1), _face_quality(V, F, f2))
    T = np.empty((2, 3), np.int64)
    T[0, 0], T[0, 1], T[0, 2], T[1, 0], T[1, 1], T[1, 2] = a, d, c, b, c, d
    n1 = _face_normal(V, F[f1, 0], F[f1, 1], F[f1, 2], True)
    n2 = _face_normal(V, F[f2, 0], F[f2, 1], F[f2, 2], True)
    r = ((0.0 + n1[0]) + n2[0], (0.0 + n1[1]) + n2[1], (0.0 + n1[2]) + n2[2])
    m = _pymax(norm3(r), 1e-300)
    ref = np.empty((2, 3))
    for j in range(2):
        ref[j, 0], ref[j, 1], ref[j, 2] = r[0] / m, r[1] / m, r[2] / m
    q = np.empty(2)
    if not valid(T, _corners(T, V, V[0], -1), ref, ctx, q) or min_of(q, 2) <= q_old + gain:
        return pool, False
    pool = _replace_face(pool, tab, sizes, F, f1, a, d, c)
    pool = _replace_face(pool, tab, sizes, F, f2, b, c, d)
    return pool, True


@njit(cache=True, error_model="numpy")
def try_move(V, F, tab, pool, v, energy_objective, ctx):
    """_Patch.try_move of vertex v: moved (V[v] updated)."""
    floor, gain = ctx[1], ctx[2]
    faces = _faces_of(pool, tab, v)
    s = faces.shape[0]
    T = np.empty((s, 3), np.int64)
    for i in range(s):
        _copy_row(T, i, F, faces[i])
    P = _corners(T, V, V[0], -1)
    q0 = np.empty(s)
    ref = np.empty((s, 3))
    cr = np.empty(3)
    nv0, nv1, nv2 = 0.0, 0.0, 0.0
    for i in range(s):
        q0[i] = _triangle_terms(P[i, 0], P[i, 1], P[i, 2], cr)
        m = npmax(norm3(cr), 1e-300)
        ref[i, 0], ref[i, 1], ref[i, 2] = cr[0] / m, cr[1] / m, cr[2] / m
        nv0, nv1, nv2 = nv0 + cr[0], nv1 + cr[1], nv2 + cr[2]
    current = min_of(q0, s)
    m = _pymax(norm3((nv0, nv1, nv2)), 1e-300)
    nv = np.empty(3)
    nv[0], nv[1], nv[2] = nv0 / m, nv1 / m, nv2 / m
    corner = _corner_of(T, v)
    others = np.empty(3 * s, np.int64)
    count = 0
    for i in range(s):
        for c in range(3):
            if T[i, c] != v:
                others[count] = T[i, c]
                count += 1
    link = _sorted_unique(others, count)
    L = link.shape[0]
    dist = np.empty(L)
    for j in range(L):
        dist[j] = norm3(sub3(V[link[j]], V[v]))
    h = 0.25 * pairwise_mean(dist, L)
    x0 = V[v].copy()
    x, val1, qmin = compass_search(T, P, corner, ref, nv, x0, h, energy_objective, current, ctx)
    if qmin < floor:
        # Also from the link centroid, in the tangent plane.
        g = np.zeros(3)
        for j in range(L):
            for d in range(3):
                g[d] += V[link[j], d]
        for d in range(3):
            g[d] = g[d] / L - x0[d]
        t = ((0.0 + g[0] * nv[0]) + g[1] * nv[1]) + g[2] * nv[2]
        for d in range(3):
            g[d] = x0[d] + (g[d] - t * nv[d])
        x2, val2, qmin2 = compass_search(T, P, corner, ref, nv, g, h, energy_objective, current, ctx)
        if np.isfinite(val2) and val2 < val1:
            x, qmin = x2, qmin2
    if qmin <= current + gain:
        return False
    for d in range(3):
        V[v, d] = x[d]
    return True


@njit(cache=True, error_model="numpy")
def try_collapse(V, F, alive, tab, pool, sizes, x, y, ctx):
    """_Patch.try_collapse of edge (x, y), x free, y kept: (pool, collapsed)."""
    k, gain, turn_cos = ctx[0], ctx[2], ctx[3]
    if x < k:
        return pool, False
    fs = _edge_faces(pool, tab, F, x, y)
    if fs.shape[0] != 2 or not _link_condition(pool, tab, F, x, y, fs, ctx):
        return pool, False
    fx, fy = _faces_of(pool, tab, x), _faces_of(pool, tab, y)
    region = np.empty(fx.shape[0] + fy.shape[0], np.int64)
    s = 0
    for faces in (fx, fy):
        for f in faces:
            if f != fs[0] and f != fs[1]:
                region[s] = f
                s += 1
    region = _sorted_unique(region, s)
    s = region.shape[0]
    old = np.empty((s + 2, 3), np.int64)
    for i in range(s):
        _copy_row(old, i, F, region[i])
    _copy_row(old, s, F, fs[0])
    _copy_row(old, s + 1, F, fs[1])
    q_old = np.inf
    for i in range(s + 2):
        q_old = npmin(q_old, _face_quality(V, old, i))
    T = old[:s].copy()
    ref = np.empty((s, 3))
    for i in range(s):
        n = _face_normal(V, T[i, 0], T[i, 1], T[i, 2], True)
        ref[i, 0], ref[i, 1], ref[i, 2] = n[0], n[1], n[2]
        for c in range(3):
            if T[i, c] == x:
                T[i, c] = y
    ref_v = _vertex_normal(V, old, y)
    if not (ref_v[0] != 0 or ref_v[1] != 0 or ref_v[2] != 0):
        return pool, False
    corner = _corner_of(T, y)
    starts = np.empty((3, 3))
    count = 1
    if y < k:
        _copy_row(starts, 0, V, y)
    else:
        for d in range(3):
            starts[0, d] = 0.5 * (V[x, d] + V[y, d])
        _copy_row(starts, 1, V, y)
        _copy_row(starts, 2, V, x)
        count = 3
    best = np.empty(3)
    found = False
    best_q = q_old + gain
    q = np.empty(s)
    for j in range(count):
        p = starts[j].copy()
        W = _corners(T, V, p, y)
        if not valid(T, W, ref, ctx, q):
            continue
        turned = False
        for i in range(s):
            cr = cross3(sub3(W[i, 1], W[i, 0]), sub3(W[i, 2], W[i, 0]))
            if gemv_row(cr, ref_v, s) <= turn_cos * norm3(cr):
                turned = True
        if turned:
            continue
        qmin = min_of(q, s)
        if y >= k:
            h = 0.25 * norm3(sub3(V[x], V[y]))
            p, _, qmin = compass_search(T, W, corner, ref, ref_v, p, h, False, qmin, ctx)
        if qmin > best_q:
            for d in range(3):
                best[d] = p[d]
            best_q = qmin
            found = True
    if not found:
        return pool, False
    for d in range(3):
        V[y, d] = best[d]
    for f in fs:
        alive[f] = False
        for c in range(3):
            set_discard(pool, tab, F[f, c], f)
    for f in _faces_of(pool, tab, x):
        for c in range(3):
            if F[f, c] == x:
                F[f, c] = y
        pool = set_add(pool, tab, sizes, y, f)
    pool = empty_set(pool, tab, sizes, x)
    return pool, True


@njit(cache=True, error_model="numpy")
def try_split(V, F, alive, tab, pool, sizes, f, ctx):
    """_Patch.try_split of face f's longest edge at a new vertex: (pool, split)."""
    k, gain = ctx[0], ctx[2]
    L = np.empty(3)
    for i in range(3):
        L[i] = norm3(sub3(V[F[f, (i + 1) % 3]], V[F[f, i]]))
    i = 0  # np.argmax: the first NaN, else the first largest
    for j in range(3):
        if L[j] != L[j]:
            i = j
            break
        if L[j] > L[i]:
            i = j
    a, b, c = F[f, i], F[f, (i + 1) % 3], F[f, (i + 2) % 3]
    if _loop_edge(a, b, k):
        return pool, False
    fs = _edge_faces(pool, tab, F, a, b)
    if fs.shape[0] != 2:
        return pool, False
    g = fs[1] if fs[0] == f else fs[0]
    d = _other(F, g, a, b)
    if c == d:
        return pool, False
    w = sizes[0]
    T = np.empty((4, 3), np.int64)
    T[0, 0], T[0, 1], T[0, 2], T[1, 0], T[1, 1], T[1, 2] = a, w, c, w, b, c
    T[2, 0], T[2, 1], T[2, 2], T[3, 0], T[3, 1], T[3, 2] = b, w, d, w, a, d
    nf = _face_normal(V, F[f, 0], F[f, 1], F[f, 2], True)
    ng = _face_normal(V, F[g, 0], F[g, 1], F[g, 2], True)
    if not (nf[0] != 0 or nf[1] != 0 or nf[2] != 0) or not (ng[0] != 0 or ng[1] != 0 or ng[2] != 0):
        return pool, False
    ref = np.empty((4, 3))
    for d_ in range(3):
        ref[0, d_], ref[1, d_], ref[2, d_], ref[3, d_] = nf[d_], nf[d_], ng[d_], ng[d_]
    nv = np.empty(3)
    for d_ in range(3):
        nv[d_] = (((0.0 + nf[d_]) + nf[d_]) + ng[d_]) + ng[d_]
    m = _pymax(norm3(nv), 1e-300)
    for d_ in range(3):
        nv[d_] = nv[d_] / m
    q_old = npmin(_face_quality(V, F, f), _face_quality(V, F, g))
    x0 = np.empty(3)
    for d_ in range(3):
        x0[d_] = 0.5 * (V[a, d_] + V[b, d_])
    W = _corners(T, V, x0, w)
    q = np.empty(4)
    ok = valid(T, W, ref, ctx, q)
    floor_min = _pymax(min_of(q, 4), 0.0) if ok else q_old
    corner = _corner_of(T, w)
    x, val, qmin = compass_search(T, W, corner, ref, nv, x0, 0.25 * L[i], False, floor_min, ctx)
    if not np.isfinite(val) or qmin <= q_old + gain:
        return pool, False
    if not valid(T, _corners(T, V, x, w), ref, ctx, q):
        return pool, False
    for d_ in range(3):
        V[w, d_] = x[d_]
    sizes[0] = w + 1
    pool = empty_set(pool, tab, sizes, w)
    for v in (a, b, c, d):
        set_discard(pool, tab, v, f)
        set_discard(pool, tab, v, g)
    n = sizes[1]
    _copy_row(F, f, T, 0)
    _copy_row(F, g, T, 2)
    _copy_row(F, n, T, 1)
    _copy_row(F, n + 1, T, 3)
    alive[n], alive[n + 1] = True, True
    sizes[1] = n + 2
    for face, row in ((f, 0), (g, 2), (n, 1), (n + 1, 3)):
        for j in range(3):
            pool = set_add(pool, tab, sizes, T[row, j], face)
    return pool, True


@njit(cache=True)
def improve_face(V, F, alive, tab, pool, sizes, f, split, ctx):
    """_improve_face: the first operation that helps poor face f; (pool, SWAPS, MOVES, COLLAPSES, SPLITS or NOTHING)."""
    k, floor = ctx[0], ctx[1]
    tri = F[f].copy()
    if _face_quality(V, F, f) >= floor:
        return pool, NOTHING
    for i in range(3):
        pool, done = try_swap(V, F, tab, pool, sizes, tri[i], tri[(i + 1) % 3], ctx)
        if done:
            return pool, SWAPS
    moved = False
    for energy_objective in (True, False):
        for v in tri:
            if v >= k and try_move(V, F, tab, pool, v, energy_objective, ctx):
                moved = True
        if moved and _face_quality(V, F, f) >= floor:
            break
    if moved:
        return pool, MOVES
    for first in (True, False):  # the edges with a free start, then those with a free end reversed
        for i in range(3):
            a, b = tri[i], tri[(i + 1) % 3]
            if not first:
                a, b = b, a
            if a >= k:
                pool, done = try_collapse(V, F, alive, tab, pool, sizes, a, b, ctx)
                if done:
                    return pool, COLLAPSES
    if split:
        pool, done = try_split(V, F, alive, tab, pool, sizes, f, ctx)
        if done:
            return pool, SPLITS
    return pool, NOTHING


@njit(cache=True)
def improve_round(V, F, alive, tab, pool, sizes, order, split, ctx):
    """_improve_round without ``keeps``: the poor faces ``order`` (worst first) in turn.

    Returns
    -------
    pool : (p,) int64
    counts : (4,) int64  swaps, moves, collapses, splits kept
    """
    counts = np.zeros(4, np.int64)
    for f in order:
        if not alive[f]:
            continue
        pool, kind = improve_face(V, F, alive, tab, pool, sizes, f, split, ctx)
        if kind != NOTHING:
            counts[kind] += 1
    return pool, counts
