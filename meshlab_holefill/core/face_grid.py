"""A uniform grid of a mesh's faces, for the faces near one patch at a time.

Worker processes check each patch they fill against the mesh (:func:`.crossings.patch_intersections`).
Scanning every face per patch costs O(m) per hole: on the bunny Loop-subdivided once (221k faces)
with 115 small holes, two workers spent more time scanning than filling and ran slower than
one. The grid is built once, before the workers fork (they inherit it), in O(m) and with
8 or 16 bytes per face; a query visits the cells of its box only.

A face whose box is at most half a cell wide on every axis is filed in the cell of its lower
corner, the others in a list every query visits. A small face meeting a box [lo, hi] then has
its lower corner in [lo - cell / 2, hi] on every axis (the half cell to spare covers the rounding
of the widths and of lo - cell), and rounding keeps that order (x <= y gives
floor((x - o) / c) <= floor((y - o) / c)), so the cells of [lo - cell, hi] hold every such face:
after testing the boxes of those, :meth:`FaceGrid.near` returns exactly the faces
:func:`.crossings.face_boxes_near` returns for the one box, in the same (increasing) order.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["FaceGrid", "face_grid", "load_face_grid_kernels"]

# About this many faces per cell of a surface mesh; and at most one cell per face, so the
# grid's index stays within the faces' own size.
FACES_PER_CELL = 8


class FaceGrid:
    """The faces of (V, F) filed by grid cell; :meth:`near` answers box queries.

    Attributes
    ----------
    origin : (3,) float64  the lower corner of the mesh's bounding box
    cell : float  cell edge length
    dims : (3,) int64  cells per axis
    starts : (c + 1,) int64  faces of cell k (linear index) are order[starts[k]:starts[k + 1]]
    order : (s,) int64  the small faces, by cell
    large : (t,) int64  faces wider than half a cell on some axis, ascending
    """

    def __init__(self, V, F, origin, cell, dims, starts, order, large):
        self.V, self.F = V, F
        self.origin, self.cell, self.dims = origin, cell, dims
        self.starts, self.order, self.large = starts, order, large

    def near(self, box):
        """Candidates for one box, as :func:`.crossings.face_boxes_near` returns them.

        Parameters
        ----------
        box : (2, 3) float  lower and upper corner

        Returns
        -------
        near : (c,) int64  the faces whose box meets ``box``, ascending
        lo, hi : (c, 3) float64  their boxes
        """
        box = np.asarray(box, np.float64)
        near = _faces_in_cells(self.V, self.F, box, self.origin, self.cell, self.dims, self.starts, self.order,
                               self.large)
        corners = self.V[self.F[near]]  # (c, 3, 3)
        return near, corners.min(axis=1), corners.max(axis=1)


def face_grid(V, F, faces_per_cell=FACES_PER_CELL):
    """Build the :class:`FaceGrid` of a mesh (compiled, O(m)).

    The cell edge is sqrt(faces_per_cell) times the faces' mean box width, so a surface puts
    about ``faces_per_cell`` faces in each cell it crosses; it is enlarged where that would
    give more cells than faces (a mesh whose faces are small against its box).

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int  C-contiguous
    faces_per_cell : float

    Returns
    -------
    FaceGrid
    """
    V = np.ascontiguousarray(V, np.float64)
    F = np.ascontiguousarray(F)
    origin, upper, width = _bounds_and_mean_width(V, F)
    extent = np.maximum(upper - origin, 0.0)
    cell = max(width * np.sqrt(faces_per_cell), float(extent.max()) * 1e-12, 1e-300)
    while np.prod(np.floor(extent / cell) + 1.0) > max(len(F), 1):
        cell *= 1.25
    dims = (np.floor(extent / cell) + 1.0).astype(np.int64)
    starts, order, large = _file_faces(V, F, origin, cell, dims)
    return FaceGrid(V, F, origin, cell, dims, starts, order, large)


def load_face_grid_kernels(face_dtype):
    """Compile (or load from the cache) the grid's kernels for faces of ``face_dtype``, in this process."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    face_grid(V, np.arange(3, dtype=face_dtype).reshape(1, 3)).near(np.array([[0.0] * 3, [1.0] * 3]))


