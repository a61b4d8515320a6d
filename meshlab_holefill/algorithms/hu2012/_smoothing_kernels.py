"""Compiled steps of the tangential smoothing (numba): its moves, its guard and its collapse search.

:func:`tangential_steps` is :func:`.tangential_smoothing._tangential_steps_numpy` (each round's
move of every movable vertex), :func:`refuse_worse_steps` is :func:`.tangential_smoothing._guarded_moves_numpy`
(the guarded moves of each step), :func:`best_collapse` the search of
:func:`.tangential_smoothing._best_collapse_numpy` (each round's collapse). They run on a few
hundred faces, every round, and their numpy forms are dominated by the overhead of small array
operations (the collapse search by Python sets, on noisy borders with many poor triangles). The kernels do the same
IEEE operations in the same order (face qualities as :func:`geometry.quality.triangle_quality`,
cross products as ``cross_rows``, row norms and dots as numpy's add.reduce and einsum, sums
over faces in bincount's order), and take minima, which are exact, so they return the same
bits. tests/algorithms/hu2012/test_smoothing_kernels.py checks them against the numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_cross, face_quality, unit_vertex_normals
from ...geometry._vector_kernels import dot3, norm3, npmax
from ._bilateral_kernels import undo_moves

__all__ = ["best_collapse", "refuse_worse_steps", "tangential_steps"]

_HALF_SQRT3 = np.sqrt(3.0) / 2.0  # the numpy code's constant, the same double


@njit(cache=True)
def tangential_steps(V, F, movable):
    """Each movable vertex's step to the mean apex of its faces, its part along the vertex normal removed.

    V : (n, 3) float64; F : (m, 3) int64 (valid indices); movable : (n,) bool.
    Returns d (n, 3) float64 (zero rows where not ``ok``) and ok (n,) bool: movable and on a face.
    """
    n, m = V.shape[0], F.shape[0]
    count = np.zeros(n)
    for f in range(m):
        for c in range(3):
            count[F[f, c]] += 1.0
    unit = np.empty((m, 3))
    for f in range(m):
        x = face_cross(V, F, f)
        length = npmax(norm3(x), 1e-300)
        unit[f, 0], unit[f, 1], unit[f, 2] = x[0] / length, x[1] / length, x[2] / length
    # target[:, j] += bincount(F[:, c], apex[:, j]) for c = 0, 1, 2: three sums, each from zero in
    # face order, added to the target in turn.
    target = np.zeros((n, 3))
    part = np.empty((n, 3))
    for c in range(3):
        part[:] = 0.0
        for f in range(m):
            v, a, b = F[f, c], F[f, (c + 1) % 3], F[f, (c + 2) % 3]
            e0, e1, e2 = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
            u0, u1, u2 = unit[f, 0], unit[f, 1], unit[f, 2]
            part[v, 0] += 0.5 * (V[a, 0] + V[b, 0]) + _HALF_SQRT3 * (u1 * e2 - u2 * e1)
            part[v, 1] += 0.5 * (V[a, 1] + V[b, 1]) + _HALF_SQRT3 * (u2 * e0 - u0 * e2)
            part[v, 2] += 0.5 * (V[a, 2] + V[b, 2]) + _HALF_SQRT3 * (u0 * e1 - u1 * e0)
        for v in range(n):
            for j in range(3):
                target[v, j] += part[v, j]
    normal = unit_vertex_normals(V, F, n)
    d = np.zeros((n, 3))
    ok = np.zeros(n, np.bool_)
    for v in range(n):
        ok[v] = movable[v] and count[v] > 0
        if not ok[v]:
            continue
        nv = (normal[v, 0], normal[v, 1], normal[v, 2])
        t = (target[v, 0] / count[v] - V[v, 0], target[v, 1] / count[v] - V[v, 1], target[v, 2] / count[v] - V[v, 2])
        along = dot3(t, nv)
        d[v, 0], d[v, 1], d[v, 2] = t[0] - along * nv[0], t[1] - along * nv[1], t[2] - along * nv[2]
    return d, ok


@njit(cache=True)
def _minimum(a, b):
    """np.minimum of two floats (NaN wins, as in np.minimum.at)."""
    if a != a or b != b:
        return np.nan
    return a if a <= b else b


@njit(cache=True)
def _quality_or_flipped(V, F, f, n_old):
    c = face_cross(V, F, f)
    if dot3((n_old[f, 0], n_old[f, 1], n_old[f, 2]), c) <= 0:
        return -1.0
    return face_quality(V, F[f, 0], F[f, 1], F[f, 2])


@njit(cache=True)
def _vertex_faces(F, n):
    """The faces at each vertex as runs of one array: faces[start[v]:start[v + 1]] (a face once per corner)."""
    start = np.zeros(n + 1, np.int64)
    for f in range(F.shape[0]):
        for c in range(3):
            start[F[f, c] + 1] += 1
    for v in range(n):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    faces = np.empty(start[n], np.int64)
    for f in range(F.shape[0]):
        for c in range(3):
            faces[fill[F[f, c]]] = f
            fill[F[f, c]] += 1
    return start, faces


@njit(cache=True)
def refuse_worse_steps(V, d, F, pending, steps):
    """The guarded moves of a smoothing round: for each step s in turn, while a vertex is pending,
    :func:`.tangential_smoothing._refuse_worse_numpy` ``(V, V + s * d * pending, F, pending)``, the vertices it
    put back pending at the next.

    V, d : (n, 3) float64; F : (m, 3) int64 (valid indices); pending : (n,) bool; steps : (s,) float64.
    The faces' qualities and normals before a step are those after the last one: only the faces of the
    vertices it moved are measured again (the same operations on the same coordinates, the same bits).
    """
    n, m = V.shape[0], F.shape[0]
    start, faces = _vertex_faces(F, n)
    q_old, n_old = _face_states(V, F)
    pending = pending.copy()
    for s in steps:
        if not pending.any():
            break
        stepped = np.empty_like(V)
        for v in range(n):
            on = 1.0 if pending[v] else 0.0
            for c in range(3):
                stepped[v, c] = V[v, c] + (s * d[v, c]) * on
        moved_to = _refused(V, stepped, F, pending, q_old, n_old, start, faces)
        changed = np.zeros(n, np.bool_)
        for v in range(n):
            changed[v] = not _same_place(moved_to, V, v)
            pending[v] = pending[v] and not changed[v]
        for f in range(m):
            if changed[F[f, 0]] or changed[F[f, 1]] or changed[F[f, 2]]:
                q_old[f] = face_quality(moved_to, F[f, 0], F[f, 1], F[f, 2])
                n_old[f, 0], n_old[f, 1], n_old[f, 2] = face_cross(moved_to, F, f)
        V = moved_to
    return V


@njit(cache=True)
def _face_states(V, F):
    """Each face's quality 2r/R (m,) and its (v1 - v0) x (v2 - v0) (m, 3)."""
    m = F.shape[0]
    q = np.empty(m)
    normals = np.empty((m, 3))
    for f in range(m):
        q[f] = face_quality(V, F[f, 0], F[f, 1], F[f, 2])
        normals[f, 0], normals[f, 1], normals[f, 2] = face_cross(V, F, f)
    return q, normals


