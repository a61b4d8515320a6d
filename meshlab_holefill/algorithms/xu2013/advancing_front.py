"""Advancing-front triangulation of a closed 3D polygon (a hole boundary).

The advancing front mesh technique of Zhao, Gao and Lin (2007) as used by Xu, Li and Tan
(2013, Sec. 3.2, Fig. 3): the front starts as the hole boundary (Step 1); at the front
vertex v with the smallest front angle theta (Step 2) triangles are created in the plane of
its two front edges (Step 3):

* theta <= 75 degrees: one triangle joining v's two front neighbours;
* 75 < theta <= 135 degrees: one new vertex on the bisector, two triangles;
* theta > 135 degrees: two new vertices trisecting the angle, three triangles.

A new vertex closer than ``merge_factor`` times the target edge length to another vertex of
the same front is merged with it (Step 4): with one of v's two neighbours the step falls back
to the rule with one vertex less, with any other vertex the front is split in two there. The
front is updated (Step 5) and the steps repeat until every front is closed (Step 6). Fronts
are cyclic linked lists of nodes (a vertex may be on two fronts after a split); a heap keeps
the angles (:class:`._front_state.FrontState`).

What the paper leaves open, as chosen here:

* **Edge length.** New vertices lie at a target length from v: a sizing value carried by
  every vertex, at a boundary vertex the mean length of its two boundary edges, at a new
  vertex the mean of v's and its neighbours'. (With the current front edges' lengths instead
  the mesh shrinks ring by ring: the rules never remove vertices from a convex front.)
* **Merge threshold.** 0.75 target lengths (see :func:`advancing_front_triangulation`). A
  merge with the vertex beyond p (or q) makes the triangle at p an ear holding p's whole
  front angle; like rule 1 it is then allowed only for angles a single triangle fits
  (``MERGE_EAR_MAX``, 120 degrees), otherwise the step falls back to the next rule.
* **Which side is inside.** The front angle is measured counter-clockwise about the normal
  of the edges' plane oriented like a reference normal (reflex when they disagree). The
  reference normal of a boundary vertex is given (default: the hole's unit vector area), a
  new vertex gets the mean of v's and its neighbours'. Where the edges' plane is unreliable
  (edges nearly collinear, or the plane more than 30 degrees from the reference normal, as on
  noisy boundaries where following it lets the front climb out of the hole) the angle is
  measured, and new vertices placed, in the plane orthogonal to the reference normal.

Beyond the paper (it has no safeguards), every step is checked before it is applied, so the
front never crosses itself: the new triangles may reuse an existing edge only to consume it
from the front, must face the way of the angle's plane and not fold back over the triangle
behind a consumed edge, every new edge must leave its existing front vertices strictly
inside their front angle, and no new edge may cross a nearby front edge (in the plane of the
angle). With ``obstacles`` (the mesh around the hole) no new triangle may cross a mesh face
and no new vertex may come within 0.35 target lengths of one. A rejected step is retried
with the next rule down (three triangles -> two -> one) and then at the vertex with the next
smallest angle; a front of at most 6 vertices on which every step is refused is closed by a
fan. The run stops with :class:`HoleFillError` when no step is possible, when the fronts grow
past 1.3 times the boundary's vertex count plus 20 (the front has left the hole: it runs over
the surrounding surface or out of a hole wrapped around a tube), or past a bound on the
triangle count: it always ends.

The checks and the merge-target search run as numba kernels (:mod:`._front_kernels`) over
array mirrors of the front; the bookkeeping (heap, linked lists, edge sets) stays in Python.
"""
from __future__ import annotations

import heapq
import math

import numpy as np

from ...errors import HoleFillError
from ._front_kernels import merge_target, near_any, step_geometry_valid
from ._front_obstacles import FrontObstacles
from ._front_state import FrontState
from ._front_predicates import cross, dot, norm, scaled, sub, unit

__all__ = ["advancing_front_triangulation"]

