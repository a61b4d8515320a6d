"""HPDE step 7, second half (Xie and Zou 2013, Sec. 4.7): mesh optimisation of the smoothed patch.

After the smoothing (:mod:`.smoothing`), edges shorter
than a rate of EdgeLen are collapsed to their midpoints and edges are swapped while that
raises the smaller angle of their two triangles (Fig. 5). The tangential relaxation and the
obtuse-edge splits are the option ``relax`` beyond the paper; the final guarded pass on the
worst triangles (option ``quality_floor``) is in :mod:`.quality_pass`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...geometry.flips import relax_edges
from ...geometry.quality import corner_angles, cross_rows, face_normals, triangle_quality, unique_edges, vertex_normals
from ...geometry.topology import edge_pair_set, interior_edges, vertex_face_runs
from ._optimisation_kernels import edge_adjacency, faces_around_edges, independent_link_edges
from ._worst_vertex_kernels import worst_vertex_moves

__all__ = ["split_obtuse_edges", "remove_valence_three", "compact_vertices", "sorted_edges", "adjacency",
           "decimate_short_edges",
           "swap_edges_min_angle", "improve_worst_vertices", "improve_worst_vertices_numpy"]

# A collapse may turn no surrounding face by more than this (cosine of 60 degrees); a swap
# may turn its two faces no further from their former mean normal.
COLLAPSE_MIN_COS = 0.5


def split_obtuse_edges(V, F, n_fixed, max_angle=np.radians(120.0)):
    """Split the long edge of every triangle with an angle above ``max_angle`` (new vertex at the quad centroid).

    Beyond the paper (part of option ``relax``): flat triangles whose three corners are loop
    vertices (ears of a nearly straight stretch of the loop, where no prediction point was
    kept) cannot be improved by moving vertices; splitting their interior long edge gives a
    free vertex that the relaxation then moves into the hole. Loop edges are never split; each
    triangle takes part in at most one split per call.

    Returns
    -------
    V : (n + s, 3) float64
    F : (m + 2 s, 3) int64
    splits : int
    """
    V = np.array(V, np.float64)
    F = np.array(F, np.int64)
    n = len(V)
    ang = corner_angles(V, F)
    obtuse = np.flatnonzero(ang.max(axis=1) > max_angle)
    if len(obtuse) == 0:
        return V, F, 0
    E, f1, c1, f2, c2 = interior_edges(F, n)
    # Half-edge of each interior edge in face f1 starts at corner c1: the edge opposite corner
    # (c1 + 2) % 3 of f1, and likewise in f2; -1 where the edge opposite a corner is a border edge.
    opposite = np.full(3 * len(F), -1, np.int64)
    opposite[3 * f1 + (c1 + 2) % 3] = np.arange(len(E))
    opposite[3 * f2 + (c2 + 2) % 3] = np.arange(len(E))
    busy = np.zeros(len(F), bool)
    new_faces, splits = [], 0
    for f in obtuse[np.argsort(-ang.max(axis=1)[obtuse])].tolist():
        i = int(opposite[3 * f + int(np.argmax(ang[f]))])
        if i < 0 or busy[f1[i]] or busy[f2[i]]:
            continue
        a, b = E[i]
        c = F[f1[i], (c1[i] + 2) % 3]
        d = F[f2[i], (c2[i] + 2) % 3]
        w = len(V)
        # The centroid of the quad a, c, b, d: off the flat corner c, towards d.
        V = np.vstack([V, 0.25 * (V[a] + V[b] + V[c] + V[d])])
        F[f1[i]] = (a, w, c)
        F[f2[i]] = (b, w, d)
        new_faces += [(w, b, c), (w, a, d)]
        busy[[f1[i], f2[i]]] = True
        splits += 1
    if new_faces:
        F = np.concatenate([F, np.asarray(new_faces, np.int64)])
    return V, F, splits


def remove_valence_three(V, F, n_fixed, forbidden_edges=()):
    """Remove free vertices with three neighbours, their three triangles becoming one.

    Beyond the paper (part of option ``relax``): such a vertex has an angle of at least 120
    degrees in one of its triangles, and no relaxation helps when its neighbours are loop
    vertices. Refused when the new triangle would duplicate an edge, use a forbidden edge or
    face against the removed ones.

    Returns
    -------
    V : (n', 3) float64  compacted (loop vertices first, unchanged)
    F : (m', 3) int64
    removed : int
    keep : (n',) int64  input index of each remaining vertex
    """
    V = np.asarray(V, np.float64)
    F = np.array(F, np.int64)
    n = len(V)
    forbidden = edge_pair_set(forbidden_edges)
    valence = np.bincount(F.ravel(), minlength=n)
    alive = np.ones(len(F), bool)
    gone = np.zeros(n, bool)
    new_faces = []
    for v in np.flatnonzero((valence == 3) & (np.arange(n) >= n_fixed)).tolist():
        ring = np.flatnonzero(np.any(F == v, axis=1) & alive)
        if len(ring) != 3 or np.any(gone[F[ring]]):
            continue
        # The link of v, in the order its faces traverse it.
        nxt = {}
        for f in ring:
            c = int(np.flatnonzero(F[f] == v)[0])
            nxt[int(F[f, (c + 1) % 3])] = int(F[f, (c + 2) % 3])
        a = next(iter(nxt))
        b = nxt.get(a)
        c = nxt.get(b)
        if b is None or c is None or nxt.get(c) != a or len({a, b, c}) != 3:
            continue  # not a closed triangle link
        tri = (a, b, c)
        if any(tuple(sorted((tri[i], tri[(i + 1) % 3]))) in forbidden for i in range(3)):
            continue
        old = face_normals(V, F[ring], normalize=False).sum(axis=0)
        new = cross_rows(V[tri[1]] - V[tri[0]], V[tri[2]] - V[tri[0]])
        if new @ old <= 0.5 * np.linalg.norm(new) * np.linalg.norm(old):
            continue
        alive[ring] = False
        gone[v] = True
        new_faces.append(tri)
    if not new_faces:
        return V, F, 0, np.arange(n)
    V, F, keep = compact_vertices(V, np.concatenate([F[alive], np.asarray(new_faces, np.int64)]), ~gone)
    return V, F, len(new_faces), keep


def compact_vertices(V, F, alive):
    """Drop the vertices not ``alive`` (removed by collapses) and renumber the faces.

    Returns
    -------
    V : (n', 3) float64  the alive vertices, in order
    F : (m, 3) int64  renumbered
    keep : (n',) int64  input index of each remaining vertex
    """
    keep = np.flatnonzero(alive)
    index = np.full(len(V), -1, np.int64)
    index[keep] = np.arange(len(keep))
    return V[keep], index[F], keep


def sorted_edges(F, n):
    """:func:`...geometry.quality.unique_edges` of a face list on n vertices, by integer keys.

    The rows (a, b), a < b, in lexicographic order are the sorted unique keys a n + b, which
    one integer sort finds faster than the row-wise unique; the result is the same array.
    """
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).astype(np.int64), axis=1)
    keys = np.unique(E[:, 0] * np.int64(n) + E[:, 1])
    return np.stack([keys // n, keys % n], axis=1)


def adjacency(F, n):
    """Unique edges (e, 2) and the symmetric (n, n) int8 CSR vertex adjacency of a face list.

    Compiled (:func:`._optimisation_kernels.edge_adjacency`): the edges of :func:`sorted_edges`
    and the canonical CSR arrays of the COO matrix of the pairs (a, b), (b, a).
    """
    if not len(F):
        E = unique_edges(F)
        A = sp.coo_matrix((np.ones(2 * len(E), np.int8), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])),
                          shape=(n, n)).tocsr()
        return E, A
    E, indptr, indices = edge_adjacency(np.ascontiguousarray(F, np.int64), int(n))
    return E, sp.csr_matrix((np.ones(len(indices), np.int8), indices, indptr), shape=(n, n))


def _sliver_priority(V, F, E, lengths, n_fixed, sliver_angle, eligible=None):
    """Edge lengths with 0 for the edge from a sliver apex to the nearer end of its loop edge.

    A sliver apex is a free vertex whose angle exceeds ``sliver_angle`` in a face whose
    opposite edge is a loop edge: it sits almost on the loop, too close to be kept.
    """
    ang = corner_angles(V, F)
    out = lengths.copy()
    n = len(V)
    keys = E[:, 0] * n + E[:, 1]
    for c in range(3):
        apex, u, w = F[:, c], F[:, (c + 1) % 3], F[:, (c + 2) % 3]
        loop_edge = (u < n_fixed) & (w < n_fixed) & ((w == (u + 1) % n_fixed) | (u == (w + 1) % n_fixed))
        ok = apex >= n_fixed
        if eligible is not None:
            ok &= eligible[apex]
        hit = np.flatnonzero(loop_edge & ok & (ang[:, c] > sliver_angle))
        if len(hit) == 0:
            continue
        du = np.linalg.norm(V[apex[hit]] - V[u[hit]], axis=1)
        dw = np.linalg.norm(V[apex[hit]] - V[w[hit]], axis=1)
        near = np.where(du <= dw, u[hit], w[hit])
        k = np.minimum(apex[hit], near) * n + np.maximum(apex[hit], near)
        out[np.isin(keys, k)] = 0.0
    return out


def _short_edges(V, F, E, n_fixed, threshold, sliver_angle, sliver_eligible):
    """Edges to collapse, shortest first: shorter than ``threshold`` (or sliver edges) and not loop-loop."""
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    if sliver_angle is not None:
        lengths = _sliver_priority(V, F, E, lengths, n_fixed, sliver_angle, sliver_eligible)
    cand = np.flatnonzero((lengths < threshold) & ~((E[:, 0] < n_fixed) & (E[:, 1] < n_fixed)))
    return cand[np.argsort(lengths[cand], kind="stable")]


def _independent_edges(A, a, b, n):
    """Mask of the edges (a, b), in priority order, whose closed neighbourhoods no earlier edge claims.

    Also the link condition: the ends share exactly two neighbours (the edge's opposite vertices).
    Compiled (:func:`._optimisation_kernels.independent_link_edges`) on the CSR arrays of A.
    """
    A = A.tocsr()
    return independent_link_edges(A.indptr.astype(np.int64), A.indices.astype(np.int64),
                                  np.asarray(a, np.int64), np.asarray(b, np.int64), n)


def _collapse_targets(V, a, b, n_fixed):
    """Survivor, victim and new position of each collapse: onto the loop end if any, else the midpoint."""
    a_fixed, b_fixed = a < n_fixed, b < n_fixed
    survivor = np.where(b_fixed, b, a)
    victim = np.where(b_fixed, a, b)
    newpos = np.where((a_fixed | b_fixed)[:, None], V[survivor], 0.5 * (V[a] + V[b]))
    return survivor, victim, newpos, a_fixed | b_fixed


def _turns_faces(V, F, a, b, newpos, n):
    """Collapses that would turn a surrounding face (not one on the edge) by more than 60 degrees."""
    # the faces around each edge but not on it (compiled: the nonzeros below 2 of VF[a] + VF[b])
    rows, faces = faces_around_edges(np.ascontiguousarray(F, np.int64), int(n), np.asarray(a, np.int64),
                                     np.asarray(b, np.int64))
    corners = V[F[faces]]
    moved = (F[faces] == a[rows, None]) | (F[faces] == b[rows, None])
    new_corners = np.where(moved[..., None], newpos[rows, None, :], corners)
    n_old = cross_rows(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    n_new = cross_rows(new_corners[:, 1] - new_corners[:, 0], new_corners[:, 2] - new_corners[:, 0])
    ok_face = np.einsum("ij,ij->i", n_old, n_new) > COLLAPSE_MIN_COS * np.linalg.norm(n_old, axis=1) * \
        np.linalg.norm(n_new, axis=1)
    bad = np.zeros(len(a), bool)
    np.logical_or.at(bad, rows, ~ok_face)
    return bad


def _joins_forbidden(A, survivor, victim, candidates, n_fixed, forbidden):
    """Mask of the ``candidates`` whose collapse onto the loop would join a forbidden pair of loop vertices."""
    bad = np.zeros(len(survivor), bool)
    indptr, indices = A.indptr, A.indices  # row v's neighbours, as A[v].indices gives them (without its slicing cost)
    for t in candidates:
        s, vct = int(survivor[t]), int(victim[t])
        nbrs = indices[indptr[vct]:indptr[vct + 1]]
        if any(tuple(sorted((s, int(x)))) in forbidden for x in nbrs if x < n_fixed and x != s):
            bad[t] = True
    return bad


def _collapse(V, F, survivor, victim, newpos, n):
    """Move each survivor to its new position, merge its victim into it and drop the degenerate faces."""
    V[survivor] = newpos
    remap = np.arange(n)
    remap[victim] = survivor
    F = remap[F]
    return F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]


def decimate_short_edges(V, F, n_fixed, threshold, forbidden_edges=(), max_rounds=100, sliver_angle=None,
                         sliver_eligible=None):
    """Collapse edges shorter than ``threshold`` (Sec. 4.7 and 4.8, Fig. 5(a)-(b)).

    The two triangles on the edge P_1 P_2 disappear and the remaining vertex moves to the
    midpoint (P_1 + P_2) / 2, shortest edges first. Readings: an edge with one boundary end
    collapses onto the boundary vertex (the loop is kept exactly); edges between two boundary
    vertices are kept; a collapse must pass the link condition (the edge's ends share only its
    two opposite vertices), must not turn any surrounding face by more than 60 degrees and must
    not create a forbidden edge. The paper's queue (sorted edges, the shortest renewed edge
    next) is realised in rounds: each round collapses, shortest first, edges whose
    neighbourhoods do not overlap.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64  consistently oriented
    n_fixed : int  the first n_fixed vertices are the boundary loop
    threshold : float
    forbidden_edges : (p, 2) int  pairs of boundary vertices that must not be joined
    sliver_angle : float, optional
        Also collapse a free vertex onto the nearer end of a loop edge when its angle opposite
        that edge exceeds this (a sliver on the loop; used after the relaxation).
    sliver_eligible : (n,) bool, optional  vertices that may be collapsed as sliver apexes

    Returns
    -------
    V : (n', 3) float64  compacted (boundary first, unchanged)
    F : (m', 3) int64
    collapses : int
    keep : (n',) int64  input index of each remaining vertex
    """
    V = np.array(V, np.float64)
    F = np.array(F, np.int64)
    n = len(V)
    forbidden = edge_pair_set(forbidden_edges)
    alive_v = np.ones(n, bool)
    collapses = 0
    for _ in range(max_rounds):
        E, A = adjacency(F, n)
        cand = _short_edges(V, F, E, n_fixed, threshold, sliver_angle, sliver_eligible)
        if len(cand) == 0:
            break
        a, b = E[cand, 0], E[cand, 1]
        sel = _independent_edges(A, a, b, n)
        if not sel.any():
            break
        a, b = a[sel], b[sel]
        survivor, victim, newpos, on_loop = _collapse_targets(V, a, b, n_fixed)
        bad = _turns_faces(V, F, a, b, newpos, n)
        if forbidden:
            bad |= _joins_forbidden(A, survivor, victim, np.flatnonzero(~bad & on_loop), n_fixed, forbidden)
        good = ~bad
        if not good.any():
            break
        F = _collapse(V, F, survivor[good], victim[good], newpos[good], n)
        alive_v[victim[good]] = False
        collapses += int(good.sum())
    V, F, keep = compact_vertices(V, F, alive_v)
    return V, F, collapses, keep


def swap_edges_min_angle(V, F, forbidden_edges=(), max_rounds=100):
    """Swap interior edges while that raises the minimum angle of the two triangles (Sec. 4.7, Fig. 5(c)-(d)).

    Edge P_1 P_2 with opposite vertices Q_1, Q_2 becomes Q_1 Q_2 when the smallest angle of
    triangles P_1 Q_1 Q_2, P_2 Q_1 Q_2 exceeds that of P_1 P_2 Q_1, P_1 P_2 Q_2
    (:func:`geometry.flips.relax_edges` with ``criterion="min_angle"``). Readings: a swap is
    refused when the new edge exists, is forbidden, or a new triangle would turn 60 degrees or
    more from the mean normal of the old pair (no fold, and the shape of a bent quad is kept);
    swaps run in rounds of face-disjoint edges, largest gain first, until none applies.

    Returns
    -------
    F : (m, 3) int64
    swaps : int
    """
    return relax_edges(V, F, forbidden_edges, max_rounds=max_rounds, criterion="min_angle",
                       normal_cos=COLLAPSE_MIN_COS)


def improve_worst_vertices(V, F, n_fixed, target=0.5, rounds=5, steps=(1.0, 0.5, 0.25)):
    """Move free vertices of poor triangles to where the worst of their triangles is best.

    Beyond the paper (part of option ``relax``): the min-angle swaps of Sec. 4.7 cannot fix a
    triangle whose long edge is a loop edge (a free vertex almost on the loop) or whose
    vertices all have poor rings. For every free vertex with an incident triangle of quality
    2r/R below ``target``, candidate positions are tried on the segment from the vertex
    towards the centroid of its link, projected onto its tangent plane, and towards the
    best apex for each poor incident triangle's opposite edge
    (the apex of an equilateral triangle on that edge, in the tangent plane, on the side the
    triangle's orientation puts the vertex); the candidate raising the
    smallest quality of the vertex's triangles most is taken, if no triangle turns by more
    than 60 degrees from the vertex normal. Rounds repeat while anything moves. Each round's
    moves are compiled (:func:`._worst_vertex_kernels.worst_vertex_moves`, the bits of
    :func:`improve_worst_vertices_numpy`), the vertices taken worst first, as numpy's argsort orders them.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    n_fixed : int  the first n_fixed vertices (the loop) do not move
    target : float  quality below which a triangle's free vertices are moved
    rounds : int
    steps : sequence of float  fractions of each candidate displacement tried

    Returns
    -------
    V : (n, 3) float64
    moved : int  accepted moves
    """
    V = np.array(V, np.float64)
    F = np.asarray(F, np.int64)
    n = len(V)
    if len(F) == 0 or n <= n_fixed:
        return V, 0
    if F.min() < 0 or F.max() >= n:
        return improve_worst_vertices_numpy(V, F, n_fixed, target, rounds, steps)  # raises numpy's IndexError
    faces_at, start = vertex_face_runs(F, n)
    F = np.ascontiguousarray(F)
    steps = np.asarray(steps, np.float64)
    moved = 0
    for _ in range(rounds):
        q = triangle_quality(V, F)
        verts = np.unique(F[q < target].ravel())
        verts = verts[verts >= n_fixed]
        if len(verts) == 0:
            break
        N = vertex_normals(V, F, n)
        worst = np.full(n, np.inf)  # each vertex's worst face, as q[its faces].min() gives it
        np.minimum.at(worst, F.ravel(), np.repeat(q, 3))
        changed = worst_vertex_moves(V, F, faces_at, start, verts[np.argsort(worst[verts])], N, float(target), steps,
                                     COLLAPSE_MIN_COS)
        moved += changed
        if changed == 0:
            break
    return V, moved


def improve_worst_vertices_numpy(V, F, n_fixed, target=0.5, rounds=5, steps=(1.0, 0.5, 0.25)):
    """:func:`improve_worst_vertices` in numpy (the reference of the compiled moves)."""
    V = np.array(V, np.float64)
    F = np.asarray(F, np.int64)
    n = len(V)
    if len(F) == 0 or n <= n_fixed:
        return V, 0
    faces_at, start = vertex_face_runs(F, n)
    incident = lambda v: faces_at[start[v]:start[v + 1]]  # noqa: E731
    moved = 0
    for _ in range(rounds):
        q = triangle_quality(V, F)
        poor = np.flatnonzero(q < target)
        verts = np.unique(F[poor].ravel())
        verts = verts[verts >= n_fixed]
        if len(verts) == 0:
            break
        N = vertex_normals(V, F, n)
        changed = 0
        for v in verts[np.argsort([q[incident(v)].min() for v in verts])].tolist():
            faces = incident(v)
            tri = F[faces]
            nv = N[v] / max(np.linalg.norm(N[v]), 1e-300)
            current = triangle_quality(V, tri).min()
            # Candidate targets: the link centroid and, for each poor incident triangle, the apex
            # of the equilateral triangle on its opposite edge (on the side the vertex is on).
            link = np.unique(tri[tri != v])
            goals = [V[link].mean(axis=0)]
            for t in tri[triangle_quality(V, tri) < target]:
                c = int(np.flatnonzero(t == v)[0])
                a, b = V[t[(c + 1) % 3]], V[t[(c + 2) % 3]]
                mid, e = 0.5 * (a + b), b - a
                side = cross_rows(nv, e)  # in the tangent plane, perpendicular to the edge
                side /= max(np.linalg.norm(side), 1e-300)
                goals.append(mid + side * (np.sqrt(3.0) / 2.0) * np.linalg.norm(e))
            best, best_q = None, current
            old_normals = face_normals(V, tri)
            W = V.copy()  # V with v moved to the candidate (only W[v] changes between candidates)
            for goal in goals:
                d = goal - V[v]
                d -= (d @ nv) * nv  # tangential: keep the shape
                for s in steps:
                    p = V[v] + s * d
                    W[v] = p
                    qn = triangle_quality(W, tri).min()
                    if qn <= best_q + 1e-6:
                        continue
                    fn = face_normals(W, tri)
                    if np.any(np.einsum("ij,j->i", fn, nv) <= COLLAPSE_MIN_COS) or \
                            np.any(np.einsum("ij,ij->i", fn, old_normals) <= COLLAPSE_MIN_COS):
                        continue
                    best, best_q = p, qn
            if best is not None:
                V[v] = best
                changed += 1
        moved += changed
        if changed == 0:
            break
    return V, moved
