"""Boundary loops of a triangle mesh and the per-hole context handed to the algorithms.

The loops are found in :mod:`._boundary_loops` (:func:`boundary_loops`, :class:`BoundaryLoop`,
:func:`edge_summary`, :func:`nonmanifold_edges`, ...: offered here); the context of one hole, its
rings of surrounding faces, normals and scales, is :func:`hole_context`.

Whether a loop is a hole or an island's outline, and its measures: :mod:`.outlines`.

Orientation convention used throughout the package: a hole's ``loop`` lists its vertices in
*patch orientation*, the order in which the patch's own boundary half-edges run. A patch face
that contains the loop edge (loop[i], loop[i+1]) contains it in that direction, so it is
consistently oriented with the surrounding mesh (whose border face holds the half-edge
(loop[i+1], loop[i])). Seen from outside (along the surrounding normals) the loop is
counter-clockwise, like the boundary of a counter-clockwise triangle.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numba import njit

from ..errors import HoleFillError
from ..geometry.intersections import FixedFaces
from ..geometry.quality import face_normals, vertex_normals
from ..geometry.sets import positions_ints, setdiff_ints, unique_ints
from ._boundary_loops import (BoundaryLoop, boundary_halfedges, boundary_loops, edge_face_counts, edge_summary,
                              nonmanifold_edges)

__all__ = ["BoundaryLoop", "HoleContext", "boundary_halfedges", "boundary_loops", "edge_face_counts", "edge_summary",
           "hole_context", "incident_faces", "nonmanifold_edges", "vertex_face_incidence"]


@njit(cache=True)
def _incidence_rows(F, n, indices):
    """Counting sort of the faces by vertex: fills ``indices`` row by row, returns the row starts.

    Faces come out in increasing order within each row; a face repeating a vertex is listed
    once in that vertex's row. Returns (indptr, number of entries written).
    """
    indptr = np.zeros(n + 1, np.int64)
    for f in range(F.shape[0]):
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        indptr[a + 1] += 1
        if b != a:
            indptr[b + 1] += 1
        if c != a and c != b:
            indptr[c + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:n].copy()
    for f in range(F.shape[0]):
        a, b, c = F[f, 0], F[f, 1], F[f, 2]
        indices[fill[a]] = f
        fill[a] += 1
        if b != a:
            indices[fill[b]] = f
            fill[b] += 1
        if c != a and c != b:
            indices[fill[c]] = f
            fill[c] += 1
    return indptr, indptr[n]


def vertex_face_incidence(F, n):
    """Sparse (n, m) incidence: row v holds the faces that contain vertex v (int8 ones, sorted rows).

    Built by a compiled counting sort (:func:`_incidence_rows`) straight into the CSR arrays, in
    int32 where the face count allows: at 3.6M faces 0.03 s CPU and 60 MB, where scipy's
    conversion from coordinates took 0.14 s and 260 MB.
    """
    F = np.asarray(F)
    if F.dtype not in (np.int32, np.int64):
        F = F.astype(np.int64)
    F = np.ascontiguousarray(F)
    m = len(F)
    index = np.int32 if max(n, m, 3 * m) < 2 ** 31 else np.int64  # scipy's own index type
    indices = np.empty(3 * m, index)
    indptr, used = _incidence_rows(F, n, indices)
    matrix = sp.csr_matrix((np.ones(used, np.int8), indices[:used], indptr.astype(index)), shape=(n, m))
    matrix.has_sorted_indices = True
    return matrix


@dataclass
class HoleContext:
    """Everything an algorithm may know about one hole: the loop and a few rings around it.

    Local vertex numbering puts the loop first: local vertex i < k is loop vertex i.

    Attributes
    ----------
    loop : (k,) int64
        Global vertex indices, patch orientation.
    points : (k, 3) float64
        Loop coordinates (== vertices[:k]).
    vertices : (n, 3) float64
        Local surrounding vertices, loop first.
    faces : (m, 3) int64
        Surrounding faces within ``rings`` rings, in local indices.
    global_index : (n,) int64
        Local -> global vertex index.
    depth : (n,) int64
        Ring number of each local vertex (0 on the loop).
    normals : (n, 3) float64
        Area-weighted vertex normals from the local faces (exact for depth < rings).
    border_faces : (k,) int64
        Local face index holding the loop edge (i, i+1).
    edge_scale : (k,) float64
        Mean length of the mesh edges incident to each loop vertex (the scale attribute
        sigma(v) of Pfeifle and Seidel / Hu et al. Sec. III.C Step 1).
    mean_edge_length : float
        Mean edge length of the local faces.
    forbidden_edges : (p, 2) int64
        Pairs of loop-local indices already joined by a mesh edge that is not a loop edge:
        a patch using such a pair as an edge would create a non-manifold edge.
    pinched : bool
    index : int
        Position of the hole in the filter's hole list.
    obstacle_vertices : (s, 3) float64
    obstacle_faces : (r, 3) int64
        Mesh faces beyond the rings that a patch must not cross either (any component), in the
        numbering of ``vertices`` followed by ``obstacle_vertices``; empty unless
        :func:`hole_context` was given ``obstacles``. Only the crossing checks see them
        (:meth:`surroundings`): normals, scales and the rings stay those of the rings.
    crossings_allowed : bool
        The filter runs with ``selfintersection=False``: an algorithm whose every patch crosses the
        surroundings returns one rather than failing the hole (MeshLab's Close Holes closes such a
        hole too when its check is off).
    """

    loop: np.ndarray
    points: np.ndarray
    vertices: np.ndarray
    faces: np.ndarray
    global_index: np.ndarray
    depth: np.ndarray
    normals: np.ndarray
    border_faces: np.ndarray
    edge_scale: np.ndarray
    mean_edge_length: float
    forbidden_edges: np.ndarray
    pinched: bool = False
    index: int = 0
    extra: dict = field(default_factory=dict)
    obstacle_vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    obstacle_faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    crossings_allowed: bool = False

    @property
    def size(self):
        """Number of boundary edges (== boundary vertices)."""
        return len(self.loop)

    @property
    def loop_normals(self):
        """(k, 3) vertex normals of the loop vertices."""
        return self.normals[: self.size]

    @property
    def border_normals(self):
        """(k, 3) unit normals of the mesh faces on the loop edges (i, i + 1) (zero for a degenerate face)."""
        return face_normals(self.vertices, self.faces[self.border_faces])

    def surroundings(self):
        """(vertices (n + s, 3), faces (m + r, 3)): everything a patch must not cross, loop first.

        The rings, then the obstacle faces; the rings' own arrays when there are none.
        """
        if len(self.obstacle_faces) == 0:
            return self.vertices, self.faces
        return (np.concatenate([self.vertices, self.obstacle_vertices]),
                np.concatenate([self.faces, self.obstacle_faces]))

    @cached_property
    def surrounding_bounds(self):
        """:class:`meshlab_holefill.geometry.intersections.FixedFaces` of :meth:`surroundings`' faces.

        Built on first use: a filter checks many patches of one hole against the same faces
        (its crossing checks read the faces' bounds from here).
        """
        return FixedFaces(*self.surroundings())

    def ring_mask(self, max_depth):
        """Boolean mask of local vertices with 0 < depth <= max_depth."""
        return (self.depth > 0) & (self.depth <= max_depth)


def incident_faces(incidence, vertices):
    """The faces holding at least one of ``vertices``, sorted and unique (of incidence's index type).

    The union of the incidence rows, read straight from the CSR arrays: the same faces as
    ``np.unique(incidence[vertices].indices)`` without building a sparse sub-matrix (scipy's
    row selection was 40% of :func:`hole_context` on face000.ply).

    Parameters
    ----------
    incidence : (n, m) scipy.sparse.csr_matrix
        :func:`vertex_face_incidence`.
    vertices : (k,) int

    Returns
    -------
    (f,) int32 or int64
    """
    vertices = np.asarray(vertices, np.int64)
    starts = incidence.indptr[vertices].astype(np.int64)
    counts = incidence.indptr[vertices + 1] - starts
    first = np.cumsum(counts) - counts  # where each row begins among the gathered entries
    positions = np.repeat(starts - first, counts) + np.arange(int(counts.sum()))
    return unique_ints(incidence.indices[positions])


def hole_context(V, F, loop, incidence=None, rings=3, index=0, obstacles=None):
    """Build the HoleContext of one boundary loop.

    Cost is proportional to the size of the neighbourhood, not of the mesh, once the
    vertex-face incidence has been built.

    Parameters
    ----------
    V : (N, 3) float64
    F : (M, 3) int
    loop : BoundaryLoop
    incidence : scipy.sparse.csr_matrix, optional
        ``vertex_face_incidence(F, len(V))``, shared between holes.
    rings : int
        Number of face rings around the loop to include (>= 1).
    index : int
        Position of the hole in the filter's hole list.
    obstacles : (r,) int, optional
        Mesh face indices a patch must not cross beyond the rings (those already in the rings
        are left out), for :attr:`HoleContext.obstacle_faces`.
    """
    F = np.asarray(F)  # int32 or int64: only the local rows are gathered, never the whole array converted
    if incidence is None:
        incidence = vertex_face_incidence(F, len(V))
    loop_v = np.asarray(loop.vertices, np.int64)
    k = len(loop_v)
    _refuse_coincident_border_vertices(np.asarray(V[loop_v], np.float64), loop_v)
    depth_parts = [np.zeros(k, np.int64)]
    vertex_parts = [loop_v]
    frontier = loop_v
    face_sets = []
    for r in range(1, max(rings, 1) + 1):
        fidx = incident_faces(incidence, frontier)
        face_sets.append(fidx)
        new = setdiff_ints(F[fidx], np.concatenate(vertex_parts)).astype(np.int64)
        vertex_parts.append(new)
        depth_parts.append(np.full(len(new), r, np.int64))
        frontier = new
        if len(frontier) == 0:
            break
    local_faces_g = unique_ints(np.concatenate(face_sets))
    global_index = np.concatenate(vertex_parts)
    depth = np.concatenate(depth_parts)
    faces = positions_ints(global_index, F[local_faces_g]).reshape(-1, 3)
    verts = np.asarray(V[global_index], dtype=np.float64)
    normals = vertex_normals(verts, faces, len(verts))
    border_pos = np.searchsorted(local_faces_g, loop.border_faces)
    border_faces = border_pos.astype(np.int64)

    # Edge scale of loop vertices and forbidden chords, from the edges of local faces.
    a, b = faces.T.ravel(), faces[:, [1, 2, 0]].T.ravel()  # edge (F[f, c], F[f, c + 1]), corner by corner
    # The edges' (smaller, larger) pairs as keys, in the rows' lexicographic order, without unique(axis=0).
    keys = unique_ints(np.minimum(a, b) * len(verts) + np.maximum(a, b))
    E = np.stack([keys // len(verts), keys % len(verts)], axis=1)
    lengths = np.linalg.norm(verts[E[:, 0]] - verts[E[:, 1]], axis=1)
    sums = np.bincount(E.ravel(), weights=np.repeat(lengths, 2), minlength=len(verts))
    cnts = np.bincount(E.ravel(), minlength=len(verts))
    edge_scale = sums[:k] / np.maximum(cnts[:k], 1)
    both_loop = (E[:, 0] < k) & (E[:, 1] < k)
    chord = E[both_loop]
    gap = np.abs(chord[:, 0] - chord[:, 1])
    chord = chord[(gap != 1) & (gap != k - 1)]
    obstacle_vertices, obstacle_faces = _obstacle_faces(V, F, global_index, local_faces_g, obstacles)
    return HoleContext(
        loop=loop_v, points=verts[:k].copy(), vertices=verts, faces=faces,
        global_index=global_index, depth=depth, normals=normals,
        border_faces=border_faces, edge_scale=edge_scale,
        mean_edge_length=float(lengths.mean()) if len(lengths) else 0.0,
        forbidden_edges=chord, pinched=bool(loop.pinched), index=index,
        extra={"global_faces": local_faces_g}, obstacle_vertices=obstacle_vertices, obstacle_faces=obstacle_faces)


#: Loop edges at most this fraction of the loop's box diagonal long are refused: every triangle on
#: such an edge has zero area by :func:`.patch.validate_patch`'s measure (at most 1e-12 diagonal^2)
#: for any apex within 100 diagonals of it, so no patch could close the hole.
ZERO_EDGE = 2e-14


def _refuse_coincident_border_vertices(P, loop_v):
    """Raise HoleFillError, naming them, where two distinct loop vertices coincide (P: (k, 3) loop points).

    Consecutive ones make a zero-length border edge. Others (an unwelded vertex: the border runs
    v -> a -> v' -> b -> v around a face cut loose at a corner) pinch the hole at one position,
    where every patch would touch or overlap itself. Once the vertices are merged the loop is a
    pinched one, which the filters fill, or no hole at all. Coincident means within ``ZERO_EDGE``
    of the loop's box diagonal, tested between neighbours in the rows' sorted order.
    """
    if len(P) == 0:
        return
    # squared lengths against the squared bound: a few small array operations per hole
    tol2 = ZERO_EDGE * ZERO_EDGE * float(((P.max(axis=0) - P.min(axis=0)) ** 2).sum())
    following = np.concatenate([P[1:], P[:1]])
    short = np.flatnonzero(((following - P) ** 2).sum(axis=1) <= tol2)
    if len(short):
        i = int(short[0])
        length = float(np.linalg.norm(following[i] - P[i]))
        raise HoleFillError(
            f"the hole's border has an edge of length {length:.3g} between vertices {loop_v[i]} and "
            f"{loop_v[(i + 1) % len(loop_v)]} (duplicate vertices), so every triangle on it would have zero area: "
            "merge close vertices first (MeshLab's Merge Close Vertices, meshing_merge_close_vertices)")
    order = np.lexsort(P.T[::-1])  # rows sorted by x, then y, then z
    S = P[order]
    same = np.flatnonzero((((S[1:] - S[:-1]) ** 2).sum(axis=1) <= tol2) & (loop_v[order[1:]] != loop_v[order[:-1]]))
    if len(same):
        a, b = sorted((int(loop_v[order[same[0]]]), int(loop_v[order[same[0] + 1]])))
        raise HoleFillError(
            f"the hole's border passes twice through one position: vertices {a} and {b} coincide (duplicate "
            "vertices, an unwelded seam), so every patch would overlap itself there: merge close vertices first "
            "(MeshLab's Merge Close Vertices, meshing_merge_close_vertices)")


def _obstacle_faces(V, F, global_index, ring_faces, obstacles):
    """(vertices (s, 3), faces (r, 3)) of the obstacle faces not in the rings, numbered after the rings' vertices.

    A vertex the rings hold keeps its local number, so that a face touching the rings shares
    that vertex rather than a copy of it.
    """
    if obstacles is None:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    faces = setdiff_ints(np.asarray(obstacles, np.int64), ring_faces)
    used = unique_ints(F[faces]) if len(faces) else np.zeros(0, np.int64)
    beyond = setdiff_ints(used, global_index).astype(np.int64)
    local = positions_ints(np.concatenate([global_index, beyond]), F[faces]).reshape(-1, 3)
    return np.asarray(V[beyond], np.float64), local
