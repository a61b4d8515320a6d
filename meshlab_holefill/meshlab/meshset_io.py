"""MeshSet <-> numpy arrays, and putting a filled mesh back as the current layer.

Only this module and ``registry.py`` touch pymeshlab objects.
"""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field

import numpy as np
import pymeshlab

from ..core.holes import MeshTopologyError, nonmanifold_edges


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
    textures : dict name -> pymeshlab.Image
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


def current_mesh_exists(ms):
    """Does the MeshSet's current mesh id name a mesh? (pymeshlab's filters crash when it does not.)"""
    try:
        return bool(ms.mesh_id_exists(ms.current_mesh_id()))
    except pymeshlab.PyMeshLabException:  # "MeshSet has no current Mesh."
        return False


def current_mesh_arrays(ms):
    """Read the current mesh of ``ms`` into a MeshArrays, checking it can be hole-filled.

    Raises
    ------
    ValueError
        Empty MeshSet, point cloud, mesh without faces, NaN/inf coordinates.
    """
    if not isinstance(ms, pymeshlab.MeshSet):
        raise TypeError(f"expected a pymeshlab.MeshSet, got {type(ms).__name__}")
    if ms.mesh_number() == 0:
        raise ValueError("the MeshSet is empty: load a mesh first")
    if not current_mesh_exists(ms):
        raise ValueError("the MeshSet has no valid current mesh")
    m = ms.current_mesh()
    if m.face_number() == 0 or m.is_point_cloud():
        raise ValueError(f"mesh '{m.label()}' is a point cloud (no faces): there are no holes to fill")
    V = np.ascontiguousarray(m.vertex_matrix(), dtype=np.float64)
    F = np.ascontiguousarray(m.face_matrix(), dtype=np.int64)
    if not np.all(np.isfinite(V)):
        bad = int(np.count_nonzero(~np.isfinite(V).all(axis=1)))
        raise ValueError(f"mesh '{m.label()}' has {bad} vertices with NaN or infinite coordinates")
    arrays = MeshArrays(V=V, F=F, label=m.label(), mesh_id=m.id())
    if m.has_vertex_color():
        arrays.vertex_attrs["color"] = m.vertex_color_matrix()
    if m.has_vertex_scalar():
        arrays.vertex_attrs["quality"] = m.vertex_scalar_array()[:, None]
    if m.has_vertex_tex_coord():
        arrays.vertex_attrs["texcoord"] = m.vertex_tex_coord_matrix()
    if m.has_face_color():
        arrays.face_attrs["color"] = m.face_color_matrix()
    if m.has_face_scalar():
        arrays.face_attrs["quality"] = m.face_scalar_array()[:, None]
    arrays.face_attrs["selected"] = m.face_selection_array().astype(np.float64)[:, None]
    if m.has_wedge_tex_coord():
        arrays.wedge_texcoords = m.wedge_tex_coord_matrix()
    arrays.textures = dict(m.textures())
    arrays.transform = np.array(m.transform_matrix(), np.float64)
    arrays.vertex_selected = np.asarray(m.vertex_selection_array(), bool)
    return arrays


def check_manifold_edges(F, label="", bad=None):
    """Raise MeshTopologyError when an edge is shared by more than two faces.

    ``bad`` may pass the non-manifold edges when already computed (``holes.edge_summary``).
    """
    bad = nonmanifold_edges(F) if bad is None else bad
    if len(bad):
        raise MeshTopologyError(
            f"mesh '{label}' has {len(bad)} non-manifold edges (e.g. vertices {bad[0].tolist()}); "
            "run meshing_repair_non_manifold_edges first")


def _idw_weights(sources, targets):
    """Inverse-squared-distance weights (t, s) of source points for target points, rows sum to 1."""
    d2 = ((targets[:, None, :] - sources[None, :, :]) ** 2).sum(axis=2)
    w = 1.0 / np.maximum(d2, 1e-300)
    return w / w.sum(axis=1, keepdims=True)


