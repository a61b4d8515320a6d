"""The surrounding mesh an advancing front must stay clear of (beyond Xu et al. 2013, Sec. 3.2).

The paper's front has no safeguards; :mod:`.advancing_front` rejects a step whose new
triangles would cross a face of the mesh around the hole, or whose new vertices would come
too close to one. :class:`FrontObstacles` answers both questions from a uniform grid over the
faces' bounding boxes, with the grid cell of the front's own vertex grid.
"""
from __future__ import annotations

import numpy as np

from ._front_kernels import min_point_triangle_distance, obstacle_candidates, triangles_cross_faces

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
        self.V = np.ascontiguousarray(V, np.float64)
        self.F = np.ascontiguousarray(np.asarray(F, np.int64).reshape(-1, 3))
        self.cell, self.k = cell, k
        self.tests = 0  # exact crossing tests run (those with candidate faces)
        corners = self.V[self.F]
        self.lo, self.hi = corners.min(axis=1), corners.max(axis=1)
        self._index_cells(np.floor(self.lo / cell).astype(np.int64), np.floor(self.hi / cell).astype(np.int64))
        self._stamp = np.zeros(len(self.F) + 1, np.int64)  # candidates' marks, the last entry the current one
        self._out = np.empty(len(self.F), np.int64)

    def _index_cells(self, lo, hi):
        """Each face listed in every grid cell its bounding box meets, as sorted cell keys with face ranges."""
        self._base = lo.min(axis=0)
        self._dims = hi.max(axis=0) - self._base + 1
        span = hi - lo + 1
        counts = span.prod(axis=1)
        face = np.repeat(np.arange(len(lo)), counts)
        r = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
        ny, nz = span[face, 1], span[face, 2]
        ix = lo[face, 0] + r // (ny * nz) - self._base[0]
        iy = lo[face, 1] + (r // nz) % ny - self._base[1]
        iz = lo[face, 2] + r % nz - self._base[2]
        key = (ix * self._dims[1] + iy) * self._dims[2] + iz
        order = np.argsort(key, kind="stable")
        key, self._cell_faces = key[order], np.ascontiguousarray(face[order])
        self._keys, first = np.unique(key, return_index=True)
        self._starts = np.append(first, len(key)).astype(np.int64)

    def border_faces(self):
        """Faces with two or more boundary vertices (the triangles behind the boundary edges)."""
        return self.F[(self.F < self.k).sum(axis=1) >= 2]

    def candidates(self, lo, hi):
        """Faces whose bounding box overlaps the box [lo, hi]: (c,) int64 (a view, valid until the next call)."""
        count = obstacle_candidates(np.asarray(lo, np.float64), np.asarray(hi, np.float64), self.cell, self._base,
                                    self._dims, self._keys, self._starts, self._cell_faces, self.lo, self.hi,
                                    self._stamp, self._out)
        return self._out[:count]

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
        T = np.asarray(corners, np.float64).reshape(-1, 3, 3)
        cand = self.candidates(T.min(axis=(0, 1)), T.max(axis=(0, 1)))
        if len(cand) == 0:
            return False
        self.tests += 1
        return bool(triangles_cross_faces(np.asarray(faces, np.int64).reshape(-1, 3), T, self.V, self.F, cand,
                                          len(cand), self.k, 1e-9 * self.cell))
