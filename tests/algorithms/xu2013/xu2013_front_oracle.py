"""Test oracle: the advancing front's step loop in Python, the reference of xu2013._front_loop.

The bookkeeping (heap of front angles, linked-list fronts, edge sets; ``FrontState``) and
Steps 2-6 (``PythonFront``) as they ran before the loop was compiled, on the same compiled
per-step checks: ``oracle_triangulation`` takes the same decisions as
``advancing_front_triangulation`` in the same order. Only the tests use it.
"""
from __future__ import annotations

import heapq
import math

import numpy as np

from meshlab_holefill.errors import HoleFillError
from meshlab_holefill.algorithms.xu2013._front_kernels import merge_target, near_any, step_geometry_valid
from meshlab_holefill.algorithms.xu2013._front_obstacles import FrontObstacles
from meshlab_holefill.algorithms.xu2013._front_predicates import cross, dot, front_angle, norm, scaled, sub, unit
from meshlab_holefill.algorithms.xu2013.advancing_front import (
    ANGLE_MARGIN, FACE_BOUND, FALLBACK_ONE_TRIANGLE_MAX, FOLD_MIN_COS, FRONT_GROWTH_LIMIT, HOVER_FACTOR,
    LEAVE_RADIUS, MERGE_EAR_MAX, ONE_TRIANGLE_MAX, TWO, TWO_TRIANGLES_MAX, leave_ball)

_NO_NORMAL = (math.nan, math.nan, math.nan)


