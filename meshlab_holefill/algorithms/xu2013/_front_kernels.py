"""Compiled kernels of the advancing front's per-step tests (numba).

The checks of one step (called by :func:`._front_step._valid`), the merge-target search of
Step 4, the release of refused nodes and the obstacle tests, over the arrays of the front's
state (:mod:`._front_state`). Each does the IEEE operations of the
Python predicates it replaces (:mod:`._front_predicates`, kept as their reference) in the same
order, without fastmath, so the front takes the same decisions in the same order
(tests/algorithms/xu2013/test_front_compiled.py and test_front_kernels.py compare them).
:func:`min_point_triangle_distance` gives bit for bit the minimum of
:func:`._front_predicates.point_triangle_distance`.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["min_point_triangle_distance"]


@njit(cache=True)
def _sq3(a0, a1, a2):
    return math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)


@njit(cache=True)
def min_point_triangle_distance(x, V, F, cand, radius):
    """min(radius, distance from x (3,) to the triangles V[F[cand]])."""
    best_all = np.inf
    for c in range(cand.shape[0]):
        f = cand[c]
        A = V[F[f, 0]]
        B = V[F[f, 1]]
        C = V[F[f, 2]]
        e1 = (B[0] - A[0], B[1] - A[1], B[2] - A[2])
        e2 = (C[0] - A[0], C[1] - A[1], C[2] - A[2])
        n0 = e1[1] * e2[2] - e1[2] * e2[1]
        n1 = e1[2] * e2[0] - e1[0] * e2[2]
        n2 = e1[0] * e2[1] - e1[1] * e2[0]
        nn = n0 * n0 + n1 * n1 + n2 * n2
        w0, w1, w2 = x[0] - A[0], x[1] - A[1], x[2] - A[2]
        ok = nn > 0
        t = (w0 * n0 + w1 * n1 + w2 * n2) / nn if ok else 0.0
        p0, p1, p2 = x[0] - t * n0, x[1] - t * n1, x[2] - t * n2
        inside = ok
        for k in range(3):
            U = A if k == 0 else (B if k == 1 else C)
            W = B if k == 0 else (C if k == 1 else A)
            a0, a1, a2 = W[0] - U[0], W[1] - U[1], W[2] - U[2]
            b0, b1, b2 = p0 - U[0], p1 - U[1], p2 - U[2]
            c0 = a1 * b2 - a2 * b1
            c1 = a2 * b0 - a0 * b2
            c2 = a0 * b1 - a1 * b0
            if not (c0 * n0 + c1 * n1 + c2 * n2 >= 0.0):
                inside = False
        best = abs(t) * math.sqrt(nn) if inside else np.inf
        for k in range(3):
            U = A if k == 0 else (B if k == 1 else C)
            W = B if k == 0 else (C if k == 1 else A)
            e0, e1_, e2_ = W[0] - U[0], W[1] - U[1], W[2] - U[2]
            ee = max(e0 * e0 + e1_ * e1_ + e2_ * e2_, 1e-300)
            s = ((x[0] - U[0]) * e0 + (x[1] - U[1]) * e1_ + (x[2] - U[2]) * e2_) / ee
            s = min(max(s, 0.0), 1.0)
            d = _sq3(x[0] - (U[0] + s * e0), x[1] - (U[1] + s * e1_), x[2] - (U[2] + s * e2_))
            best = min(best, d)
        best_all = min(best_all, best)
    return min(best_all, radius)


# ---------------------------------------------------------------------------------------------
# The per-step tests of the front over the arrays of its state (see _front_state.FrontArrays):
# positions P (n, 3), per node its vertex, next node and front label, and the list of alive
# nodes. Each kernel does the IEEE operations of the Python code it replaces in the same
# order; squares are ``x ** two`` with the exponent 2.0 passed at run time, so that they go
# through libm's pow like Python's ``x ** 2`` (pow(x, 2) is not always x * x bit for bit).


# pow costs ~10 multiplications; a distance whose product form exceeds the bound by this
# factor (far beyond the few ulps by which the two forms can differ) is beyond it either way.
_CLEARLY_BEYOND = 1.0 + 1e-12


# The scans over the alive nodes read a vertex's coordinates as scalars (P[u, i]), not as a row
# view P[u]: each view takes and drops a reference on P, two atomic operations per node that
# would cost more than the node's test.


@njit(cache=True)
def _beyond_xyz(x0, x1, x2, Y, r2, two):
    """Is |X - Y|^2 > r2 for X = (x0, x1, x2), with the squares as Python's ``(X[i] - Y[i]) ** 2``?"""
    a, b, c = x0 - Y[0], x1 - Y[1], x2 - Y[2]
    if a * a + b * b + c * c > r2 * _CLEARLY_BEYOND:
        return True
    return not (a ** two + b ** two + c ** two <= r2)


