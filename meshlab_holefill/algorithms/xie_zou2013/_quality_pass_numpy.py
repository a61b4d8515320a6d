"""The quality pass of :mod:`.quality_pass` in numpy and Python sets, kept as the tests' reference.

:func:`.quality_pass.raise_min_quality_numpy` runs the rounds with :class:`_Patch`, whose
operations are those the module docstring of :mod:`.quality_pass` describes;
:func:`.quality_pass.raise_min_quality` runs the same rounds compiled
(:mod:`._quality_pass_ops`), with the same results.
"""
from __future__ import annotations

import numpy as np

from ...geometry.quality import cross_rows, face_normals, vertex_normals
from ...geometry.topology import edge_pair_set, vertex_face_runs
from ._quality_pass_kernels import star_candidate_scores
from .optimisation import compact_vertices

__all__ = ["TURN_COS", "BORDER_COS", "GAIN"]

TURN_COS = 0.5  # a changed triangle may turn by less than 60 degrees
BORDER_COS = np.cos(np.radians(150.0))  # and bend less than 150 degrees against the mesh across a loop edge
GAIN = 1e-6
_X_AXIS, _Y_AXIS = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])


def _quality(P):
    """2r/R of triangles given by corner arrays P (..., 3, 3) and their cross products; 0 if degenerate."""
    e0 = P[..., 1, :] - P[..., 0, :]
    e1 = P[..., 2, :] - P[..., 1, :]
    e2 = P[..., 0, :] - P[..., 2, :]
    a = np.sqrt((e1 * e1).sum(-1))
    b = np.sqrt((e2 * e2).sum(-1))
    c = np.sqrt((e0 * e0).sum(-1))
    cr = cross_rows(e0, -e2)
    area2 = (cr * cr).sum(-1) / 4.0
    den = (a + b + c) * a * b * c
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(den > 0, 16.0 * area2 / np.where(den > 0, den, 1.0), 0.0)
    return np.clip(q, 0.0, 1.0), cr


