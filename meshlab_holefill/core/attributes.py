"""The mesh as arrays with its per-element attributes, and those attributes carried over to a filled mesh.

Nothing here touches pymeshlab: the pymeshlab layer reads a MeshSet's current mesh into a
:class:`MeshArrays` and writes the filled one back; the array API builds one from (V, F).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshTopologyError
from ._attribute_kernels import idw_interpolated
from .holes import nonmanifold_edges

__all__ = ["MeshArrays", "check_manifold_edges", "check_faces_joined", "extend_attributes", "refine_mesh_arrays"]


@dataclass
class MeshArrays:
    """The current mesh of a MeshSet as arrays, with the per-element attributes it carries.

    Attributes
    ----------
    V : (n, 3) float64, C-ordered copy
    F : (m, 3) int64
    vertex_attrs : dict name -> (n, c) array   (``color``, ``quality``, ``texcoord``)
    face_attrs : dict name -> (m, c) array     (``color``, ``quality``, ``selected``)
    wedge_texcoords : (3m, 2) float64 or None
    label : str
    mesh_id : int
    textures : dict name -> image  (the layer's textures, handed back unchanged)
    transform : (4, 4) float64  the layer's transformation matrix (not applied to V)
    vertex_selected : (n,) bool

    Custom per-vertex and per-face attributes are not read: pymeshlab cannot list their names.
    """

    V: np.ndarray
    F: np.ndarray
    vertex_attrs: dict = field(default_factory=dict)
    face_attrs: dict = field(default_factory=dict)
    wedge_texcoords: np.ndarray | None = None
    label: str = ""
    mesh_id: int = 0
    textures: dict = field(default_factory=dict)
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    vertex_selected: np.ndarray | None = None


def check_manifold_edges(F, label="", bad=None):
    """Raise MeshTopologyError when an edge is shared by more than two faces.

    Where faces that use a vertex twice (such as [a, a, b]) or faces on the same three vertices
    (a face stored twice, in either orientation) are present, the message names them and the
    repair that removes them: they are what makes such edges, most often. Elsewhere in the mesh
    these faces are kept as they are. ``bad`` may pass the non-manifold edges when already
    computed (``holes.edge_summary``).
    """
    bad = nonmanifold_edges(F) if bad is None else bad
    if not len(bad):
        return
    repeats = np.flatnonzero((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0]))
    if len(repeats):
        raise MeshTopologyError(
            f"mesh '{label}' has {len(bad)} non-manifold edges and {len(repeats)} faces that use a vertex twice "
            f"(e.g. face {int(repeats[0])}: vertices {F[repeats[0]].tolist()}); run meshing_remove_null_faces first")
    twins = _faces_stored_twice(F)
    if len(twins):
        raise MeshTopologyError(
            f"mesh '{label}' has {len(bad)} non-manifold edges and {len(twins)} faces stored twice (e.g. faces "
            f"{twins[0].tolist()} on vertices {sorted(F[twins[0][0]].tolist())}); run meshing_remove_duplicate_faces "
            "first")
    raise MeshTopologyError(
        f"mesh '{label}' has {len(bad)} non-manifold edges (e.g. vertices {bad[0].tolist()}); "
        "run meshing_repair_non_manifold_edges first")


def _faces_stored_twice(F):
    """(d, 2) int64: pairs (first, later) of faces on the same three vertices, one row per later copy."""
    keys = np.sort(np.asarray(F, np.int64), axis=1)
    order = np.lexsort(keys.T[::-1])  # rows in sorted order, copies side by side, the first stored first
    same = np.flatnonzero(np.all(keys[order[1:]] == keys[order[:-1]], axis=1))
    if not len(same):
        return np.zeros((0, 2), np.int64)
    runs = np.r_[0, np.flatnonzero(np.diff(same) != 1) + 1]  # each run of copies starts here in ``same``
    first = np.repeat(order[same[runs]], np.diff(np.r_[runs, len(same)]))
    return np.stack([first, order[same + 1]], axis=1)


def check_faces_joined(F, border_halfedges, label=""):
    """Raise MeshTopologyError for a triangle soup: two faces or more, and no vertex shared by two of them.

    Such a mesh (an STL file read without welding its vertices) has a border loop round every
    face and no hole to fill; the message names the repair. ``border_halfedges`` is the count of
    the mesh's border half-edges: only where it is 3 per face (no edge shared) are the vertices
    counted.
    """
    if len(F) < 2 or border_halfedges != 3 * len(F):
        return
    if np.bincount(np.asarray(F).ravel()).max() == 1:
        raise MeshTopologyError(
            f"mesh '{label}' is a triangle soup: its {len(F)} faces share no vertex, so each face is an island of "
            "its own and there is no hole to fill; run meshing_merge_close_vertices (Merge Close Vertices) first")


def _new_values(name, values):
    """Interpolated attribute values as stored: colours on MeshLab's 8-bit grid, the rest as computed.

    MeshLab keeps a colour channel as a byte and pymeshlab truncates c * 255, so an interpolated
    white (0.9999999...) would be stored as 254; rounding to the nearest k / 255 stores what was
    meant (k / 255 * 255 is k exactly in float64, for every byte k).
    """
    return np.round(values * 255.0) / 255.0 if name == "color" else values


def extend_attributes(arrays, V2, F2, loops, new_vertex_counts):
    """Per-element attributes for the filled mesh: originals unchanged, new ones interpolated.

    A new vertex gets the inverse-distance interpolation of its hole's loop-vertex values
    (:func:`._attribute_kernels.idw_interpolated`, every column of a hole in one pass; its sums
    run in loop order, so against a numpy product of the (t, s) weights an interpolated value
    differs in its last bits: face000.ply's vertex quality by at most 2.6e-12 on values up to
    808); a new face gets the mean value of its hole's border faces, each counted once (colours,
    quality), and is unselected; wedge texture coordinates of new corners come from the loop
    vertex's coordinate in a border face, or the interpolation above for new vertices.

    Returns
    -------
    vertex_attrs, face_attrs : dict name -> array
    wedge : (3 m2, 2) float64 or None
    """
    n, m = len(arrays.V), len(arrays.F)
    new_v_owner = np.repeat(np.arange(len(loops)), new_vertex_counts)
    per_vertex = None  # each vertex's wedge texture coordinate, where the mesh has them
    if arrays.wedge_texcoords is not None:
        per_vertex = np.zeros((len(V2), 2))
        # Any original corner's coordinate is a valid one for its vertex (seams aside).
        per_vertex[arrays.F.ravel()] = arrays.wedge_texcoords.reshape(-1, 2)
    sources = list(arrays.vertex_attrs.values()) + ([] if per_vertex is None else [per_vertex])
    widths = np.cumsum([0] + [A.shape[1] for A in sources])
    new_values = np.zeros((len(V2) - n, widths[-1]))  # every interpolated column of every new vertex
    if widths[-1]:  # nothing to interpolate otherwise
        first = np.cumsum([0] + list(new_vertex_counts))  # the new vertices come hole after hole
        for h, loop in enumerate(loops):
            rows = slice(first[h], first[h + 1])
            columns = np.ascontiguousarray(np.concatenate([A[loop] for A in sources], axis=1), np.float64)
            new_values[rows] = idw_interpolated(arrays.V[loop], V2[n:][rows], columns)
    vertex_attrs = {name: np.concatenate([A, _new_values(name, new_values[:, widths[i]:widths[i + 1]])])
                    for i, (name, A) in enumerate(arrays.vertex_attrs.items())}
    new_faces = F2[m:]
    # Hole of each new face: the loop or new vertex it touches.
    vert_owner = np.full(len(V2), -1)
    for h, loop in enumerate(loops):
        vert_owner[loop] = h
    vert_owner[n:] = new_v_owner
    face_owner = vert_owner[new_faces].max(axis=1)
    face_attrs = {}
    border = _border_faces_per_loop(arrays.F, loops, n)
    for name, A in arrays.face_attrs.items():
        if name == "selected":  # bool or float, as given
            face_attrs[name] = np.concatenate([A, np.zeros((len(new_faces), 1), A.dtype)])
            continue
        means = np.array([A[b].mean(axis=0) if len(b) else A.mean(axis=0) for b in border]).reshape(len(loops), -1)
        face_attrs[name] = np.concatenate([A, _new_values(name, means[face_owner])]) if len(new_faces) else A
    wedge = None
    if per_vertex is not None:
        per_vertex[n:] = new_values[:, widths[-2]:]
        wedge = np.concatenate([arrays.wedge_texcoords, per_vertex[new_faces].reshape(-1, 2)])
    return vertex_attrs, face_attrs, wedge


def refine_mesh_arrays(arrays, refinement):
    """The MeshArrays of a border-refined mesh (a ``prepare`` hook's result), attributes carried over.

    Used by filters that split original faces without changing the surface (Xu et al.'s
    boundary edge pre-treatment): original vertices keep positions, order and attributes; a
    new vertex on original edge (a, b) at parameter t gets (1 - t) A[a] + t A[b] (the mean
    of its edge's endpoints for a midpoint); every face takes its parent face's colour,
    quality and selection, and its wedge texture coordinates are the parent's interpolated
    at its corners (which lie on the parent's corners or edges).

    Parameters
    ----------
    arrays : MeshArrays  the mesh before refinement
    refinement : object with ``V``, ``F``, ``edge_vertices`` (s, 2), ``edge_weights`` (s,)
        and ``face_parents`` (m2,), e.g. :class:`meshlab_holefill.algorithms.xu2013.border_split.BorderRefinement`

    Returns
    -------
    MeshArrays  (same label, mesh id, textures, transform and vertex selection; split points unselected)
    """
    n, m = len(arrays.V), len(arrays.F)
    E = np.asarray(refinement.edge_vertices, np.int64).reshape(-1, 2)
    t = np.asarray(refinement.edge_weights, np.float64)[:, None]
    parents = np.asarray(refinement.face_parents, np.int64)
    F2 = np.asarray(refinement.F, np.int64)
    vertex_attrs = {name: np.concatenate([A, _new_values(name, (1.0 - t) * A[E[:, 0]] + t * A[E[:, 1]])])
                    for name, A in arrays.vertex_attrs.items()}
    face_attrs = {name: A[parents] for name, A in arrays.face_attrs.items()}
    wedge = None
    if arrays.wedge_texcoords is not None:
        W0 = arrays.wedge_texcoords.reshape(m, 3, 2)
        W2 = np.concatenate([W0, np.zeros((len(F2) - m, 3, 2))])
        rows = np.flatnonzero((parents != np.arange(len(F2))) | (np.arange(len(F2)) >= m)
                              | np.r_[np.any(F2[:m] != arrays.F, axis=1), np.zeros(len(F2) - m, bool)])
        if len(rows):
            P = arrays.F[parents[rows]]                       # (r, 3) parent corners
            C = F2[rows]                                      # (r, 3) child corners
            is_new = C >= n
            idx = np.where(is_new, C - n, 0)
            a = np.where(is_new, E[idx, 0], C)                # corner on parent edge (a, b) at t
            b = np.where(is_new, E[idx, 1], C)
            tt = np.where(is_new, t[idx, 0], 0.0)
            ca = np.argmax(P[:, None, :] == a[:, :, None], axis=2)
            cb = np.argmax(P[:, None, :] == b[:, :, None], axis=2)
            Wp = W0[parents[rows]]                            # (r, 3, 2)
            r = np.arange(len(rows))[:, None]
            W2[rows] = (1.0 - tt)[..., None] * Wp[r, ca] + tt[..., None] * Wp[r, cb]
        wedge = W2.reshape(-1, 2)
    return MeshArrays(V=np.ascontiguousarray(refinement.V, np.float64), F=F2, vertex_attrs=vertex_attrs,
                      face_attrs=face_attrs, wedge_texcoords=wedge, label=arrays.label,
                      mesh_id=arrays.mesh_id, textures=arrays.textures, transform=arrays.transform,
                      vertex_selected=arrays.vertex_selected)


def _border_faces_per_loop(F, loops, n):
    """For each loop, the faces holding one of its edges.

    Only faces with two vertices on some loop can hold a loop edge; those few are found with
    one gather of bytes over F (``n`` vertices), so no mesh-wide edge sort is needed here
    (1.9 s at 3.6M faces) and F keeps its integer type.
    """
    F = np.asarray(F)
    on_loop = np.zeros(n, np.uint8)
    for loop in loops:
        on_loop[loop] = 1
    candidates = np.flatnonzero(on_loop[F[:, 0]] + on_loop[F[:, 1]] + on_loop[F[:, 2]] >= 2)

    def edge_keys(a):  # undirected keys of the edges (a[..., i], a[..., i + 1]), cyclically
        b = np.roll(a, -1, axis=-1)
        return np.minimum(a, b) * n + np.maximum(a, b)

    face_keys = edge_keys(F[candidates].astype(np.int64))  # (c, 3)
    return [candidates[np.isin(face_keys, edge_keys(np.asarray(loop, np.int64))).any(axis=1)] for loop in loops]