@njit(cache=True)
def _bounds_and_mean_width(V, F):
    """(lower corner, upper corner) of the vertices (zeros for none) and the faces' mean largest box side."""
    lo = np.zeros(3)
    hi = np.zeros(3)
    if V.shape[0]:
        lo[:] = V[0]
        hi[:] = V[0]
    for v in range(V.shape[0]):
        for axis in range(3):
            lo[axis] = min(lo[axis], V[v, axis])
            hi[axis] = max(hi[axis], V[v, axis])
    total = 0.0
    for f in range(F.shape[0]):
        widest = 0.0
        for axis in range(3):
            a, b, c = V[F[f, 0], axis], V[F[f, 1], axis], V[F[f, 2], axis]
            widest = max(widest, max(a, max(b, c)) - min(a, min(b, c)))
        total += widest
    return lo, hi, total / max(F.shape[0], 1)


@njit(cache=True)
def _cell_of(x, origin, cell, dims, axis):
    k = np.int64(np.floor((x - origin[axis]) / cell))
    return min(max(k, 0), dims[axis] - 1)


@njit(cache=True)
def _file_faces(V, F, origin, cell, dims):
    """(starts, order, large): a counting sort of the small faces by the cell of their lower corner."""
    m = F.shape[0]
    key = np.empty(m, np.int64)
    n_large = 0
    for f in range(m):
        k = 0
        small = True
        for axis in range(3):
            a, b, c = V[F[f, 0], axis], V[F[f, 1], axis], V[F[f, 2], axis]
            lo = min(a, min(b, c))
            if max(a, max(b, c)) - lo > 0.5 * cell:
                small = False
            k = k * dims[axis] + _cell_of(lo, origin, cell, dims, axis)
        key[f] = k if small else -1
        if not small:
            n_large += 1
    cells = dims[0] * dims[1] * dims[2]
    starts = np.zeros(cells + 1, np.int64)
    for f in range(m):
        if key[f] >= 0:
            starts[key[f] + 1] += 1
    for k in range(cells):
        starts[k + 1] += starts[k]
    fill = starts[:-1].copy()
    order = np.empty(m - n_large, np.int64)
    large = np.empty(n_large, np.int64)
    t = 0
    for f in range(m):
        if key[f] >= 0:
            order[fill[key[f]]] = f
            fill[key[f]] += 1
        else:
            large[t] = f
            t += 1
    return starts, order, large


@njit(cache=True)
def _faces_in_cells(V, F, box, origin, cell, dims, starts, order, large):
    """The faces filed in the cells of [box_lo - cell, box_hi] and the large ones, ascending, that meet the box."""
    first = np.empty(3, np.int64)
    last = np.empty(3, np.int64)
    for axis in range(3):
        first[axis] = _cell_of(box[0, axis] - cell, origin, cell, dims, axis)
        last[axis] = _cell_of(box[1, axis], origin, cell, dims, axis)
    count = large.shape[0]
    for i in range(first[0], last[0] + 1):
        for j in range(first[1], last[1] + 1):
            k0 = (i * dims[1] + j) * dims[2]
            count += starts[k0 + last[2] + 1] - starts[k0 + first[2]]
    out = np.empty(count, np.int64)
    c = 0
    for f in large:
        if _meets(V, F, f, box):
            out[c] = f
            c += 1
    for i in range(first[0], last[0] + 1):
        for j in range(first[1], last[1] + 1):
            k0 = (i * dims[1] + j) * dims[2]
            for e in range(starts[k0 + first[2]], starts[k0 + last[2] + 1]):  # a z-run of cells is contiguous
                if _meets(V, F, order[e], box):
                    out[c] = order[e]
                    c += 1
    return np.sort(out[:c])


@njit(cache=True)
def _meets(V, F, f, box):
    """Does face f's bounding box meet ``box`` (closed boxes, as crossings.face_boxes_near tests)?"""
    for axis in range(3):
        a, p, q = V[F[f, 0], axis], V[F[f, 1], axis], V[F[f, 2], axis]
        if max(a, max(p, q)) < box[0, axis] or min(a, min(p, q)) > box[1, axis]:
            return False
    return True
