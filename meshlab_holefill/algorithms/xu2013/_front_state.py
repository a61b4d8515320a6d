"""The state of an advancing front (Xu et al. 2013, Sec. 3.2): fronts, their vertices, the faces so far.

:mod:`.advancing_front` decides each step (Steps 2-4: the vertex with the smallest front
angle, the angle rules, the merges, the checks); :class:`FrontState` keeps the bookkeeping a
step changes (Step 5): the vertex positions, normals and sizing values, the faces and edges
made, the directed front edges with the normal of the triangle behind each, and the fronts as
cyclic linked lists of nodes (a vertex is on two fronts after a split), with a heap of their
angles, and array mirrors of positions and nodes for the compiled step tests.
"""
from __future__ import annotations

import heapq

import numpy as np

from ._front_predicates import cross, front_angle, sub, unit

__all__ = ["FrontState"]


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
