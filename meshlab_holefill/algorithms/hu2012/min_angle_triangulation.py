"""Modified principle of minimum angle (Hu et al., Sec. III.B): the initial triangulation of a hole.

Boundary vertices get the angle of Eq. 2 (concave ones reflexed, from the oriented-triangle
normal against the vertex normal), and ears are cut at the vertex of smallest angle whose two
neighbours' normals agree within the threshold sigma. The LS-SVM filter's fallback uses the
same triangulation.
"""
from __future__ import annotations

import copy
import math

import numpy as np

from ...geometry.topology import edge_pair_set
from ...errors import HoleFillError
from . import _min_angle_kernels as K

__all__ = ["boundary_angles", "normal_angle_threshold", "min_angle_triangulation", "hole_plane_triangulation"]


def boundary_angles(P, normals):
    """Angle of each boundary vertex, with concave vertices reflexed (Sec. III.B, Eq. 2).

    With the loop in patch orientation, vertex i is convex when the normal of the oriented
    triangle (v_{i-1}, v_i, v_{i+1}) points the same way as the vertex normal (the paper's
    anticlockwise case); convex vertices get theta_i, concave ones 2 pi - theta_i.

    Parameters
    ----------
    P : (k, 3) float64  loop points in patch orientation
    normals : (k, 3) float64  vertex normals

    Returns
    -------
    angle : (k,) float64 in [0, 2 pi]
    convex : (k,) bool
    """
    prev, nxt = np.roll(P, 1, axis=0), np.roll(P, -1, axis=0)
    u, w = prev - P, nxt - P
    theta = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    n_t = np.cross(P - prev, nxt - prev)
    convex = np.einsum("ij,ij->i", n_t, normals) >= 0
    return np.where(convex, theta, 2 * np.pi - theta), convex


def normal_angle_threshold(normals):
    """Threshold sigma on the angle between neighbour normals (Sec. III.B).

    45 degrees when the largest angle between two boundary-vertex normals is below 55
    degrees, otherwise 85% of that largest angle.
    """
    N = np.asarray(normals, np.float64)
    largest = float(np.arccos(np.clip((N @ N.T).min(), -1.0, 1.0)))
    return np.radians(45.0) if largest < np.radians(55.0) else 0.85 * largest


def _vertex_angle(p_prev, p, p_next, normal):
    """Eq. 2 angle of one boundary vertex given its current neighbours (plain-float 3-sequences).

    Returns the angle and |u x w| (twice the ear's area).
    """
    u = (p_prev[0] - p[0], p_prev[1] - p[1], p_prev[2] - p[2])
    w = (p_next[0] - p[0], p_next[1] - p[1], p_next[2] - p[2])
    cross = _cross3(u, w)
    area2 = math.sqrt(cross[0] ** 2 + cross[1] ** 2 + cross[2] ** 2)
    theta = math.atan2(area2, u[0] * w[0] + u[1] * w[1] + u[2] * w[2])
    # n_t = (p - p_prev) x (p_next - p_prev) = w x u = -(u x w): convex when it agrees with the normal.
    convex = -(cross[0] * normal[0] + cross[1] * normal[1] + cross[2] * normal[2]) >= 0
    return (theta if convex else 2 * math.pi - theta), area2


