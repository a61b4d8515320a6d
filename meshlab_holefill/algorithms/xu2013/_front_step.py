"""One step of the advancing front, compiled (numba): Steps 3-5 of Xu et al. 2013, Sec. 3.2.

At the node :func:`._front_loop.run_front` pops: the angle rule and its fallbacks
(:func:`_rules`, Step 3), the triangles of a rule with their merged vertices (:func:`_build`,
Steps 3-4), the topological and geometric checks (:func:`_valid`, with the kernels of
:mod:`._front_kernels`) and the obstacle check (:func:`_clear_of_obstacles`), then the update
(:func:`_apply`, Step 5: the new vertices and faces, the front edges, the linked-list surgery,
the splits, and the front angles of the changed nodes, :func:`front_angle`). The arrays are
those of :mod:`._front_state`. Every floating-point operation is that of the Python reference
(``tests/algorithms/xu2013/xu2013_front_oracle.py``) in the same order.

A compiled function that receives a tuple of arrays takes and drops a reference on each of
them (atomic operations) unless numba's reference-count pruning proves the pair redundant; with
26 arrays in the state that cost several times a step's arithmetic. The pruning fails once the
function frees an array of its own or takes one from a tuple (or a row view or a slice, which
branches) after a branch. So the step functions allocate nothing (their per-step arrays are the
scratch arrays of :func:`._front_state.new_scratch`), take the arrays they use from the tuples
first, read coordinates as scalars, and the helpers they call in their loops take arrays, not
the tuples.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._front_kernels import (merge_target, min_point_triangle_distance, obstacle_candidates, step_geometry_valid,
                             triangles_cross_faces)
from ._front_state import (DELETED, F_USED, MERGES, N_ALIVE, N_FACES, NEXT_LABEL, OBSTACLE_TESTS, RULE1, SPLITS,
                           _add_edge, _add_vertex, _find, _has_edge, _insert, _kill, _kill_node, _link, _new_node,
                           _node_on_front, heap_push)


# --------------------------------------------------------------------------- vectors: front angles, face normals
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


@njit(cache=True)
def _face_unit_normal(P, a, b, c):
    e0, e1, e2 = P[b, 0] - P[a, 0], P[b, 1] - P[a, 1], P[b, 2] - P[a, 2]
    g0, g1, g2 = P[c, 0] - P[a, 0], P[c, 1] - P[a, 1], P[c, 2] - P[a, 2]
    return _unit(e1 * g2 - e2 * g1, e2 * g0 - e0 * g2, e0 * g1 - e1 * g0)


# --------------------------------------------------------------------------- the triangles of a rule and their checks
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


# --------------------------------------------------------------------------- applying a step
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
def _kill_run(st, x, count):
    """Kill ``count`` nodes of a front, from node x on along ``nnext`` (a cycle too short to keep)."""
    for _ in range(count):
        nx = st.nnext[x]
        _kill_node(st, x)
        x = nx