ONE_TRIANGLE_MAX = math.radians(75.0)
TWO_TRIANGLES_MAX = math.radians(135.0)
# Falling back to the single triangle (p, v, q) is allowed only below this angle (quality).
FALLBACK_ONE_TRIANGLE_MAX = math.radians(150.0)
# New edges must leave an existing front vertex this far inside its front angle (radians).
ANGLE_MARGIN = math.radians(2.0)
# A new triangle may not fold over the triangle behind a front edge it consumes by more than
# 120 degrees (cosine of the angle between their normals below -0.5).
FOLD_MIN_COS = -0.5
# A merge (Step 4) that turns the triangle at v's neighbour p into an ear (p's two front edges
# and the chord joining their ends) is refused when p's front angle exceeds this: the ear keeps
# p's whole angle, and above ~133 degrees no triangle reaches quality 0.3. 120 degrees (best
# quality 0.46) still lets rule 2 close a square by merging with its opposite corner.
MERGE_EAR_MAX = math.radians(120.0)
# A front of a disk-like hole shrinks; one that grows past this many times the boundary's
# vertex count has run out of the hole (over the surrounding surface).
FRONT_GROWTH_LIMIT = 1.3
# A new vertex must keep this fraction of its target edge length away from the surrounding
# mesh: closer, the front is running over the existing surface instead of across the hole.
HOVER_FACTOR = 0.35
# The exponent of the compiled kernels' squares, passed at run time (see _front_kernels).
TWO = 2.0
_NO_NORMAL = (math.nan, math.nan, math.nan)  # no known triangle behind a front edge