@njit(cache=True)
def _beyond(X, Y, r2, two):
    """Is |X - Y|^2 > r2, with the squares as Python's ``(X[i] - Y[i]) ** 2``?"""
    return _beyond_xyz(X[0], X[1], X[2], Y, r2, two)


@njit(cache=True)
def _cell(x, c):
    return math.floor(x / c)


@njit(cache=True)
def _in_query_cells(x0, x1, x2, pos, radius, cell):
    """Is (x0, x1, x2) in a grid cell of the box pos +- radius (the cells of the grid query the Python reference made)?"""
    for i in range(3):
        key = _cell(x0 if i == 0 else (x1 if i == 1 else x2), cell)
        if key < _cell(pos[i] - radius, cell) or key > _cell(pos[i] + radius, cell):
            return False
    return True


@njit(cache=True)
def merge_target(pos, radius, v, p, q, label, P, node_vertex, node_front, alive, n_alive, cell, two):
    """The vertex a new vertex at ``pos`` merges with (Sec. 3.2, Step 4), or -1.

    The nearest (by squared distance, then by id) vertex within ``radius`` that has a node on
    front ``label``, other than v, p and q, found as by a query of a uniform grid of cell
    ``cell`` (the cells of the box pos +- radius, then the exact squared distance).
    """
    r2 = radius * radius
    best_d, best_u = np.inf, -1
    for t in range(n_alive):
        n = alive[t]
        if node_front[n] != label:
            continue
        u = node_vertex[n]
        if u == v or u == p or u == q:
            continue
        x0, x1, x2 = P[u, 0], P[u, 1], P[u, 2]
        if _beyond_xyz(x0, x1, x2, pos, r2, two):
            continue
        d = (x0 - pos[0]) ** two + (x1 - pos[1]) ** two + (x2 - pos[2]) ** two
        if (d < best_d or (d == best_d and u < best_u)) and _in_query_cells(x0, x1, x2, pos, radius, cell):
            best_d, best_u = d, u
    return best_u


@njit(cache=True)
def _orient(px, py, qx, qy, rx, ry):
    return (qx - px) * (ry - py) - (qy - py) * (rx - px)