class _Patch:
    """Faces with incidence sets, for local edits (faces are replaced in place or killed)."""

    def __init__(self, V, F, k, forbidden_edges, border_normals, floor=0.4, blocked=frozenset()):
        self.floor = floor
        self.blocked = blocked
        self.V = np.array(V, np.float64)
        self.F = np.array(F, np.int64)
        self.k = k
        self.alive = np.ones(len(self.F), bool)
        faces, start = vertex_face_runs(self.F, len(self.V))
        faces, start = faces.tolist(), start.tolist()  # flat: ints, no row lists
        self.inc = [set(faces[start[v]:start[v + 1]]) for v in range(len(self.V))]
        self.forbidden = edge_pair_set(forbidden_edges)
        self.border = None if border_normals is None else np.asarray(border_normals, np.float64)

    # ------------------------------------------------------------------ queries
    def neighbours(self, v):
        return {int(x) for f in self.inc[v] for x in self.F[f] if x != v}

    def has_edge(self, a, b):
        return any(b in self.F[f] for f in self.inc[a])

    def edge_faces(self, a, b):
        return [f for f in self.inc[a] if b in self.F[f]]

    def border_ok(self, T, N):
        """Triangles T (s, 3) with unit normals N: those on a loop edge bend < 150 deg against the mesh."""
        if self.border is None:
            return True
        k = self.k
        for c in range(3):
            u, w = T[:, c], T[:, (c + 1) % 3]
            on = (u < k) & (w == (u + 1) % k)
            if on.any() and np.any(np.einsum("ij,ij->i", N[on], self.border[u[on]]) < BORDER_COS):
                return False
        return True

    def valid(self, T, P, ref):
        """New triangles T with corners P (s, 3, 3) against reference unit normals ref (s, 3)."""
        q, cr = _quality(P)
        length = np.linalg.norm(cr, axis=1)
        if np.any(length <= 0):
            return None
        N = cr / length[:, None]
        if np.any(np.einsum("ij,ij->i", N, ref) <= TURN_COS) or not self.border_ok(T, N):
            return None
        return q

    # ------------------------------------------------------------------ operations
    def try_swap(self, a, b):
        if a < self.k and b < self.k and (abs(a - b) == 1 or abs(a - b) == self.k - 1):
            return False
        fs = self.edge_faces(a, b)
        if len(fs) != 2:
            return False
        f1, f2 = fs
        t1, t2 = self.F[f1].tolist(), self.F[f2].tolist()
        # Orient: f1 holds a -> b.
        i = t1.index(a)
        if t1[(i + 1) % 3] != b:
            f1, f2, t1, t2 = f2, f1, t2, t1
            i = t1.index(a)
        c = t1[(i + 2) % 3]
        d = [x for x in t2 if x not in (a, b)][0]
        if c == d or self.has_edge(c, d) or tuple(sorted((c, d))) in self.forbidden:
            return False
        if self.blocked and (tuple(sorted((a, c, d))) in self.blocked or tuple(sorted((b, c, d))) in self.blocked):
            return False
        old = self.F[[f1, f2]]
        q_old = _quality(self.V[old])[0].min()
        T = np.array([(a, d, c), (b, c, d)])
        on = face_normals(self.V, old)
        ref = on.sum(axis=0)
        ref /= max(np.linalg.norm(ref), 1e-300)
        q = self.valid(T, self.V[T], np.repeat(ref[None], 2, axis=0))
        if q is None or q.min() <= q_old + GAIN:
            return False
        for f, tri in ((f1, T[0]), (f2, T[1])):
            for v in self.F[f]:
                self.inc[v].discard(f)
            self.F[f] = tri
            for v in tri:
                self.inc[v].add(f)
        return True

    def optimise_position(self, T, P, mask, ref, nv, x, h, objective, floor_min, steps=24):
        """Compass search in the tangent plane (normal nv) for the position of the corner ``mask`` of T.

        ``objective`` 'min': maximise the smallest quality of T; 'energy': minimise sum 1 / q
        (values the other triangles too). Candidates must keep every triangle within 60 degrees
        of ``ref`` and of ``nv``, pass the loop-edge test and keep the minimum >= ``floor_min``.

        Returns
        -------
        x : (3,) best position found, value : its objective (lower is better), qmin : its min quality
        """
        t1 = cross_rows(nv, _X_AXIS)
        if np.linalg.norm(t1) < 0.5:
            t1 = cross_rows(nv, _Y_AXIS)
        t1 /= np.linalg.norm(t1)
        t2 = cross_rows(nv, t1)
        ang = np.arange(8) * (np.pi / 4)
        D = np.cos(ang)[:, None] * t1 + np.sin(ang)[:, None] * t2

        k = self.k
        border_edges = any(np.any((T[:, c] < k) & (T[:, (c + 1) % 3] == (T[:, c] + 1) % k)) for c in range(3))

        # The corner of each triangle that moves (a triangle holds the vertex once; -1: not at all).
        corner = np.where(mask.any(axis=1), np.argmax(mask, axis=1), -1)
        P_c, ref_c, nv_c = np.ascontiguousarray(P, np.float64), np.ascontiguousarray(ref, np.float64), \
            np.ascontiguousarray(nv, np.float64)

        def score(X):
            # The numpy steps of this score, compiled in their order (see _quality_pass_kernels).
            val, qmin, N = star_candidate_scores(P_c, corner, np.ascontiguousarray(X, np.float64), ref_c, nv_c,
                                                 float(floor_min), float(self.floor), GAIN, TURN_COS,
                                                 objective == "energy")
            if self.border is not None and border_edges:
                # Only the best candidate matters: test it, the next if it fails, ...
                for j in np.argsort(val):
                    if not np.isfinite(val[j]) or self.border_ok(T, N[j]):
                        break
                    val[j] = np.inf
            return val, qmin

        val, qm = score(x[None])
        best, best_min = val[0], qm[0]
        h_min = 1e-2 * h
        for _ in range(steps):
            val, qm = score(x + h * D)
            j = int(np.argmin(val))
            if np.isfinite(val[j]) and val[j] < best - 1e-9 * (max(abs(best), 1.0) if np.isfinite(best) else 0.0):
                x, best, best_min = x + h * D[j], val[j], qm[j]
            else:
                h *= 0.5
                if h < h_min:
                    break
        return x, best, best_min

    def try_move(self, v, objective="min"):
        faces = np.fromiter(self.inc[v], np.int64)
        T = self.F[faces]
        P = self.V[T]
        q0, cr = _quality(P)
        current = q0.min()
        ref = cr / np.maximum(np.linalg.norm(cr, axis=1), 1e-300)[:, None]
        nv = cr.sum(axis=0)
        nv /= max(np.linalg.norm(nv), 1e-300)
        mask = T == v
        link = np.unique(T[~mask])
        h = 0.25 * np.mean(np.linalg.norm(self.V[link] - self.V[v], axis=1))
        x0 = self.V[v].copy()
        x, val1, qmin = self.optimise_position(T, P, mask, ref, nv, x0, h, objective, current)
        if qmin < self.floor:
            # Also from the link centroid (in the tangent plane).
            g = self.V[link].mean(axis=0) - x0
            g -= (g @ nv) * nv
            x2, val2, qmin2 = self.optimise_position(T, P, mask, ref, nv, x0 + g, h, objective, current)
            if np.isfinite(val2) and val2 < val1:
                x, qmin = x2, qmin2
        if qmin <= current + GAIN:
            return False
        self.V[v] = x
        return True

    def try_collapse(self, x, y):
        """Collapse edge (x, y), x free; y kept (moved to its best position when free)."""
        k = self.k
        if x < k:
            return False
        fs = self.edge_faces(x, y)
        if len(fs) != 2:
            return False
        nx, ny = self.neighbours(x), self.neighbours(y)
        opposite = {int(w) for f in fs for w in self.F[f] if w != x and w != y}
        if nx & ny != opposite:
            return False  # link condition
        if y < k and any(w < k and tuple(sorted((y, w))) in self.forbidden for w in nx if w != y):
            return False
        region = sorted((self.inc[x] | self.inc[y]) - set(fs))
        old = self.F[np.r_[region, fs]]
        q_old = _quality(self.V[old])[0].min()
        T = self.F[region].copy()
        T[T == x] = y
        ref = face_normals(self.V, self.F[region])
        ref_v = vertex_normals(self.V, old, len(self.V))[y]
        if not np.any(ref_v):
            return False
        mask = T == y
        best, best_q = None, q_old + GAIN
        starts = [self.V[y]] if y < k else [0.5 * (self.V[x] + self.V[y]), self.V[y], self.V[x]]
        for p in starts:
            W = self.V[T]
            W[mask] = p
            q = self.valid(T, W, ref)
            if q is None:
                continue
            cr = cross_rows(W[:, 1] - W[:, 0], W[:, 2] - W[:, 0])
            if np.any(cr @ ref_v <= TURN_COS * np.linalg.norm(cr, axis=1)):
                continue
            qmin = q.min()
            if y >= k:
                h = 0.25 * np.linalg.norm(self.V[x] - self.V[y])
                p, _, qmin = self.optimise_position(T, W, mask, ref, ref_v, p.copy(), h, "min", qmin)
            if qmin > best_q:
                best, best_q = p, qmin
        if best is None:
            return False
        self.V[y] = best
        for f in fs:
            self.alive[f] = False
            for v in self.F[f]:
                self.inc[v].discard(f)
        for f in list(self.inc[x]):
            self.F[f][self.F[f] == x] = y
            self.inc[y].add(f)
        self.inc[x] = set()
        return True

    def try_split(self, f):
        """Split the longest edge of face f (an interior edge) at a new free vertex, placed at its best."""
        T0 = self.F[f]
        P0 = self.V[T0]
        L = np.linalg.norm(P0[[1, 2, 0]] - P0, axis=1)  # edge (i, i+1)
        i = int(np.argmax(L))
        a, b = int(T0[i]), int(T0[(i + 1) % 3])
        k = self.k
        if a < k and b < k and (abs(a - b) == 1 or abs(a - b) == k - 1):
            return False
        fs = self.edge_faces(a, b)
        if len(fs) != 2:
            return False
        g = fs[1] if fs[0] == f else fs[0]
        c = int(T0[(i + 2) % 3])
        d = [int(x) for x in self.F[g] if x != a and x != b][0]
        if c == d:
            return False
        w = len(self.V)
        T = np.array([(a, w, c), (w, b, c), (b, w, d), (w, a, d)])
        old = self.F[[f, f, g, g]]
        ref = face_normals(self.V, old)
        if not np.all(np.any(ref != 0, axis=1)):
            return False
        nv = ref.sum(axis=0)
        nv /= max(np.linalg.norm(nv), 1e-300)
        q_old = _quality(self.V[self.F[[f, g]]])[0].min()
        x0 = 0.5 * (self.V[a] + self.V[b])
        Vx = np.vstack([self.V, x0])
        W = Vx[T]
        mask = T == w
        q = self.valid(T, W, ref)
        qmin = -1.0 if q is None else q.min()
        x, val, qmin = self.optimise_position(T, W, mask, ref, nv, x0.copy(), 0.25 * L[i], "min",
                                              max(qmin, 0.0) if q is not None else q_old)
        if not np.isfinite(val) or qmin <= q_old + GAIN:
            return False
        W[mask] = x
        if self.valid(T, W, ref) is None:
            return False
        self.V = np.vstack([self.V, x])
        self.inc.append(set())
        for v in (a, b, c, d):
            self.inc[v].discard(f)
            self.inc[v].discard(g)
        self.F[f], self.F[g] = T[0], T[2]
        n = len(self.F)
        self.F = np.vstack([self.F, T[[1, 3]]])
        self.alive = np.r_[self.alive, True, True]
        for face, tri in ((f, T[0]), (g, T[2]), (n, T[1]), (n + 1, T[3])):
            for v in tri:
                self.inc[v].add(face)
        return True

    def improve_round(self, order, split, keeps=None):
        """:func:`_improve_round` of this patch."""
        return _improve_round(self, order, self.k, self.floor, split, keeps)

    def snapshot(self):
        return self.V.copy(), self.F.copy(), self.alive.copy(), [set(faces) for faces in self.inc]

    def restore(self, state):
        self.V, self.F, self.alive, self.inc = state  # a snapshot is restored at most once

    def compact(self):
        used = np.zeros(len(self.V), bool)
        used[: self.k] = True
        F = self.F[self.alive]
        used[F.ravel()] = True
        return compact_vertices(self.V, F, used)