class _AdvancingFront(FrontState):
    """One advancing-front run: Steps 2-4 and 6 on a :class:`FrontState`; see :func:`advancing_front_triangulation`."""

    def __init__(self, points, reference_normal, forbidden_edges, merge_factor, max_faces, obstacles=None,
                 merge_ear_max=None):
        super().__init__(points, reference_normal, forbidden_edges)
        self.merge_factor = merge_factor
        self.merge_ear_max = MERGE_EAR_MAX if merge_ear_max is None else merge_ear_max
        self.max_faces = max_faces
        self._set_obstacles(obstacles)
        # Bounds of the reach of one step's checks (_release_blocked_near): new vertices take
        # the mean sizing value of three vertices, so no S exceeds the loop's largest.
        self.S_max = max(self.S)
        self.max_edge = self.longest_edge
        for i in range(self.k):
            self._update_node(i)

    # ----------------------------------------------------------------- main loop
    def run(self):
        limit = FRONT_GROWTH_LIMIT * self.k + 20
        while self.front_size:
            if len(self.faces) > self.max_faces:
                raise HoleFillError(f"advancing front did not close within {self.max_faces} triangles")
            size = sum(self.front_size.values())
            self.stats["max_front"] = max(self.stats.get("max_front", 0), size)
            if size > limit:
                raise HoleFillError(f"advancing front grew to {size} vertices from {self.k}: it left the hole")
            node = self._pop()
            if node is None:
                if self._close_small_front():
                    continue
                raise HoleFillError("advancing front is stuck: no valid triangle can be added "
                                    f"({sum(self.front_size.values())} front vertices left)")
            n_faces, n_topology = len(self.faces), self.stats["merges"] + self.stats["splits"]
            if self._advance(node):
                self.stats["steps"] += 1
                if self.stats["merges"] + self.stats["splits"] != n_topology:
                    self._release_blocked()  # a split relabels a whole front: any refusal may change
                else:
                    self._release_blocked_near(self.faces[n_faces:])
            else:
                self.stats["rejected"] += 1
                self.blocked.append(node)
        F = np.asarray(self.faces, np.int64).reshape(-1, 3)
        return np.asarray(self.P[self.k:], np.float64).reshape(-1, 3), F

    def _release_blocked_near(self, new_faces):
        """Put back on the heap the refused nodes that the step which made ``new_faces`` may unblock.

        The checks of a step at node B (:meth:`_build`, :meth:`_valid`) read the front only
        near B's vertex: its candidate triangles reach max(longest front edge, (1 +
        merge_factor) S_max), the crossing test one loop edge further, the front-angle and
        merge-ear tests the nodes up to three front edges along. A step whose triangles have no
        vertex within that reach leaves B's verdict as it was, so B stays refused, and the steps
        taken are those of releasing every refused node after each step (which made failing
        runs on large holes quadratic: every step retried every refused node). Splits relabel
        whole fronts and release them all.
        """
        verts = {x for f in new_faces for x in f}
        P = self.P
        for a, b, c in new_faces:
            for x, y in ((a, b), (b, c), (c, a)):
                self.max_edge = max(self.max_edge, norm(sub(P[x], P[y])))
        reach = 3.0 * self.max_edge + (1.0 + self.merge_factor) * self.S_max + self.longest_edge
        r2 = reach * reach
        still = []
        if self.blocked:
            near = near_any(np.array(self.blocked, np.int64), self.Pa[sorted(verts)], r2, self.Pa, self.na_vertex,
                            self.na_alive, TWO)
            for b, hit in zip(self.blocked, near.tolist()):
                if hit > 0:
                    heapq.heappush(self.heap, (self.node_theta[b], b, self.node_version[b]))
                elif hit == 0:
                    still.append(b)
        self.stats["kept_blocked"] = self.stats.get("kept_blocked", 0) + len(still)
        self.blocked = still

    def _close_small_front(self):
        """Last resort when every step is rejected: close a front of at most 6 vertices by a fan.

        On very noisy boundaries the front angles of a tiny remaining front can be
        inconsistent (each measured in its own plane), so that no single step passes the
        angle checks although the front bounds a small disk. The first fan (from each
        vertex in turn) whose triangles reuse no edge and face the way of the hole is used.
        """
        for label, size in sorted(self.front_size.items(), key=lambda item: item[1]):
            if size > 6:
                return False
            start = next(i for i, alive in enumerate(self.node_alive)
                         if alive and self.node_front[i] == label)
            cycle = [start]
            while self.node_next[cycle[-1]] != start:
                cycle.append(self.node_next[cycle[-1]])
            verts = [self.node_vertex[i] for i in cycle]
            for shift in range(size):
                ring = verts[shift:] + verts[:shift]
                fan = [(ring[0], ring[j], ring[j + 1]) for j in range(1, size - 1)]
                chords = [(ring[0], ring[j]) for j in range(2, size - 1)]
                if any((min(a, b), max(a, b)) in self.edges for a, b in chords):
                    continue
                if any(dot(cross(sub(self.P[b], self.P[a]), sub(self.P[c], self.P[a])), self.N[a]) <= 0.0
                       for a, b, c in fan):
                    continue
                for f in fan:
                    self.faces.append(f)
                    self.edges.update((min(x, y), max(x, y)) for x, y in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])))
                for a, b in zip(ring, ring[1:] + ring[:1]):
                    self.front_edges.pop((a, b), None)
                for i in cycle:
                    self._kill_node(i)
                del self.front_size[label]
                self.stats["fan_closures"] = self.stats.get("fan_closures", 0) + 1
                self._release_blocked()
                return True
        return False

    def _advance(self, node):
        """Apply the angle rule at ``node`` (Sec. 3.2, Step 3) or its first valid fallback."""
        theta = self.node_theta[node]
        if self.front_size[self.node_front[node]] == 3 or theta <= ONE_TRIANGLE_MAX:
            rules = (1,)
        elif theta <= TWO_TRIANGLES_MAX:
            rules = (2, 1)
        elif theta <= FALLBACK_ONE_TRIANGLE_MAX:
            rules = (3, 2, 1)
        else:
            rules = (3, 2)
        for rule in rules:
            op = self._build(node, rule)
            if op is not None and self._valid(node, *op):
                self._apply(node, rule, *op)
                return True
        return False

    # ----------------------------------------------------------------- one step
    def _build(self, node, rule):
        """Triangles of one rule at ``node`` (Sec. 3.2, Fig. 3) with merged vertices (Step 4).

        Returns (faces, new_positions, sequence) or None when a new vertex falls next to
        one of v's neighbours (the caller then tries the rule with one vertex less). Faces
        use vertex ids, new vertices get temporary ids -1, -2; ``sequence`` replaces v
        between p and q on the front.
        """
        v = self.node_vertex[node]
        p = self.node_vertex[self.node_prev[node]]
        q = self.node_vertex[self.node_next[node]]
        if rule == 1:
            return [(p, v, q)], {}, []
        theta, m = self.node_theta[node], self.node_plane[node]
        V = self.P[v]
        length = (self.S[v] + self.S[p] + self.S[q]) / 3.0
        a = sub(self.P[q], V)
        ua = unit(sub(a, scaled(m, dot(a, m))))
        ut = cross(m, ua)
        count = rule - 1
        radius = self.merge_factor * length
        ids, new_pos = [], {}
        for j in range(1, count + 1):
            phi = theta * j / (count + 1)
            c, s = math.cos(phi) * length, math.sin(phi) * length
            pos = (V[0] + c * ua[0] + s * ut[0], V[1] + c * ua[1] + s * ut[1], V[2] + c * ua[2] + s * ut[2])
            for u in (p, q):
                if sum((pos[i] - self.P[u][i]) ** 2 for i in range(3)) < radius * radius:
                    return None
            target = merge_target(np.array(pos), radius, v, p, q, self.node_front[node], self.Pa, self.na_vertex,
                                  self.na_front, self.alive, self.n_alive, self.cell, TWO)
            if target < 0:
                target = -j
                new_pos[target] = pos
            ids.append(target)
        # A merge with the vertex beyond p (or q) makes the triangle at p (or q) an ear that
        # closes p's whole front angle: allowed only where a single triangle fits the angle.
        prev2 = self.node_vertex[self.node_prev[self.node_prev[node]]]
        next2 = self.node_vertex[self.node_next[self.node_next[node]]]
        if self.merge_ear_max is not None:
            if ids[-1] == prev2 and self.node_theta[self.node_prev[node]] > self.merge_ear_max:
                return None
            if ids[0] == next2 and self.node_theta[self.node_next[node]] > self.merge_ear_max:
                return None
        if rule == 2:
            w = ids[0]
            return [(v, q, w), (p, v, w)], new_pos, [w]
        w1, w2 = ids
        if w1 == w2:
            return None
        return [(v, q, w1), (v, w1, w2), (p, v, w2)], new_pos, [w2, w1]

    def _pos(self, x, new_pos):
        return new_pos[x] if x < 0 else self.P[x]

    def _valid(self, node, faces, new_pos, sequence):
        """Topological and geometric checks of one step (see module docstring)."""
        m = self.node_plane[node]
        label = self.node_front[node]
        directed = []
        for a, b, c in faces:
            directed += [(a, b), (b, c), (c, a)]
        dset = set(directed)
        if len(dset) != len(directed):
            return False
        new_edges = []
        for a, b in directed:
            if (a, b) in self.front_edges:
                continue
            if a >= 0 and b >= 0 and (min(a, b), max(a, b)) in self.edges:
                return False
            if (b, a) in dset and a > b:
                continue  # interior edge of the step, kept once
            new_edges.append((a, b))
        v = self.node_vertex[node]
        scale = self.S[v]
        # The node of each existing end of a new edge, on this front (a new edge must leave
        # from inside its front angle there).
        edge_nodes = []
        for a, b in new_edges:
            ends = [-1, -1]
            for j, x in enumerate((a, b)):
                if x >= 0:
                    ends[j] = self._same_front_node(x, label)
                    if ends[j] < 0:
                        return False
            edge_nodes.append(ends)
        positions = np.empty((2, 3))
        for temp, pos in new_pos.items():
            positions[-temp - 1] = pos
        behind = [[self.front_edges.get(e) or _NO_NORMAL for e in ((a, b), (b, c), (c, a))] for a, b, c in faces]
        if not step_geometry_valid(
                np.array(faces, np.int64), positions, np.array(behind), self.na_plane[node], 1e-10 * scale * scale,
                FOLD_MIN_COS, np.array(new_edges, np.int64).reshape(-1, 2), np.array(edge_nodes, np.int64).reshape(-1, 2),
                ANGLE_MARGIN, self.Pa[v], self.longest_edge, self.Pa, self.na_vertex, self.na_next, self.na_plane,
                self.na_theta, self.alive, self.n_alive, self.cell, TWO):
            return False
        if self.obstacles is None:
            return True
        v = self.node_vertex[node]
        clearance = HOVER_FACTOR * self.S[v]
        for pos in new_pos.values():
            if self.obstacles.distance(pos, clearance) < clearance:
                return False
        return not self.obstacles.crossed(faces, [[self._pos(x, new_pos) for x in f] for f in faces])

    def _set_obstacles(self, obstacles):
        """Index the surrounding mesh; its border faces are the triangles behind the boundary edges."""
        self.obstacles = None
        if obstacles is None or len(np.asarray(obstacles[1]).reshape(-1, 3)) == 0:
            return
        self.obstacles = FrontObstacles(obstacles[0], obstacles[1], self.cell, self.k)
        OV, k = self.obstacles.V, self.k
        for f in self.obstacles.border_faces().tolist():
            for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
                if (b, a) in self.front_edges and a < k and b < k:
                    c = cross(sub(OV[f[1]], OV[f[0]]), sub(OV[f[2]], OV[f[0]]))
                    self.front_edges[(b, a)] = unit(tuple(map(float, c)))