class FrontState:
    """Fronts, vertices and faces of one advancing-front run (see :mod:`.advancing_front`)."""

    def __init__(self, points, reference_normal, forbidden_edges):
        k = len(points)
        self.k = k
        self.P = [tuple(map(float, p)) for p in points]
        self.N = [tuple(map(float, x)) for x in np.asarray(reference_normal, np.float64).reshape(-1, 3)]
        if len(self.N) == 1:
            self.N = self.N * k
        lengths = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
        self.S = (0.5 * (lengths + np.roll(lengths, 1))).tolist()
        self.longest_edge = float(lengths.max())
        self.faces = []
        self.edges = set()
        # Directed front edge -> unit normal of the triangle behind it (None: unknown).
        self.front_edges = {}
        for i in range(k):
            j = (i + 1) % k
            self.edges.add((min(i, j), max(i, j)))
            self.front_edges[(i, j)] = None
        for a, b in np.asarray(forbidden_edges, np.int64).reshape(-1, 2).tolist():
            self.edges.add((min(a, b), max(a, b)))
        # Cell of the uniform grids of neighbourhood queries (the kernels' query boxes, the obstacles).
        self.cell = max(2.0 * float(np.mean(lengths)), 1e-300)
        # Nodes of the cyclic front lists.
        self.node_vertex = list(range(k))
        self.node_prev = [(i - 1) % k for i in range(k)]
        self.node_next = [(i + 1) % k for i in range(k)]
        self.node_front = [0] * k
        self.node_alive = [True] * k
        self.node_version = [0] * k
        self.node_theta = [0.0] * k
        self.node_plane = [None] * k
        self.vertex_nodes = {i: {i} for i in range(k)}
        self._init_arrays(points)
        self.front_size = {0: k}
        self.next_label = 1
        self.heap = []
        self.blocked = []
        self.stats = {"steps": 0, "rule1": 0, "rule2": 0, "rule3": 0, "merges": 0, "splits": 0,
                      "rejected": 0, "obstacle_tests": 0}

    # ----------------------------------------------------------------- array mirrors
    def _init_arrays(self, points):
        """Array copies of the positions and nodes for the compiled step tests (:mod:`._front_kernels`).

        ``Pa`` (vertices, 3), per node ``na_vertex``, ``na_next``, ``na_front``, ``na_alive``,
        ``na_theta``, ``na_plane``, and ``alive`` the alive nodes (in no particular order; ``n_alive`` of them, node i at
        ``alive_at[i]``). Capacities double as the front grows.
        """
        k = self.k
        cap = max(4 * k, 64)
        self.Pa = np.empty((cap, 3))
        self.Pa[:k] = points
        self.na_vertex = np.empty(cap, np.int64)
        self.na_vertex[:k] = np.arange(k)
        self.na_next = np.empty(cap, np.int64)
        self.na_next[:k] = (np.arange(k) + 1) % k
        self.na_front = np.zeros(cap, np.int64)
        self.na_alive = np.zeros(cap, np.bool_)
        self.na_alive[:k] = True
        self.na_theta = np.zeros(cap)
        self.na_plane = np.zeros((cap, 3))
        self.alive = np.empty(cap, np.int64)
        self.alive[:k] = np.arange(k)
        self.alive_at = np.empty(cap, np.int64)
        self.alive_at[:k] = np.arange(k)
        self.n_alive = k

    @staticmethod
    def _grown(a, n):
        if n < len(a):
            return a
        b = np.empty((2 * len(a),) + a.shape[1:], a.dtype)
        b[:len(a)] = a
        return b

    def _add_vertex(self, pos, normal, size):
        i = len(self.P)
        self.P.append(pos)
        self.N.append(normal)
        self.S.append(size)
        self.Pa = self._grown(self.Pa, i)
        self.Pa[i] = pos
        return i

    def _link(self, a, b):
        self.node_next[a] = b
        self.node_prev[b] = a
        self.na_next[a] = b

    def _set_front(self, i, label):
        self.node_front[i] = label
        self.na_front[i] = label

    # ----------------------------------------------------------------- bookkeeping
    def _new_node(self, vertex, label):
        i = len(self.node_vertex)
        self.node_vertex.append(vertex)
        self.node_prev.append(-1)
        self.node_next.append(-1)
        self.node_front.append(label)
        self.node_alive.append(True)
        self.node_version.append(0)
        self.node_theta.append(0.0)
        self.node_plane.append(None)
        self.na_vertex = self._grown(self.na_vertex, i)
        self.na_next = self._grown(self.na_next, i)
        self.na_front = self._grown(self.na_front, i)
        self.na_alive = self._grown(self.na_alive, i)
        self.alive_at = self._grown(self.alive_at, i)
        self.na_theta = self._grown(self.na_theta, i)
        self.na_plane = self._grown(self.na_plane, i)
        self.na_vertex[i], self.na_next[i], self.na_front[i], self.na_alive[i] = vertex, -1, label, True
        self.alive = self._grown(self.alive, self.n_alive)
        self.alive[self.n_alive] = i
        self.alive_at[i] = self.n_alive
        self.n_alive += 1
        self.vertex_nodes.setdefault(vertex, set()).add(i)
        return i

    def _kill_node(self, i):
        self.node_alive[i] = False
        if self.na_alive[i]:
            self.na_alive[i] = False
            # Swap-remove from the alive list.
            at, last = self.alive_at[i], self.alive[self.n_alive - 1]
            self.alive[at] = last
            self.alive_at[last] = at
            self.n_alive -= 1
        self.node_version[i] += 1
        v = self.node_vertex[i]
        self.vertex_nodes[v].discard(i)

    def _update_node(self, i):
        v = self.node_vertex[i]
        p = self.node_vertex[self.node_prev[i]]
        q = self.node_vertex[self.node_next[i]]
        theta, m = front_angle(self.P[v], self.P[p], self.P[q], self.N[v])
        self.node_theta[i] = theta
        self.node_plane[i] = m
        self.na_theta[i] = theta
        self.na_plane[i] = m
        self.node_version[i] += 1
        heapq.heappush(self.heap, (theta, i, self.node_version[i]))

    def _same_front_node(self, u, label):
        for x in self.vertex_nodes.get(u, ()):
            if self.node_front[x] == label:
                return x
        return -1

    def _pop(self):
        while self.heap:
            theta, i, version = heapq.heappop(self.heap)
            if self.node_alive[i] and self.node_version[i] == version:
                return i
        return None

    def _release_blocked(self):
        """Put the nodes refused since the last change back on the heap (a change may unblock them)."""
        for b in self.blocked:
            if self.node_alive[b]:
                heapq.heappush(self.heap, (self.node_theta[b], b, self.node_version[b]))
        self.blocked = []

    # ----------------------------------------------------------------- Step 5: update the front
    def _apply(self, node, rule, faces, new_pos, sequence):
        label = self.node_front[node]
        v = self.node_vertex[node]
        prev, nxt = self.node_prev[node], self.node_next[node]
        p, q = self.node_vertex[prev], self.node_vertex[nxt]
        ids = {}
        if new_pos:
            size = (self.S[v] + self.S[p] + self.S[q]) / 3.0
            normal = unit(tuple(self.N[v][i] + self.N[p][i] + self.N[q][i] for i in range(3)))
            for temp in sorted(new_pos, reverse=True):
                ids[temp] = self._add_vertex(new_pos[temp], normal, size)
        faces = [tuple(ids.get(x, x) for x in f) for f in faces]
        sequence = [ids.get(x, x) for x in sequence]
        directed = []
        face_normal = {}
        for f in faces:
            self.faces.append(f)
            directed += [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])]
            c = unit(cross(sub(self.P[f[1]], self.P[f[0]]), sub(self.P[f[2]], self.P[f[0]])))
            for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
                face_normal[e] = c
        dset = set(directed)
        for a, b in directed:
            self.edges.add((min(a, b), max(a, b)))
            if (a, b) in self.front_edges:
                del self.front_edges[(a, b)]
            elif (b, a) not in dset:
                self.front_edges[(b, a)] = face_normal[(a, b)]
        self.stats[f"rule{rule}"] += 1
        self.stats["merges"] += len(sequence) - len(ids)
        # Linked-list surgery: p -> sequence -> q replaces p -> v -> q.
        self._kill_node(node)
        chain = [prev] + [self._new_node(x, label) for x in sequence] + [nxt]
        for a, b in zip(chain[:-1], chain[1:]):
            self._link(a, b)
        dirty = set(chain)
        self.front_size[label] += len(sequence) - 1
        if self.front_size[label] <= 2:
            # The last triangle of this front consumed all its edges.
            for x in (prev, nxt):
                if self.node_alive[x]:
                    self._kill_node(x)
            del self.front_size[label]
            return
        # A merged vertex is now twice on its front: split the front there.
        for w in chain[1:-1]:
            if not self.node_alive[w]:
                continue
            u = self.node_vertex[w]
            others = [x for x in self.vertex_nodes[u] if x != w and self.node_front[x] == self.node_front[w]]
            if others:
                dirty |= self._split(w, others[0])
        for x in dirty:
            if self.node_alive[x]:
                self._update_node(x)

    def _split(self, w, u):
        """Split the front through nodes w and u of one vertex into two cycles; drop cycles of <= 2 nodes."""
        self.stats["splits"] += 1
        label = self.node_front[w]
        wn, un = self.node_next[w], self.node_next[u]
        self._link(w, un)
        self._link(u, wn)
        # Walk both cycles in lockstep: the shorter one is found in O(its length).
        a, b, la, lb = self.node_next[w], self.node_next[u], 1, 1
        while a != w and b != u:
            a, b, la, lb = self.node_next[a], self.node_next[b], la + 1, lb + 1
        short, short_len = (w, la) if a == w else (u, lb)
        long_start = u if short == w else w
        long_len = self.front_size[label] - short_len
        cycle = [short]
        x = self.node_next[short]
        while x != short:
            cycle.append(x)
            x = self.node_next[x]
        if short_len <= 2:
            for x in cycle:
                self._kill_node(x)
        else:
            new_label = self.next_label
            self.next_label += 1
            for x in cycle:
                self._set_front(x, new_label)
            self.front_size[new_label] = short_len
        self.front_size[label] = long_len
        if long_len <= 2:
            x = long_start
            for _ in range(long_len):
                nx = self.node_next[x]
                self._kill_node(x)
                x = nx
            del self.front_size[label]
        return {w, u, wn, un}