@njit(cache=True)
def _same_place(A, B, v):
    """Whether vertex v has equal coordinates in A and B."""
    return A[v, 0] == B[v, 0] and A[v, 1] == B[v, 1] and A[v, 2] == B[v, 2]


@njit(cache=True)
def _corners_moved(V_old, V, F, f):
    """Whether a corner of face f differs between V_old and V."""
    return not (_same_place(V, V_old, F[f, 0]) and _same_place(V, V_old, F[f, 1]) and _same_place(V, V_old, F[f, 2]))


@njit(cache=True)
def _refused(V_old, V_new, F, moved, q_old, n_old, start, faces):
    """V_new with the moves taken back that lower the smallest quality around a moved vertex or flip a face,
    given the faces' states in V_old (:func:`_face_states`) and :func:`_vertex_faces`.

    A face whose corners are where they were has the quality q_old (-1 where its normal is zero,
    as a recomputation finds it). After the first pass only the vertices of the faces a
    put-back vertex touches are looked at again: every other vertex keeps its faces' qualities, and
    so its verdict (minima are exact, so the result is the same as re-testing every vertex each pass).
    """
    n, m = V_old.shape[0], F.shape[0]
    worst_old = np.full(n, np.inf)
    for f in range(m):
        for c in range(3):
            worst_old[F[f, c]] = _minimum(worst_old[F[f, c]], q_old[f])
    V = V_new.copy()
    moved = moved.copy()
    q = np.empty(m)
    worst = np.full(n, np.inf)
    for f in range(m):
        if _corners_moved(V_old, V, F, f):
            q[f] = _quality_or_flipped(V, F, f, n_old)
        else:
            q[f] = -1.0 if dot3((n_old[f, 0], n_old[f, 1], n_old[f, 2]), (n_old[f, 0], n_old[f, 1], n_old[f, 2])) <= 0 \
                else q_old[f]
        for c in range(3):
            worst[F[f, c]] = _minimum(worst[F[f, c]], q[f])
    check = np.flatnonzero(moved)  # the vertices whose verdict may be a put-back
    following = np.empty(n, np.int64)
    checked = check.shape[0]
    check = np.concatenate((check, np.empty(n - checked, np.int64)))
    back = np.zeros(n, np.bool_)
    face_stamp = np.zeros(m, np.int64)
    vertex_stamp = np.zeros(n, np.int64)
    for it in range(1, n + 1):
        anything = False
        for i in range(checked):
            v = check[i]
            back[v] = moved[v] and worst[v] < worst_old[v] - 1e-12
            anything = anything or back[v]
        if not anything:
            break
        undo_moves(V, V_old, moved, back)
        count = 0
        for i in range(checked):
            v = check[i]
            if not back[v]:
                continue
            back[v] = False
            for j in range(start[v], start[v + 1]):
                f = faces[j]
                if face_stamp[f] == it:
                    continue
                face_stamp[f] = it
                q[f] = _quality_or_flipped(V, F, f, n_old)
                for c in range(3):
                    u = F[f, c]
                    if vertex_stamp[u] != it:
                        vertex_stamp[u] = it
                        following[count] = u
                        count += 1
        for i in range(count):
            u = following[i]
            w = np.inf
            for j in range(start[u], start[u + 1]):
                w = _minimum(w, q[faces[j]])
            worst[u] = w
        check, following, checked = following, check, count
    return V