@njit(cache=True)
def segments_cross_2d(a0x, a0y, a1x, a1y, b0x, b0y, b1x, b1y):
    """:func:`._front_predicates.segments_cross` on scalar coordinates."""
    scale = max(max(max(abs(a1x - a0x), abs(a1y - a0y)), abs(b1x - b0x)), abs(b1y - b0y))
    eps = 1e-9 * scale * scale
    o1 = _orient(a0x, a0y, a1x, a1y, b0x, b0y)
    o2 = _orient(a0x, a0y, a1x, a1y, b1x, b1y)
    if (o1 > eps and o2 > eps) or (o1 < -eps and o2 < -eps):
        return False
    o3 = _orient(b0x, b0y, b1x, b1y, a0x, a0y)
    o4 = _orient(b0x, b0y, b1x, b1y, a1x, a1y)
    if (o3 > eps and o4 > eps) or (o3 < -eps and o4 < -eps):
        return False
    if abs(o1) <= eps and abs(o2) <= eps:
        if abs(a1x - a0x) + abs(b1x - b0x) >= abs(a1y - a0y) + abs(b1y - b0y):
            a0, a1, b0, b1, c0, c1, d0, d1 = a0x, a1x, b0x, b1x, a0y, a1y, b0y, b1y
        else:
            a0, a1, b0, b1, c0, c1, d0, d1 = a0y, a1y, b0y, b1y, a0x, a1x, b0x, b1x
        lo_a, hi_a = min(a0, a1), max(a0, a1)
        lo_b, hi_b = min(b0, b1), max(b0, b1)
        tol = 1e-9 * scale
        return (hi_a >= lo_b and hi_b >= lo_a and max(c0, c1) + tol >= min(d0, d1)
                and max(d0, d1) + tol >= min(c0, c1))
    return True


@njit(cache=True)
def _norm3(a0, a1, a2):
    return math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)


@njit(cache=True)
def front_edges_crossed(edge_ids, seg, V, m, longest_edge, P, node_vertex, node_next, alive, n_alive, cell, two):
    """Does a new edge cross a front edge near V, in the plane of normal m?

    The crossing test of a step: the new edges ``edge_ids`` (e, 2)
    with end points ``seg`` (e, 2, 3) against the front edges (x, next x) whose x lies within
    the longest new edge's reach from V plus ``longest_edge``, projected on m's plane,
    skipping pairs that share a vertex.
    """
    reach = -np.inf
    for s in range(seg.shape[0]):
        d0 = _norm3(seg[s, 0, 0] - V[0], seg[s, 0, 1] - V[1], seg[s, 0, 2] - V[2])
        d1 = _norm3(seg[s, 1, 0] - V[0], seg[s, 1, 1] - V[1], seg[s, 1, 2] - V[2])
        reach = max(reach, max(d0, d1))
    reach = reach + longest_edge
    if abs(m[0]) < 0.9:
        r0, r1, r2 = 1.0, 0.0, 0.0
    else:
        r0, r1, r2 = 0.0, 1.0, 0.0
    c0, c1, c2 = m[1] * r2 - m[2] * r1, m[2] * r0 - m[0] * r2, m[0] * r1 - m[1] * r0
    nc = _norm3(c0, c1, c2)
    if nc > 0.0:
        c0, c1, c2 = c0 / nc, c1 / nc, c2 / nc
    e1 = (c0, c1, c2)
    e2 = (m[1] * e1[2] - m[2] * e1[1], m[2] * e1[0] - m[0] * e1[2], m[0] * e1[1] - m[1] * e1[0])
    ne = seg.shape[0]
    flat = np.empty((ne, 4))
    for s in range(ne):
        for j in range(2):
            flat[s, 2 * j] = seg[s, j, 0] * e1[0] + seg[s, j, 1] * e1[1] + seg[s, j, 2] * e1[2]
            flat[s, 2 * j + 1] = seg[s, j, 0] * e2[0] + seg[s, j, 1] * e2[1] + seg[s, j, 2] * e2[2]
    lo_x, hi_x = min(flat[0, 0], flat[0, 2]), max(flat[0, 0], flat[0, 2])
    lo_y, hi_y = min(flat[0, 1], flat[0, 3]), max(flat[0, 1], flat[0, 3])
    for s in range(1, ne):
        lo_x, hi_x = min(lo_x, min(flat[s, 0], flat[s, 2])), max(hi_x, max(flat[s, 0], flat[s, 2]))
        lo_y, hi_y = min(lo_y, min(flat[s, 1], flat[s, 3])), max(hi_y, max(flat[s, 1], flat[s, 3]))
    r2_reach = reach * reach
    for t in range(n_alive):
        n = alive[t]
        x = node_vertex[n]
        x0, x1, x2 = P[x, 0], P[x, 1], P[x, 2]
        if _beyond_xyz(x0, x1, x2, V, r2_reach, two) or not _in_query_cells(x0, x1, x2, V, reach, cell):
            continue
        y = node_vertex[node_next[n]]
        y0, y1, y2 = P[y, 0], P[y, 1], P[y, 2]
        fx0 = x0 * e1[0] + x1 * e1[1] + x2 * e1[2]
        fx1 = x0 * e2[0] + x1 * e2[1] + x2 * e2[2]
        fy0 = y0 * e1[0] + y1 * e1[1] + y2 * e1[2]
        fy1 = y0 * e2[0] + y1 * e2[1] + y2 * e2[2]
        if max(fx0, fy0) < lo_x or min(fx0, fy0) > hi_x or max(fx1, fy1) < lo_y or min(fx1, fy1) > hi_y:
            continue
        for s in range(ne):
            a, b = edge_ids[s, 0], edge_ids[s, 1]
            if a == x or a == y or b == x or b == y:
                continue
            if segments_cross_2d(flat[s, 0], flat[s, 1], flat[s, 2], flat[s, 3], fx0, fx1, fy0, fy1):
                return True
    return False