class PythonFront(FrontState):
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
        *centre, r2 = leave_ball(np.asarray(self.P[:self.k], np.float64))
        checked = len(self.P)
        while self.front_size:
            for i in range(checked, len(self.P)):
                if sum((self.P[i][j] - centre[j]) ** 2 for j in range(3)) > r2:
                    raise HoleFillError(f"advancing front left the hole: a new vertex lies more than {LEAVE_RADIUS} "
                                        "times the loop's radius from the loop's centre")
            checked = len(self.P)
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
        points = self.Pa[sorted(verts)]
        for b in self.blocked:
            if not self.na_alive[b]:
                continue
            X = self.Pa[self.na_vertex[b]]
            if near_any(X[0], X[1], X[2], points, r2, TWO):
                heapq.heappush(self.heap, (self.node_theta[b], b, self.node_version[b]))
            else:
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
                np.array(faces, np.int64), len(faces), positions, np.array(behind), self.na_plane[node],
                1e-10 * scale * scale, FOLD_MIN_COS, np.array(new_edges, np.int64).reshape(-1, 2),
                np.array(edge_nodes, np.int64).reshape(-1, 2), len(new_edges), ANGLE_MARGIN, self.Pa[v],
                self.longest_edge, self.Pa, self.na_vertex, self.na_next, self.na_plane, self.na_theta, self.alive,
                self.n_alive, self.cell, TWO):
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


def oracle_triangulation(points, forbidden_edges=(), merge_factor=0.75, max_faces=None,
                                  reference_normal=None, obstacles=None, merge_ear_max=MERGE_EAR_MAX):
    """``advancing_front_triangulation`` run by :class:`PythonFront`."""
    P = np.asarray(points, np.float64).reshape(-1, 3)
    k = len(P)
    if k < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    Q = P - P[0]  # about a loop vertex, as advancing_front_triangulation
    vector_area = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    area = float(np.linalg.norm(vector_area))
    if reference_normal is None:
        if area <= 0.0:
            raise HoleFillError("the hole boundary encloses no area")
        reference_normal = vector_area / area
    n_ref = np.asarray(reference_normal, np.float64).reshape(-1, 3)
    n_ref = n_ref / np.maximum(np.linalg.norm(n_ref, axis=1, keepdims=True), 1e-300)
    if max_faces is None:
        h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean()) or 1.0
        max_faces = int(FACE_BOUND * area / (0.43 * h * h) + 10 * k + 100)
    front = PythonFront(P, n_ref, forbidden_edges, merge_factor, max_faces, obstacles, merge_ear_max)
    new_vertices, faces = front.run()
    stats = dict(front.stats)
    if front.obstacles is not None:
        stats["obstacle_tests"] = front.obstacles.tests
    return new_vertices, faces, stats