def advancing_front_triangulation(points, forbidden_edges=(), merge_factor=0.75, max_faces=None,
                                  reference_normal=None, obstacles=None, merge_ear_max=MERGE_EAR_MAX):
    """Triangulate a hole by the advancing front method (Xu et al. 2013, Sec. 3.2).

    Parameters
    ----------
    points : (k, 3) float64
        Boundary polygon in patch orientation (see :mod:`meshlab_holefill.core.holes`).
    forbidden_edges : (p, 2) int
        Pairs of boundary vertices that must not be joined (already joined by the mesh).
    merge_factor : float
        A new vertex closer than ``merge_factor`` times the target edge length to a vertex of
        the same front is merged with it (Sec. 3.2, Step 4). The paper gives no value; 0.75
        keeps every new front edge at least 3/4 of the target length, which holds the
        patch's density to that of the boundary (with 0.5 a round hole gets ~1.4 times the
        triangles of an equilateral mesh of the boundary's edge length, with 0.75 ~1.1 times)
        and raises the mean triangle quality.
    max_faces : int, optional
        Bound on the number of triangles before giving up; default 20 times the estimate
        from the boundary's vector area and mean edge length, plus 10 k + 100.
    reference_normal : (3,) or (k, 3) float64, optional
        Reference normal(s) at the boundary vertices: they orient the front angles (convex or
        reflex) and give their plane where the plane of the two front edges is unreliable.
        Default: the boundary's unit vector area, which points to the side the patch will face.
        (:mod:`meshlab_holefill.algorithms.xu2013.poisson_patch` passes each vertex's surface
        normal plus that mean normal.)
    obstacles : ((n, 3) float64, (m, 3) int), optional
        Surrounding mesh (vertices with the boundary first, as in a HoleContext, and faces):
        a step whose triangles would intersect one of these faces is rejected, so the
        patch goes around folds of the surface next to the hole.

    Returns
    -------
    new_vertices : (p, 3) float64
    faces : (q, 3) int64
        Indices into ``concatenate([points, new_vertices])``, oriented like the boundary.
    stats : dict
        ``steps``, ``rule1``, ``rule2``, ``rule3``, ``merges``, ``splits``, ``rejected``
        (and ``fan_closures`` when the last resort was used, ``kept_blocked`` when refused
        nodes were left out of a retry because the step was beyond their reach).

    Raises
    ------
    HoleFillError
        When the front gets stuck or does not close within ``max_faces`` triangles.
    """
    P = np.asarray(points, np.float64).reshape(-1, 3)
    k = len(P)
    if k < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    vector_area = 0.5 * np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0)
    area = float(np.linalg.norm(vector_area))
    if reference_normal is None:
        if area <= 0.0:
            raise HoleFillError("the hole boundary encloses no area")
        reference_normal = vector_area / area
    n_ref = np.asarray(reference_normal, np.float64).reshape(-1, 3)
    n_ref = n_ref / np.maximum(np.linalg.norm(n_ref, axis=1, keepdims=True), 1e-300)
    if max_faces is None:
        h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean()) or 1.0
        max_faces = int(20 * area / (0.43 * h * h) + 10 * k + 100)
    front = _AdvancingFront(P, n_ref, forbidden_edges, merge_factor, max_faces, obstacles, merge_ear_max)
    new_vertices, faces = front.run()
    stats = dict(front.stats)
    if front.obstacles is not None:
        stats["obstacle_tests"] = front.obstacles.tests
    return new_vertices, faces, stats


_WARM = []  # set once the kernels are loaded in this process


def warm_up():
    """Load (or compile) the front's numba kernels now, by running the front on a small hole.

    The kernels are compiled lazily, on first use, and cached on disk; loading them takes a
    few tenths of a second per process. A caller about to fork worker processes can call this
    first, so that the workers inherit the loaded kernels instead of each loading them again
    inside its first hole's time.
    """
    if _WARM:
        return
    t = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), 0.1 * np.cos(3 * t)], axis=1)
    outer = 1.5 * ring
    V = np.concatenate([ring, outer])
    k = len(ring)
    F = [(i, (i + 1) % k, k + i) for i in range(k)] + [((i + 1) % k, k + (i + 1) % k, k + i) for i in range(k)]
    advancing_front_triangulation(ring, obstacles=(V, np.array(F)))
    near_any(np.zeros(1, np.int64), ring[[0]], 1.0, ring, np.zeros(1, np.int64), np.ones(1, np.bool_), TWO)
    _WARM.append(True)