@njit(cache=True)
def near_any(x0, x1, x2, points, r2, two):
    """Is (x0, x1, x2) within sqrt(r2) of one of ``points`` (m, 3)? (:func:`._front_loop._release_blocked_near`)"""
    for j in range(points.shape[0]):
        if not _beyond_xyz(x0, x1, x2, points[j], r2, two):
            return True
    return False


# ---------------------------------------------------------------------------------------------
# Obstacle faces indexed by grid cell (_front_obstacles.FrontObstacles): ``keys`` the sorted
# linear keys of the non-empty cells of a box of cells from ``base`` with ``dims``, the faces
# of cell keys[i] in faces[starts[i]:starts[i + 1]].


@njit(cache=True)
def _search_sorted(keys, key):
    """``np.searchsorted(keys, key)`` (the first index whose key is >= key), as a plain bisection.

    numpy's takes and drops references on ``keys`` at each call, which cost more than the search.
    """
    lo, hi = 0, keys.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if keys[mid] < key:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def obstacle_candidates(lo, hi, cell, base, dims, keys, starts, faces, face_lo, face_hi, stamp, out):
    """Faces whose bounding box overlaps [lo, hi] (padded by 1e-9 cell), written to ``out``; their count.

    The faces of the grid cells the box covers, each once (``stamp`` (m,) marks those seen:
    its entries must be below stamp[-1], which is advanced), then filtered by bounding box,
    as :meth:`.FrontObstacles.candidates` does.
    """
    stamp[-1] += 1
    mark = stamp[-1]
    pad = 1e-9 * cell
    count = 0
    x0, y0, z0 = _cell(lo[0], cell) - base[0], _cell(lo[1], cell) - base[1], _cell(lo[2], cell) - base[2]
    x1, y1, z1 = _cell(hi[0], cell) - base[0], _cell(hi[1], cell) - base[1], _cell(hi[2], cell) - base[2]
    for ix in range(max(x0, 0), min(x1, dims[0] - 1) + 1):
        for iy in range(max(y0, 0), min(y1, dims[1] - 1) + 1):
            for iz in range(max(z0, 0), min(z1, dims[2] - 1) + 1):
                key = (ix * dims[1] + iy) * dims[2] + iz
                at = _search_sorted(keys, key)
                if at == keys.shape[0] or keys[at] != key:
                    continue
                for j in range(starts[at], starts[at + 1]):
                    f = faces[j]
                    if stamp[f] == mark:
                        continue
                    stamp[f] = mark
                    if (face_hi[f, 0] >= lo[0] - pad and face_hi[f, 1] >= lo[1] - pad and face_hi[f, 2] >= lo[2] - pad
                            and face_lo[f, 0] <= hi[0] + pad and face_lo[f, 1] <= hi[1] + pad
                            and face_lo[f, 2] <= hi[2] + pad):
                        out[count] = f
                        count += 1
    return count


