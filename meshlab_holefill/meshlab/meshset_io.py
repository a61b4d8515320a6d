"""MeshSet <-> numpy arrays: loading, reading the current layer, and putting a filled mesh back in its place."""
from __future__ import annotations

import os
import tempfile

import numpy as np
import pymeshlab

from ..core.attributes import MeshArrays


def load_meshset(path):
    """A new MeshSet with the mesh file at ``path`` loaded as its current layer."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path)
    return ms


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
