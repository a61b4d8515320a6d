"""Compiled walk of :func:`._boundary_loops.boundary_loops` over the boundary half-edges (numba)."""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["walk_loops"]


@njit(cache=True)
def _take_outgoing(v, order, used, next_free, end):
    """The first unused half-edge leaving ``v`` (in ``order``), -1 when there is none; skips the used ones for good."""
    s = next_free[v]
    if s < 0:
        return -1
    while s < end[v] and used[order[s]]:
        s += 1
    next_free[v] = s
    return order[s] if s < end[v] else -1


@njit(cache=True)
def walk_loops(order, src, dst, n):
    """Split boundary half-edges ``src[e] -> dst[e]`` into simple loops, as :func:`boundary_loops_python` does.

    ``order`` sorts the half-edges by ``src`` (stably). Each walk starts from the first unused
    half-edge in that order, takes at every vertex its first unused outgoing half-edge, and cuts
    a loop off as soon as it returns to a vertex on its path; a walk that reaches a vertex with no
    unused outgoing half-edge ends in an open chain.

    Returns
    -------
    vertices : (V,) int64  the loops' vertices, loop after loop
    edges : (E,) int64  the loops' half-edges (indices into src, dst), loop after loop
    vertex_offsets, edge_offsets : (L + 1,) int64
    closed, pinched : (L,) bool  (pinched: a vertex of the loop has several outgoing half-edges; every open chain)
    """
    b = len(order)
    next_free = np.full(n, -1, np.int64)
    end = np.zeros(n, np.int64)
    for s in range(b):
        v = src[order[s]]
        if next_free[v] < 0:
            next_free[v] = s
        end[v] = s + 1
    several = np.zeros(n, np.bool_)
    for v in range(n):
        several[v] = next_free[v] >= 0 and end[v] - next_free[v] > 1
    used = np.zeros(b, np.bool_)
    position = np.full(n, -1, np.int64)
    path_v = np.empty(b + 1, np.int64)
    path_e = np.empty(b, np.int64)
    vertices = np.empty(2 * b + 1, np.int64)
    edges = np.empty(b, np.int64)
    vertex_offsets = np.zeros(b + 1, np.int64)
    edge_offsets = np.zeros(b + 1, np.int64)
    closed = np.zeros(b, np.bool_)
    pinched = np.zeros(b, np.bool_)
    loops = 0
    for s0 in range(b):
        e = order[s0]
        if used[e]:
            continue
        path_v[0] = src[e]
        pv, pe = 1, 0
        position[src[e]] = 0
        while True:
            used[e] = True
            path_e[pe] = e
            pe += 1
            v = dst[e]
            if position[v] >= 0:
                cut = position[v]
                loops = _emit(path_v, cut, pv, path_e, cut, pe, True, several, vertices, edges, vertex_offsets,
                              edge_offsets, closed, pinched, loops)
                for i in range(cut + 1, pv):
                    position[path_v[i]] = -1
                pv, pe = cut + 1, cut
                if pe == 0:
                    e = _take_outgoing(v, order, used, next_free, end)
                    if e < 0:
                        break
                    continue
            else:
                position[v] = pv
                path_v[pv] = v
                pv += 1
            e = _take_outgoing(v, order, used, next_free, end)
            if e < 0:  # a dead end: only where neighbouring faces disagree on orientation
                loops = _emit(path_v, 0, pv, path_e, 0, pe, False, several, vertices, edges, vertex_offsets,
                              edge_offsets, closed, pinched, loops)
                break
        for i in range(pv):
            position[path_v[i]] = -1
    return (vertices[:vertex_offsets[loops]].copy(), edges[:edge_offsets[loops]].copy(),
            vertex_offsets[:loops + 1].copy(), edge_offsets[:loops + 1].copy(), closed[:loops].copy(),
            pinched[:loops].copy())


@njit(cache=True)
def _emit(path_v, v0, v1, path_e, e0, e1, is_closed, several, vertices, edges, vertex_offsets, edge_offsets,
          closed, pinched, loops):
    """Append the loop ``path_v[v0:v1]``, ``path_e[e0:e1]`` to the outputs of :func:`walk_loops`; the loop count."""
    at = vertex_offsets[loops]
    flag = not is_closed
    for i in range(v0, v1):
        vertices[at] = path_v[i]
        at += 1
        flag = flag or several[path_v[i]]
    vertex_offsets[loops + 1] = at
    at = edge_offsets[loops]
    for i in range(e0, e1):
        edges[at] = path_e[i]
        at += 1
    edge_offsets[loops + 1] = at
    closed[loops] = is_closed
    pinched[loops] = flag
    return loops + 1