NO_COLLAPSE = -1  # :func:`best_collapse`'s status when it finds none


@njit(cache=True)
def _faces_with(F, v):
    """Indices of the faces with corner v, increasing."""
    out = np.empty(F.shape[0], np.int64)
    count = 0
    for f in range(F.shape[0]):
        if F[f, 0] == v or F[f, 1] == v or F[f, 2] == v:
            out[count] = f
            count += 1
    return out[:count]


@njit(cache=True)
def _split_by_corner(F, faces, u):
    """The faces of ``faces`` with corner u, and the others, each in the given order."""
    with_u, without = np.empty(len(faces), np.int64), np.empty(len(faces), np.int64)
    i = j = 0
    for g in faces:
        if F[g, 0] == u or F[g, 1] == u or F[g, 2] == u:
            with_u[i] = g
            i += 1
        else:
            without[j] = g
            j += 1
    return with_u[:i], without[:j]


@njit(cache=True)
def _corners_but(F, faces, a, b):
    """The distinct corners of ``faces`` other than a and b, increasing."""
    corners = np.empty(3 * len(faces), np.int64)
    count = 0
    for f in faces:
        for c in range(3):
            x = F[f, c]
            if x != a and x != b:
                corners[count] = x
                count += 1
    return np.unique(corners[:count])