@njit(cache=True)
def _cross_into(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True)
def _edge_side(U, W, P0, d0, d1, d2):
    """Side of the direction d of the triangle edge U W seen from P0: ((U - P0) x (W - P0)) . d."""
    c0, c1, c2 = _cross_into(U[0] - P0[0], U[1] - P0[1], U[2] - P0[2], W[0] - P0[0], W[1] - P0[1], W[2] - P0[2])
    return c0 * d0 + c1 * d1 + c2 * d2


@njit(cache=True)
def _other_two(f0, f1, f2, s):
    """Positions, in order, of the two corners of the face (f0, f1, f2) other than vertex s (one of them)."""
    if f0 == s:
        return 1, 2
    if f1 == s:
        return 0, 2
    return 0, 1


@njit(cache=True)
def segment_hits_triangle(P0, P1, A, B, C, tol):
    """One row of :func:`._front_predicates.segments_hit_triangles` (the same operations)."""
    n0, n1, n2 = _cross_into(B[0] - A[0], B[1] - A[1], B[2] - A[2], C[0] - A[0], C[1] - A[1], C[2] - A[2])
    scale = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    s0 = (P0[0] - A[0]) * n0 + (P0[1] - A[1]) * n1 + (P0[2] - A[2]) * n2
    s1 = (P1[0] - A[0]) * n0 + (P1[1] - A[1]) * n1 + (P1[2] - A[2]) * n2
    eps = tol * scale
    if (s0 > eps and s1 > eps) or (s0 < -eps and s1 < -eps):
        return False
    if abs(s0) <= eps and abs(s1) <= eps:
        return False
    d0, d1, d2 = P1[0] - P0[0], P1[1] - P0[1], P1[2] - P0[2]
    e0 = _edge_side(A, B, P0, d0, d1, d2)
    e1 = _edge_side(B, C, P0, d0, d1, d2)
    e2 = _edge_side(C, A, P0, d0, d1, d2)
    lim = tol * math.sqrt(scale) * math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return (e0 >= -lim and e1 >= -lim and e2 >= -lim) or (e0 <= lim and e1 <= lim and e2 <= lim)


@njit(cache=True)
def triangles_cross_faces(new_faces, corners, V, F, cand, n_cand, k, tol):
    """Does one of the new triangles intersect one of the faces F[cand[:n_cand]]?

    :meth:`.FrontObstacles.crossed`: pairs sharing two boundary vertices (ids below k) are
    skipped, pairs sharing one test the opposite edge of each against the other triangle,
    others every edge of each against the other.
    """
    for i in range(new_faces.shape[0]):
        T = corners[i]
        for c in range(n_cand):
            o = F[cand[c]]
            n_shared, s = 0, -1
            for j in range(3):
                x = new_faces[i, j]
                if 0 <= x < k and (x == o[0] or x == o[1] or x == o[2]):
                    n_shared += 1
                    s = x
            if n_shared >= 2:
                continue
            A, B, C = V[o[0]], V[o[1]], V[o[2]]
            if n_shared == 1:
                ja, jb = _other_two(new_faces[i, 0], new_faces[i, 1], new_faces[i, 2], s)
                ka, kb = _other_two(o[0], o[1], o[2], s)
                if segment_hits_triangle(T[ja], T[jb], A, B, C, tol):
                    return True
                if segment_hits_triangle(V[o[ka]], V[o[kb]], T[0], T[1], T[2], tol):
                    return True
            else:
                for j in range(3):
                    if segment_hits_triangle(T[j], T[(j + 1) % 3], A, B, C, tol):
                        return True
                    if segment_hits_triangle(V[o[j]], V[o[(j + 1) % 3]], T[0], T[1], T[2], tol):
                        return True
    return False