def _improve_round(p, order, k, floor, split, keeps=None):
    """One round of the pass over the poor faces ``order`` (worst first); counts of the operations kept.

    With ``keeps`` (a callable), an operation after which ``keeps()`` is false is undone.
    """
    done = {"swaps": 0, "moves": 0, "collapses": 0, "splits": 0}
    for f in order:
        if not p.alive[f]:
            continue
        state = p.snapshot() if keeps is not None else None
        kind = _improve_face(p, f, k, floor, split)
        if kind is None:
            continue
        if state is not None and not keeps():
            p.restore(state)
            continue
        done[kind] += 1
    return done


def _improve_face(p, f, k, floor, split):
    """The first operation that helps poor face f: 'swaps', 'moves', 'collapses', 'splits' or None."""
    tri = p.F[f].tolist()
    if _quality(p.V[p.F[f]])[0] >= floor:
        return None
    if any(p.try_swap(tri[i], tri[(i + 1) % 3]) for i in range(3)):
        return "swaps"
    moved = False
    for objective in ("energy", "min"):
        for v in tri:
            if v >= k and p.try_move(v, objective):
                moved = True
        if moved and _quality(p.V[p.F[f]])[0] >= floor:
            break
    if moved:
        return "moves"
    edges = [(tri[i], tri[(i + 1) % 3]) for i in range(3)]
    pairs = [(a, b) for a, b in edges if a >= k] + [(b, a) for a, b in edges if b >= k]
    if any(p.try_collapse(a, b) for a, b in pairs):
        return "collapses"
    if split and p.try_split(f):
        return "splits"
    return None