def _cross3(a, b):
    """Cross product of two 3-vectors as a tuple (np.cross's overhead dominates at this size)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _in_sector(apex, normal, prev_point, next_point, target, margin=1e-9):
    """Scalar :func:`hole_guards.inside_hole_sector` for one target (plain floats: called once per ear).

    True when the segment apex -> target starts into the hole sector, swept counter-clockwise
    about the normal from the next boundary vertex to the previous one.
    """
    nl = max(math.sqrt(normal[0] ** 2 + normal[1] ** 2 + normal[2] ** 2), 1e-300)
    n = (normal[0] / nl, normal[1] / nl, normal[2] / nl)
    u = (next_point[0] - apex[0], next_point[1] - apex[1], next_point[2] - apex[2])
    un = u[0] * n[0] + u[1] * n[1] + u[2] * n[2]
    u = (u[0] - un * n[0], u[1] - un * n[1], u[2] - un * n[2])
    ul = max(math.sqrt(u[0] ** 2 + u[1] ** 2 + u[2] ** 2), 1e-300)
    u = (u[0] / ul, u[1] / ul, u[2] / ul)
    w = _cross3(n, u)

    def angle(p):
        d = (p[0] - apex[0], p[1] - apex[1], p[2] - apex[2])
        return math.atan2(d[0] * w[0] + d[1] * w[1] + d[2] * w[2], d[0] * u[0] + d[1] * u[1] + d[2] * u[2]) % (2 * math.pi)

    phi = angle(target)
    return margin < phi < angle(prev_point) - margin


def _ear_holds_a_vertex(P, p, v, n, others):
    """True when a boundary vertex of ``others`` lies in the ear triangle (p, v, n) or on its new edge.

    The test is made in the ear's plane, for vertices within half the ear's longest edge of
    that plane: the classic ear condition, which the paper's angle rule takes for granted.
    """
    A, B, C = P[p], P[v], P[n]
    nt = np.array(_cross3(B - A, C - A))
    area2 = math.sqrt(nt @ nt)
    if area2 == 0 or len(others) == 0:
        return False
    nt = nt / area2
    reach = 0.5 * math.sqrt(max((B - A) @ (B - A), (C - B) @ (C - B), (A - C) @ (A - C)))
    Q = P[others]
    height = (Q - A) @ nt
    near = np.abs(height) <= reach
    if not near.any():
        return False
    Q = Q[near] - np.outer(height[near], nt)
    # Barycentric signs: inside or on the boundary of the triangle (tolerance relative to its size).
    # (x - X) . ((Y - X) x nt) is the signed area of (X, Y, x) about nt, for each side X -> Y.
    tol = -1e-9
    inside = np.ones(len(Q), bool)
    for X, Y in ((B, C), (C, A), (A, B)):
        m = np.array(_cross3(nt, Y - X))  # points into the triangle, |m| = |Y - X|
        inside &= (Q - X) @ m / area2 >= tol
    return bool(inside.any())


def min_angle_triangulation(P, normals, forbidden_edges=()):
    """Modified principle of minimum angle (Sec. III.B, Steps 1-3).

    Repeatedly take the vertex v of smallest angle (Eq. 2) whose two loop neighbours'
    normals make an angle alpha <= sigma (:func:`normal_angle_threshold`), add the oriented
    triangle (v1, v, v2) and remove v, until three vertices remain, which form the last
    triangle (Step 3). When no vertex passes the normal test the smallest-angle vertex is
    used (the paper leaves this case open). An ear is never cut when its new edge (v1, v2)
    already exists in the mesh (``forbidden_edges``) or its area is zero; ears whose new
    edge leaves v1 or v2 outside the hole (:func:`inside_hole_sector`, about the vertex
    normal) or whose triangle holds another boundary vertex (:func:`_ear_holds_a_vertex`)
    are cut only when no other ear is left. Where this greedy order leaves no valid ear, the
    ear order is searched by backtracking (:func:`_search_ears`; the paper leaves this case open).

    After a cut only the ears within two positions of the removed vertex change, so each
    step costs O(1) updates plus one arg-min over the remaining vertices.

    Parameters
    ----------
    P : (k, 3) float64  loop points, patch orientation
    normals : (k, 3) float64
    forbidden_edges : (p, 2) int  loop-index pairs that must not become edges

    Returns
    -------
    F : (k - 2, 3) int64  faces in loop indices, oriented like the loop
    """
    if len(P) < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    faces, status = _compiled_faces(P, normals, forbidden_edges)
    if status == K.OK:
        return faces
    return min_angle_triangulation_python(P, normals, forbidden_edges)  # undecided comparison, or an error


def _compiled_faces(P, normals, forbidden_edges):
    """The compiled loop (:func:`._min_angle_kernels.min_angle_faces`) on the inputs of :class:`_Ears`."""
    P = np.ascontiguousarray(P, np.float64)
    N = np.ascontiguousarray(normals, np.float64)
    k = len(P)
    E = np.sort(np.asarray(forbidden_edges, np.int64).reshape(-1, 2), axis=1)
    E = E[(E[:, 0] >= 0) & (E[:, 1] < k)]  # other pairs never match an ear's loop-index pair
    keys = np.unique(E[:, 0] * k + E[:, 1])
    area_tol = 1e-14 * float(np.ptp(P, axis=0).max()) ** 2
    return K.min_angle_faces(P, N, float(np.cos(normal_angle_threshold(N))), keys, area_tol, 2.0)


STUCK_CUTS_PER_VERTEX = 20  # the search after a stuck greedy run cuts at most this many ears per loop vertex


def min_angle_triangulation_python(P, normals, forbidden_edges=()):
    """:func:`min_angle_triangulation` in Python (:class:`_Ears`), the reference of the compiled loop.

    When the greedy order leaves no valid ear (or a last triangle on a mesh edge), the
    triangulation is searched by backtracking (:func:`_search_ears`).
    """
    if len(P) < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    try:
        return greedy_ear_faces(P, normals, forbidden_edges)
    except HoleFillError as stuck:
        faces = _search_ears(_Ears(P, normals, forbidden_edges), STUCK_CUTS_PER_VERTEX * len(P))
        if faces is None:
            raise stuck
        return np.asarray(faces, np.int64)


def greedy_ear_faces(P, normals, forbidden_edges=()):
    """Steps 1-3 of Sec. III.B exactly (:class:`_Ears`), the reference of the compiled loop: raises
    HoleFillError where the greedy order leaves no valid ear."""
    if len(P) < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    ears = _Ears(P, normals, forbidden_edges)
    faces = []
    for _ in range(len(P) - 3):
        faces.append(ears.cut(ears.pick()))
    faces.append(ears.last_triangle())
    return np.asarray(faces, np.int64)


def _search_ears(ears, budget):
    """The first ear order, depth first in :meth:`_Ears.ranked` order, that closes the loop with
    triangles of non-zero area; None when there is none within ``budget`` cuts.

    Not in the paper, which does not say what to do when no ear is left. The greedy order can
    cut a loop down to vertices on one line: at the corner of a CAD part's box, where the
    border runs straight along two creases into the corner, the last ears are all flat or
    would duplicate a mesh edge, while cutting a few ears in another order closes the hole.
    The search starts with the greedy order (each step's first-ranked ear) and changes the
    latest steps first. Only loops the greedy order cannot close get here: every other
    triangulation is the paper's.
    """
    stack = [(ears, [], ears.ranked())]  # one entry per cut made: the state, the faces so far, the ears left to try
    while stack:
        ears, faces, untried = stack[-1]
        if int(ears.active.sum()) == 3:
            stack.pop()
            try:
                last = ears.last_triangle()
            except HoleFillError:
                continue
            if ears.has_area(last):
                return faces + [last]
            continue
        v = next(untried, None)
        if v is None or budget <= 0:
            stack.pop()
            continue
        budget -= 1
        child = ears.copy()
        stack.append((child, faces + [child.cut(v)], child.ranked()))
    return None


class _Ears:
    """The shrinking loop of :func:`min_angle_triangulation` and the state of its ears (Sec. III.B).

    Ear v is the triangle (prv[v], v, nxt[v]); ``angle`` (Eq. 2), ``cuttable`` (non-degenerate,
    new edge not already in the mesh) and ``normals_agree`` (the normal test alpha <= sigma)
    are kept per vertex and re-evaluated for the ears a cut changes. Coordinates are also kept
    as plain floats: the scalar per-ear tests are cheaper on them than on numpy rows.
    """

    def __init__(self, P, normals, forbidden_edges):
        k = len(P)
        self.P = np.asarray(P, np.float64)
        self.N = np.asarray(normals, np.float64)
        self.cos_sigma = np.cos(normal_angle_threshold(self.N))
        self.forbidden = edge_pair_set(forbidden_edges)
        self.Pl, self.Nl = self.P.tolist(), self.N.tolist()
        self.prv = [(i - 1) % k for i in range(k)]
        self.nxt = [(i + 1) % k for i in range(k)]
        self.active = np.ones(k, bool)
        self.angle = np.full(k, np.inf)
        self.cuttable = np.zeros(k, bool)
        self.normals_agree = np.zeros(k, bool)
        self.verdict = {}  # cached proper-ear test, dropped when the ear changes
        self.area_tol = 1e-14 * float(np.ptp(self.P, axis=0).max()) ** 2
        for v in range(k):
            self.evaluate(v)

    def evaluate(self, v):
        """Angle (Eq. 2), cuttability and normal test of ear v with its current neighbours."""
        p, n = self.prv[v], self.nxt[v]
        self.angle[v], area2 = _vertex_angle(self.Pl[p], self.Pl[v], self.Pl[n], self.Nl[v])
        self.cuttable[v] = area2 > self.area_tol and (min(p, n), max(p, n)) not in self.forbidden
        self.normals_agree[v] = self.N[p] @ self.N[n] >= self.cos_sigma
        self.verdict.pop(v, None)

    def proper(self, v):
        """Ear v keeps its new edge inside the hole at both ends and holds no other boundary vertex.

        Removing other vertices can only unblock an ear, so a cached False stays safe.
        """
        if v not in self.verdict:
            Pl, Nl, prv, nxt = self.Pl, self.Nl, self.prv, self.nxt
            p, n = prv[v], nxt[v]
            ok = (_in_sector(Pl[p], Nl[p], Pl[prv[p]], Pl[v], Pl[n])
                  and _in_sector(Pl[n], Nl[n], Pl[v], Pl[nxt[n]], Pl[p]))
            if ok:
                others = np.flatnonzero(self.active)
                others = others[(others != p) & (others != v) & (others != n)]
                ok = not _ear_holds_a_vertex(self.P, p, v, n, others)
            self.verdict[v] = ok
        return self.verdict[v]

    def pick(self):
        """Step 1-2: the smallest-angle proper ear passing the normal test, else any proper cuttable
        ear, else the smallest-angle cuttable one."""
        for tier in (self.active & self.cuttable & self.normals_agree, self.active & self.cuttable):
            candidates = np.flatnonzero(tier)
            for v in candidates[np.argsort(self.angle[candidates], kind="stable")].tolist():
                if self.proper(v):
                    return v
        candidates = np.flatnonzero(self.active & self.cuttable)
        if len(candidates) == 0:
            raise HoleFillError("no valid ear left in the minimum-angle triangulation")
        return int(candidates[np.argmin(self.angle[candidates])])

    def has_area(self, face):
        """Whether the triangle ``face`` (loop indices) has more than the ears' zero-area tolerance."""
        a, b, c = (self.P[i] for i in face)
        n = np.array(_cross3(b - a, c - a))
        return math.sqrt(n @ n) > self.area_tol

    def ranked(self):
        """Every ear :meth:`pick` could take, in its order of preference (the first is its choice), lazily."""
        seen = set()
        for tier in (self.active & self.cuttable & self.normals_agree, self.active & self.cuttable):
            candidates = np.flatnonzero(tier)
            for v in candidates[np.argsort(self.angle[candidates], kind="stable")].tolist():
                if v not in seen and self.proper(v):
                    seen.add(v)
                    yield v
        candidates = np.flatnonzero(self.active & self.cuttable)
        for v in candidates[np.argsort(self.angle[candidates], kind="stable")].tolist():
            if v not in seen:
                seen.add(v)
                yield v

    def copy(self):
        """An independent copy of the loop's state (the search's backtracking point)."""
        other = copy.copy(self)
        other.prv, other.nxt, other.verdict = list(self.prv), list(self.nxt), dict(self.verdict)
        for name in ("active", "angle", "cuttable", "normals_agree"):
            setattr(other, name, getattr(self, name).copy())
        return other

    def cut(self, v):
        """Add the ear triangle (v1, v, v2), remove v from the loop, re-evaluate the ears it changes."""
        p, n = self.prv[v], self.nxt[v]
        self.nxt[p], self.prv[n] = n, p
        self.active[v] = False
        for u in {self.prv[p], p, n, self.nxt[n]}:
            self.evaluate(u)
        return (p, v, n)

    def last_triangle(self):
        """Step 3: the three vertices left form the last triangle."""
        a = int(np.flatnonzero(self.active)[0])
        b, c = self.nxt[a], self.nxt[self.nxt[a]]
        if any(tuple(sorted(e)) in self.forbidden for e in ((a, b), (b, c), (c, a))):
            raise HoleFillError("the last triangle would duplicate an existing edge")
        return (a, b, c)


def hole_plane_triangulation(P, forbidden_edges=()):
    """Sec. III.B's triangulation with every vertex normal replaced by the loop's own normal (beyond the paper).

    Eq. 2 tells convex from concave boundary vertices by the vertex normals of the mesh. Where
    the mesh stands on the hole's plane (a model cut across, its walls meeting the cut at right
    angles), those normals lie in that plane, orthogonal to every ear's normal, and the test
    decides by noise: the triangulation folds over itself (bone.ply cut at 40 % of its height,
    85 edges: 67 pairs of its triangles cross) or through the walls (cow.obj at 20 % along x).
    About the loop's vector-area normal the same procedure is ear cutting in the hole's plane.

    Parameters
    ----------
    P : (k, 3) float64  loop points, patch orientation
    forbidden_edges : (p, 2) int

    Returns
    -------
    F : (k - 2, 3) int64
    """
    P = np.asarray(P, np.float64)
    n = np.cross(P - P[0], np.roll(P, -1, axis=0) - P[0]).sum(axis=0)
    length = np.linalg.norm(n)
    if not length > 0:
        raise HoleFillError("the hole's loop encloses no area: it has no plane")
    return min_angle_triangulation(P, np.tile(n / length, (len(P), 1)), forbidden_edges)
