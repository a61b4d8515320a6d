"""Splitting long hole-boundary edges at their midpoints (Xu et al. 2013, Sec. 3.1).

A boundary edge much longer than the others makes long, thin triangles in any patch built
from the boundary. Xu et al. split every boundary edge longer than k * L_ave (L_ave the
mean boundary edge length of the hole) at its midpoint, replacing its border triangle
(a, b, c) by (a, m, c) and (m, b, c), until no boundary edge changes. The surface stays
geometrically identical: new vertices lie on the old edges and the two new triangles
exactly cover the old one. This module changes *original* faces, so it reports, for every
new vertex, the original edge it lies on and, for every face, the original face it lies in,
so that per-element attributes can be carried over (see
:func:`meshlab_holefill.core.attributes.refine_mesh_arrays`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...core.holes import BoundaryLoop

__all__ = ["BorderRefinement", "split_long_boundary_edges"]


@dataclass
class BorderRefinement:
    """A mesh whose hole boundaries were refined, and where everything came from.

    Attributes
    ----------
    V : (n + s, 3) float64
        The n original vertices unchanged and in order, then s new boundary vertices.
    F : (m + s, 3) int64
        Faces: row f < m is original face f or, if it was split, its child that keeps the
        edge's end vertex; rows >= m are the other children.
    loops : list of BoundaryLoop
        The refined loops, in the order given (each original loop vertex stays, new vertices
        are inserted between its ends).
    edge_vertices : (s, 2) int64
        Original vertices (a, b) of the original edge each new vertex lies on.
    edge_weights : (s,) float64
        t such that new vertex = (1 - t) V[a] + t V[b] (0.5 for a first split).
    face_parents : (m + s,) int64
        Original face each face lies in (f itself for unsplit faces).
    split_counts : (len(loops),) int64
        Number of edge splits made on each loop.
    """

    V: np.ndarray
    F: np.ndarray
    loops: list
    edge_vertices: np.ndarray
    edge_weights: np.ndarray
    face_parents: np.ndarray
    split_counts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def n_original_vertices(self):
        return len(self.V) - len(self.edge_weights)

    @property
    def split_edges(self):
        """Total number of edge splits (== number of new vertices == number of new faces)."""
        return int(len(self.edge_weights))


def split_long_boundary_edges(V, F, loops, factor=1.5):
    """Boundary edge pre-treatment (Xu et al. 2013, Sec. 3.1, Steps 1-3).

    For each loop: L_ave is the mean length of its edges (Step 1, computed once, so the
    process terminates: an edge of length l is split into 2^d equal parts with d the least
    integer such that l / 2^d <= factor * L_ave, and l <= k_edges * L_ave bounds d); every
    boundary edge longer than ``factor * L_ave`` is split at its midpoint with its border
    triangle (Steps 2-3), and the halves are tested again until no edge changes. A border
    triangle holding several loop edges is split once for each of them, in turn.

    Only the border faces of the given loops are touched: the work is a Python loop over
    boundary edges and splits, no loop over the whole mesh.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    loops : list of BoundaryLoop
        Loops in patch orientation (from :func:`meshlab_holefill.core.holes.boundary_loops`).
    factor : float
        k of the paper (> 0); it leaves k open.

    Returns
    -------
    BorderRefinement
    """
    state = _SplitState(np.asarray(V, np.float64), np.asarray(F, np.int64), loops)
    counts = np.zeros(len(loops), np.int64)
    for li, loop in enumerate(loops):
        if len(loop.vertices) >= 3 and loop.closed:
            counts[li] = _split_loop(state, np.asarray(loop.vertices, np.int64), factor)
    F2, face_parents = state.faces()
    return BorderRefinement(V=state.vertices(), F=F2, loops=_refined_loops(state, loops),
                            edge_vertices=np.asarray(state.new_edge, np.int64).reshape(-1, 2),
                            edge_weights=np.asarray(state.new_t, np.float64), face_parents=face_parents,
                            split_counts=counts)


class _SplitState:
    """The splits made so far: new vertices, changed and new face rows, and which face holds each loop edge."""

    def __init__(self, V, F0, loops):
        self.V, self.F0 = V, F0
        self.n, self.m = len(V), len(F0)
        self.F_rows = {}     # modified or new face rows
        self.parents = {}    # new face row -> original face
        self.new_pos, self.new_edge, self.new_t = [], [], []
        self.points_on = {}  # subdivision points of every split original loop edge: (a, b) -> [(t, vertex)]
        # Loop edge (a, b) in patch orientation -> face row holding half-edge (b, a).
        self.holder = {}
        for loop in loops:
            lv = np.asarray(loop.vertices, np.int64)
            for i, f in enumerate(np.asarray(loop.border_faces, np.int64).tolist()):
                self.holder[(int(lv[i]), int(lv[(i + 1) % len(lv)]))] = f

    def face(self, row):
        return self.F_rows[row] if row in self.F_rows else tuple(self.F0[row].tolist())

    def split(self, a0, b0, a, b, t):
        """Split sub-edge (a, b) of original loop edge (a0, b0) at parameter t, with its border triangle."""
        mid = self.n + len(self.new_pos)
        self.new_pos.append((1.0 - t) * self.V[a0] + t * self.V[b0])
        self.new_edge.append((a0, b0))
        self.new_t.append(t)
        self.points_on[(a0, b0)].append((t, mid))
        row = self.holder.pop((a, b))
        f = self.face(row)
        j = next(j for j in range(3) if f[j] == b and f[(j + 1) % 3] == a)
        c = f[(j + 2) % 3]
        child_row = self.m + len(self.parents)
        self.F_rows[row] = (b, mid, c)
        self.F_rows[child_row] = (mid, a, c)
        self.parents[child_row] = self.parents.get(row, row)
        self.holder[(a, mid)] = child_row
        self.holder[(mid, b)] = row
        if self.holder.get((c, a)) == row:
            self.holder[(c, a)] = child_row
        return mid

    def vertices(self):
        return np.concatenate([self.V, np.asarray(self.new_pos, np.float64).reshape(-1, 3)])

    def faces(self):
        """(m + s, 3) faces and their (m + s,) original parent faces."""
        s = len(self.new_pos)
        F2 = np.concatenate([self.F0, np.zeros((s, 3), np.int64)])
        if self.F_rows:
            rows = np.fromiter(self.F_rows.keys(), np.int64, len(self.F_rows))
            F2[rows] = np.asarray(list(self.F_rows.values()), np.int64)
        face_parents = np.arange(self.m + s, dtype=np.int64)
        if self.parents:
            face_parents[np.fromiter(self.parents.keys(), np.int64)] = np.fromiter(self.parents.values(), np.int64)
        return F2, face_parents


def _split_loop(state, lv, factor):
    """Steps 1-3 on one loop: split its edges longer than factor * L_ave until none is; returns the splits."""
    k = len(lv)
    P = state.V[lv]
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    limit = factor * float(lengths.mean())
    splits = 0
    for i in range(k):
        a0, b0 = int(lv[i]), int(lv[(i + 1) % k])
        if lengths[i] <= limit:
            continue
        state.points_on[(a0, b0)] = []
        # Work items: (a, b, t_a, t_b, length) of sub-edges of the original edge (a0, b0).
        work = [(a0, b0, 0.0, 1.0, float(lengths[i]))]
        while work:
            a, b, ta, tb, length = work.pop()
            if length <= limit:
                continue
            t = 0.5 * (ta + tb)
            mid = state.split(a0, b0, a, b, t)
            splits += 1
            work.append((a, mid, ta, t, 0.5 * length))
            work.append((mid, b, t, tb, 0.5 * length))
    return splits


def _refined_loops(state, loops):
    """The loops with the new vertices inserted between the ends of the edges they split."""
    new_loops = []
    for loop in loops:
        lv = [int(x) for x in np.asarray(loop.vertices, np.int64)]
        k = len(lv)
        if not state.points_on or k < 3 or not loop.closed:
            new_loops.append(loop)
            continue
        verts = []
        for i in range(k):
            a, b = lv[i], lv[(i + 1) % k]
            verts.append(a)
            verts += [x for _, x in sorted(state.points_on.get((a, b), []))]
        border = [state.holder[(verts[i], verts[(i + 1) % len(verts)])] for i in range(len(verts))]
        new_loops.append(BoundaryLoop(vertices=np.asarray(verts, np.int64),
                                      border_faces=np.asarray(border, np.int64),
                                      pinched=loop.pinched, closed=loop.closed))
    return new_loops