def extend_attributes(arrays, V2, F2, loops, new_vertex_counts):
    """Per-element attributes for the filled mesh: originals unchanged, new ones interpolated.

    A new vertex gets the inverse-distance interpolation of its hole's loop-vertex values;
    a new face gets the mean value of its hole's border faces, each counted once (colours,
    quality), and is unselected; wedge texture coordinates of new corners come from the loop
    vertex's coordinate in a border face, or the interpolation above for new vertices.

    Returns
    -------
    vertex_attrs, face_attrs : dict name -> array
    wedge : (3 m2, 2) float64 or None
    """
    n, m = len(arrays.V), len(arrays.F)
    new_v_owner = np.repeat(np.arange(len(loops)), new_vertex_counts)
    weights = []
    for h, loop in enumerate(loops):
        targets = V2[n:][new_v_owner == h]
        weights.append(_idw_weights(arrays.V[loop], targets) if len(targets) else np.zeros((0, len(loop))))
    vertex_attrs = {}
    for name, A in arrays.vertex_attrs.items():
        parts = [A] + [W @ A[loop] for W, loop in zip(weights, loops)]
        vertex_attrs[name] = np.concatenate(parts) if parts else A
    new_faces = F2[m:]
    # Hole of each new face: the loop or new vertex it touches.
    face_owner = np.full(len(new_faces), -1)
    vert_owner = np.full(len(V2), -1)
    for h, loop in enumerate(loops):
        vert_owner[loop] = h
    vert_owner[n:] = new_v_owner
    face_owner = vert_owner[new_faces].max(axis=1)
    face_attrs = {}
    border = _border_faces_per_loop(arrays.F, loops)
    for name, A in arrays.face_attrs.items():
        if name == "selected":
            face_attrs[name] = np.concatenate([A, np.zeros((len(new_faces), 1))])
            continue
        means = np.array([A[b].mean(axis=0) if len(b) else A.mean(axis=0) for b in border]).reshape(len(loops), -1)
        face_attrs[name] = np.concatenate([A, means[face_owner]]) if len(new_faces) else A
    wedge = None
    if arrays.wedge_texcoords is not None:
        W0 = arrays.wedge_texcoords.reshape(m, 3, 2)
        per_vertex = np.zeros((len(V2), 2))
        # Any original corner's coordinate is a valid one for its vertex (seams aside).
        per_vertex[arrays.F.ravel()] = W0.reshape(-1, 2)
        for h, (W, loop) in enumerate(zip(weights, loops)):
            per_vertex[n:][new_v_owner == h] = W @ per_vertex[loop]
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
    vertex_attrs = {name: np.concatenate([A, (1.0 - t) * A[E[:, 0]] + t * A[E[:, 1]]])
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


def _border_faces_per_loop(F, loops):
    """For each loop, the faces holding one of its edges.

    Only faces with two vertices on some loop can hold a loop edge; those few are found with
    one gather over F, so no mesh-wide edge sort is needed here (1.9 s at 3.6M faces).
    """
    F = np.asarray(F, np.int64)
    on_loop = np.zeros(int(F.max()) + 1 if F.size else 0, bool)
    for loop in loops:
        on_loop[loop] = True
    candidates = np.flatnonzero(on_loop[F].sum(axis=1) >= 2)
    n = len(on_loop)

    def edge_keys(a):  # undirected keys of the edges (a[..., i], a[..., i + 1]), cyclically
        b = np.roll(a, -1, axis=-1)
        return np.minimum(a, b) * n + np.maximum(a, b)

    face_keys = edge_keys(F[candidates])  # (c, 3)
    return [candidates[np.isin(face_keys, edge_keys(np.asarray(loop, np.int64))).any(axis=1)] for loop in loops]


def replace_current_mesh(ms, arrays, V2, F2, vertex_attrs, face_attrs, wedge, select_faces=None):
    """Put the filled mesh into ``ms`` in place of the current layer, keeping its name.

    The old layer is removed and the new one becomes current; other layers are untouched.
    Face selection: the original selection is kept on original faces, and faces in
    ``select_faces`` (indices into F2) are added to it.

    The old layer goes first: the new ``pymeshlab.Mesh`` and the MeshSet's copy of it already
    hold the mesh twice, and the old layer beside them would be a third (measured at 3.6M
    faces: 836 MB above the start instead of 480). Should building the new mesh fail, the
    old layer is put back from ``arrays`` before the error propagates.
    """
    ms.set_current_mesh(arrays.mesh_id)
    ms.delete_current_mesh()
    try:
        mesh = _new_mesh(V2, F2, vertex_attrs, face_attrs, wedge)
    except BaseException:
        original = _new_mesh(arrays.V, arrays.F, arrays.vertex_attrs, arrays.face_attrs, arrays.wedge_texcoords)
        _add_layer(ms, arrays, original, arrays.face_attrs)
        raise
    return _add_layer(ms, arrays, mesh, face_attrs, select_faces)


def _new_mesh(V, F, vertex_attrs, face_attrs, wedge):
    """A pymeshlab.Mesh with the per-vertex, per-face and wedge attributes the layer had."""
    kwargs = {"vertex_matrix": np.asarray(V, np.float64), "face_matrix": np.asarray(F, np.int32)}
    if "color" in vertex_attrs:
        kwargs["v_color_matrix"] = np.clip(vertex_attrs["color"], 0.0, 1.0)
    if "quality" in vertex_attrs:
        kwargs["v_scalar_array"] = vertex_attrs["quality"].ravel()
    if "texcoord" in vertex_attrs:
        kwargs["v_tex_coords_matrix"] = vertex_attrs["texcoord"]
    if "color" in face_attrs:
        kwargs["f_color_matrix"] = np.clip(face_attrs["color"], 0.0, 1.0)
    if "quality" in face_attrs:
        kwargs["f_scalar_array"] = face_attrs["quality"].ravel()
    if wedge is not None:
        kwargs["w_tex_coords_matrix"] = wedge
    return pymeshlab.Mesh(**kwargs)


def _add_layer(ms, arrays, mesh, face_attrs, select_faces=None):
    """Add ``mesh`` as the current layer with the old layer's name, textures, matrix and selections."""
    ms.add_mesh(mesh, arrays.label, set_as_current=True)
    _restore_textures(ms, arrays.textures)
    if not np.array_equal(arrays.transform, np.eye(4)):
        # the layer's placement in the scene (V is in the layer's own frame)
        ms.set_matrix(transformmatrix=arrays.transform, compose=False, freeze=False)
    n_vertices, n_faces = mesh.vertex_number(), mesh.face_number()
    if arrays.vertex_selected is not None and arrays.vertex_selected.any():
        keep = np.zeros(n_vertices, bool)
        keep[:len(arrays.vertex_selected)] = arrays.vertex_selected  # new vertices unselected
        set_selection(ms, keep, "vertex")
    selected = face_attrs.get("selected", np.zeros((n_faces, 1))).ravel() > 0
    if select_faces is not None and len(select_faces):
        selected = selected.copy()
        selected[np.asarray(select_faces)] = True
    if selected.any():
        set_selection(ms, selected)
    return ms.current_mesh_id()


MAX_SELECTION_RANGES = 256  # index ranges written into one selection condition (about 30 characters each)


def index_ranges(mask):
    """Runs of True in a boolean mask as half-open (start, stop) index pairs, in order."""
    mask = np.asarray(mask, bool).ravel()
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.view(np.int8), [0]])))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def set_selection(ms, selected, element="face"):
    """Select exactly the faces (or vertices, ``element="vertex"``) where ``selected`` is True.

    pymeshlab's selections are read-only arrays, so a conditional selection writes them. The
    condition names index ranges (``fi`` / ``vi``, the element's index), which covers the usual
    masks (new faces at the end, a few selected blocks) and leaves nothing behind on the layer.
    A mask of more than MAX_SELECTION_RANGES runs goes in as a custom scalar attribute
    ``holefill_select`` instead, which then stays on the layer (pymeshlab cannot remove one).
    """
    m = ms.current_mesh()
    ranges = index_ranges(selected)
    if len(ranges) <= MAX_SELECTION_RANGES:
        index = "fi" if element == "face" else "vi"
        condition = " || ".join(f"({index} >= {a} && {index} < {b})" for a, b in ranges) or "0"
    else:
        getattr(m, f"add_{element}_custom_scalar_attribute")(np.asarray(selected, np.float64), "holefill_select")
        condition = "holefill_select > 0"
    getattr(ms, f"compute_selection_by_condition_per_{element}")(condselect=condition)


def _restore_textures(ms, textures):
    """Re-attach texture images (pymeshlab.Mesh cannot take them in its constructor)."""
    if not textures:
        return
    with tempfile.TemporaryDirectory() as tmp:
        for name, image in textures.items():
            path = os.path.join(tmp, os.path.basename(name) or "texture.png")
            image.save(path)
            ms.set_texture_per_mesh(textname=path)