@njit(cache=True)
def _same(a, b):
    """Whether two increasing arrays hold the same numbers."""
    if len(a) != len(b):
        return False
    for i in range(len(a)):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True)
def _common(a, b):
    """The numbers in both increasing arrays a and b, increasing."""
    out = np.empty(min(len(a), len(b)), np.int64)
    i = j = count = 0
    while i < len(a) and j < len(b):
        if a[i] == b[j]:
            out[count] = a[i]
            count += 1
            i += 1
            j += 1
        elif a[i] < b[j]:
            i += 1
        else:
            j += 1
    return out[:count]


@njit(cache=True)
def _nan_min(values):
    """np.min: NaN if any value is NaN (``values`` not empty)."""
    out = values[0]
    for x in values[1:]:
        out = _minimum(out, x)
    return out


@njit(cache=True)
def _is_fixed(fixed_keys, base, a, b):
    """Whether the edge (a, b) is one of the sorted keys min * base + max."""
    key = min(a, b) * base + max(a, b)
    i = np.searchsorted(fixed_keys, key)
    return i < len(fixed_keys) and fixed_keys[i] == key


@njit(cache=True)
def best_collapse(V, F, q, order, movable, fixed_keys, base, max_quality):
    """(status, v, u): the collapse of v into u that :func:`.tangential_smoothing.collapse_poor` makes.

    V (n, 3) float64; F (m, 3) int64 (valid indices); q (m,) the faces' qualities; order (m,)
    the faces by increasing quality (np.argsort(q)); movable (n,) bool; fixed_keys the sorted
    keys min * base + max of the fixed edges. status: 0 with the collapse, :data:`NO_COLLAPSE`
    when there is none.
    """
    for f in order:
        if q[f] >= max_quality:
            break
        found, best_q, best_v, best_u = False, 0.0, -1, -1
        for corner in range(3):
            v = F[f, corner]
            if not movable[v]:
                continue
            ring = _faces_with(F, v)
            nbrs = _corners_but(F, ring, v, v)
            old_min = _nan_min(q[ring])
            for u in nbrs:
                both, stay = _split_by_corner(F, ring, u)
                opposite = _corners_but(F, both, u, v)
                u_nbrs = _corners_but(F, _faces_with(F, u), u, u)
                if not _same(_common(nbrs, u_nbrs), opposite) or len(both) != 2:
                    continue
                refused = False
                for x in nbrs:
                    if x != u and not _is_member(opposite, x) and _is_fixed(fixed_keys, base, u, x):
                        refused = True
                        break
                if refused or len(stay) == 0:  # every face of v has u: all would go
                    continue
                G = np.empty((len(stay), 3), np.int64)
                for i in range(len(stay)):
                    for c in range(3):
                        G[i, c] = u if F[stay[i], c] == v else F[stay[i], c]
                for i in range(len(stay)):
                    n_old = face_cross(V, F, stay[i])
                    n_new = face_cross(V, G, i)
                    if dot3(n_new, n_old) <= 0:
                        refused = True
                        break
                if refused:
                    continue
                new_min = face_quality(V, G[0, 0], G[0, 1], G[0, 2])
                for i in range(1, len(stay)):
                    new_min = _minimum(new_min, face_quality(V, G[i, 0], G[i, 1], G[i, 2]))
                if new_min > old_min + 1e-9 and (not found or new_min > best_q):
                    found, best_q, best_v, best_u = True, new_min, v, u
        if found:
            return 0, best_v, best_u
    return NO_COLLAPSE, -1, -1


@njit(cache=True)
def _is_member(values, x):
    """Whether x is in the increasing array ``values``."""
    i = np.searchsorted(values, x)
    return i < len(values) and values[i] == x
