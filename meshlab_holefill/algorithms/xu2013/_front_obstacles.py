"""The surrounding mesh an advancing front must stay clear of (beyond Xu et al. 2013, Sec. 3.2).

The paper's front has no safeguards; :mod:`.advancing_front` rejects a step whose new
triangles would cross a face of the mesh around the hole, or whose new vertices would come
too close to one. :class:`FrontObstacles` answers both questions from a uniform grid over the
faces' bounding boxes, with the grid cell of the front's own vertex grid.
"""
from __future__ import annotations

import math

import numpy as np

from ._front_kernels import min_point_triangle_distance
from ._front_predicates import segments_hit_triangles

__all__ = ["FrontObstacles"]


class FrontObstacles:
    """Surrounding mesh faces indexed by a grid of their bounding boxes.

    Parameters
    ----------
    V : (n, 3) float64
        Vertices, the hole's k boundary vertices first (as in a HoleContext).
    F : (m, 3) int
        Faces, m > 0.
    cell : float
        Grid cell size.
    k : int
        Number of boundary vertices (indices below k are shared with the front).
    """

    def __init__(self, V, F, cell, k):
        self.V = np.asarray(V, np.float64)
        self.F = np.asarray(F, np.int64).reshape(-1, 3)
        self.cell, self.k = cell, k
        self.tests = 0  # exact crossing tests run (those with candidate faces)
        corners = self.V[self.F]
        self.lo, self.hi = corners.min(axis=1), corners.max(axis=1)
        lo = np.floor(self.lo / cell).astype(np.int64)
        hi = np.floor(self.hi / cell).astype(np.int64)
        grid = {}
        for f, (a, b) in enumerate(zip(lo.tolist(), hi.tolist())):
            for ix in range(a[0], b[0] + 1):
                for iy in range(a[1], b[1] + 1):
                    for iz in range(a[2], b[2] + 1):
                        grid.setdefault((ix, iy, iz), []).append(f)
        self.grid = grid

    def _key(self, pos):
        c = self.cell
        return (math.floor(pos[0] / c), math.floor(pos[1] / c), math.floor(pos[2] / c))

    def border_faces(self):
        """Faces with two or more boundary vertices (the triangles behind the boundary edges)."""
        return self.F[(self.F < self.k).sum(axis=1) >= 2]

    def candidates(self, lo, hi):
        """Faces whose bounding box overlaps the box [lo, hi]: (c,) int64."""
        x0, y0, z0 = self._key(lo)
        x1, y1, z1 = self._key(hi)
        cand = set()
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                for iz in range(z0, z1 + 1):
                    cell = self.grid.get((ix, iy, iz))
                    if cell:
                        cand.update(cell)
        if not cand:
            return np.zeros(0, np.int64)
        cand = np.fromiter(cand, np.int64, len(cand))
        pad = 1e-9 * self.cell
        keep = np.all(self.hi[cand] >= np.asarray(lo) - pad, axis=1) & \
            np.all(self.lo[cand] <= np.asarray(hi) + pad, axis=1)
        return cand[keep]

    def distance(self, pos, radius):
        """Distance from pos to the nearest face, if below radius (else radius)."""
        cand = self.candidates([x - radius for x in pos], [x + radius for x in pos])
        if len(cand) == 0:
            return radius
        return float(min_point_triangle_distance(np.asarray(pos, np.float64), self.V, self.F, cand, radius))

    def crossed(self, faces, corners):
        """Whether a new triangle intersects a face (shared boundary vertices allowed).

        Parameters
        ----------
        faces : list of (3,) int
            The new triangles' vertex ids (boundary vertices below k, others any id that is
            not a boundary vertex).
        corners : list of 3 (3,) tuples per face
            Their corner positions.
        """
        pts = [p for T in corners for p in T]
        lo = [min(p[i] for p in pts) for i in range(3)]
        hi = [max(p[i] for p in pts) for i in range(3)]
        cand = self.candidates(lo, hi)
        if len(cand) == 0:
            return False
        self.tests += 1
        k = self.k
        OF = self.F[cand]
        # Pairs (new triangle, obstacle) and the vertices they share (boundary vertices only).
        segs_a, segs_b, tris = [], [], []
        for f, T in zip(faces, corners):
            for o in OF.tolist():
                shared = [x for x in f if 0 <= x < k and x in o]
                O = [tuple(self.V[x]) for x in o]
                if len(shared) >= 2:
                    continue  # across a boundary edge: the front-angle checks keep them apart
                if len(shared) == 1:
                    s = shared[0]
                    ta = [T[j] for j in range(3) if f[j] != s]
                    ob = [O[j] for j in range(3) if o[j] != s]
                    segs_a += [ta[0], ob[0]]
                    segs_b += [ta[1], ob[1]]
                    tris += [O, T]
                else:
                    for j in range(3):
                        segs_a += [T[j], O[j]]
                        segs_b += [T[(j + 1) % 3], O[(j + 1) % 3]]
                        tris += [O, T]
        if not tris:
            return False
        return bool(segments_hit_triangles(np.asarray(segs_a), np.asarray(segs_b), np.asarray(tris),
                                           1e-9 * self.cell).any())