@njit(cache=True)
def _direction_angle(r0, r1, r2, d0, d1, d2, m):
    """:func:`._front_predicates.direction_angle` on scalars."""
    c0, c1, c2 = _cross_into(r0, r1, r2, d0, d1, d2)
    t = math.atan2(m[0] * c0 + m[1] * c1 + m[2] * c2,
                   (r0 * d0 + r1 * d1 + r2 * d2) - (r0 * m[0] + r1 * m[1] + r2 * m[2]) * (d0 * m[0] + d1 * m[1] + d2 * m[2]))
    return t + 2.0 * math.pi if t < 0.0 else t


@njit(cache=True)
def _coords(x, new_pos, P):
    """Coordinates of vertex x, a temporary id -1, -2 of the step being row -x - 1 of new_pos (scalars: a row
    view would take and drop a reference on its array)."""
    if x < 0:
        return new_pos[-x - 1, 0], new_pos[-x - 1, 1], new_pos[-x - 1, 2]
    return P[x, 0], P[x, 1], P[x, 2]


@njit(cache=True)
def step_geometry_valid(faces, nf, new_pos, behind, m, tiny, fold_min_cos, edge_ids, edge_nodes, ne, angle_margin, V,
                        longest_edge, P, node_vertex, node_next, node_plane, node_theta, alive, n_alive, cell, two):
    """The geometric checks of one step (:func:`._front_step._valid`, before the obstacles).

    Each new triangle of the first nf rows of ``faces`` (vertex ids, temporary ids for
    ``new_pos``) faces the way of m by more than ``tiny`` and does not fold onto the triangle
    behind a front edge it consumes (``behind[f, j]`` the normal behind its edge j, NaN where
    none) by more than arccos(fold_min_cos); each of the first ne new edges ``edge_ids[i]``
    leaves its existing ends (nodes ``edge_nodes[i]``, -1 for a new vertex) strictly inside
    their front angles, ``angle_margin`` from either side; no new edge crosses a nearby front
    edge (:func:`front_edges_crossed`). Counts rather than slices: the caller passes its scratch
    arrays whole (a slice branches, which defeats numba's pruning of reference counts).
    """
    for f in range(nf):
        a0, a1, a2 = _coords(faces[f, 0], new_pos, P)
        b0, b1, b2 = _coords(faces[f, 1], new_pos, P)
        c0, c1, c2 = _coords(faces[f, 2], new_pos, P)
        n0, n1, n2 = _cross_into(b0 - a0, b1 - a1, b2 - a2, c0 - a0, c1 - a1, c2 - a2)
        if n0 * m[0] + n1 * m[1] + n2 * m[2] <= tiny:
            return False
        for j in range(3):
            h0, h1, h2 = behind[f, j, 0], behind[f, j, 1], behind[f, j, 2]
            if not math.isnan(h0) and h0 * n0 + h1 * n1 + h2 * n2 < fold_min_cos * _norm3(n0, n1, n2):
                return False
    for i in range(ne):
        for j in range(2):
            nx = edge_nodes[i, j]
            if nx < 0:
                continue
            x, r = node_vertex[nx], node_vertex[node_next[nx]]
            y0, y1, y2 = _coords(edge_ids[i, 1 - j], new_pos, P)
            phi = _direction_angle(P[r, 0] - P[x, 0], P[r, 1] - P[x, 1], P[r, 2] - P[x, 2], y0 - P[x, 0],
                                   y1 - P[x, 1], y2 - P[x, 2], node_plane[nx])
            if not (angle_margin < phi < node_theta[nx] - angle_margin):
                return False
    if ne == 0:
        return True
    seg = np.empty((ne, 2, 3))
    for i in range(ne):
        for j in range(2):
            seg[i, j, 0], seg[i, j, 1], seg[i, j, 2] = _coords(edge_ids[i, j], new_pos, P)
    return not front_edges_crossed(edge_ids, seg, V, m, longest_edge, P, node_vertex, node_next, alive, n_alive,
                                   cell, two)
