"""MeshSet <-> numpy arrays: loading, reading the current layer, and putting a filled mesh back in its place."""
from __future__ import annotations

import contextlib
import os
import sys
import tempfile

import numpy as np
import pymeshlab

from ..core.attributes import MeshArrays
from .layer_ply import has_repeated_corners, layer_ply_bytes, unit_range, write_layer_ply
from .scratch_folder import scratch_folder
from .selection import set_selection


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
    F = np.ascontiguousarray(m.face_matrix())  # int32, as pymeshlab holds it: no int64 copy of the whole mesh
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
    arrays.face_attrs["selected"] = np.asarray(m.face_selection_array(), bool)[:, None]
    if m.has_wedge_tex_coord():
        arrays.wedge_texcoords = m.wedge_tex_coord_matrix()
    arrays.textures = dict(m.textures())
    arrays.transform = np.array(m.transform_matrix(), np.float64)
    arrays.vertex_selected = np.asarray(m.vertex_selection_array(), bool)
    return arrays


def replace_current_mesh(ms, arrays, V2, F2, vertex_attrs, face_attrs, wedge, select_faces=None):
    """Put the filled mesh into ``ms`` in place of the current layer: same id, place, name and visibility.

    pymeshlab gives every new layer the next id of a counter that only ``MeshSet.clear()``
    resets, and appends it last. To keep the layer's id and place, the other layers are copied
    to a scratch MeshSet (``add_mesh`` copies a mesh; ``ms.mesh(i)`` is only a reference into
    its layer, dangling once the layer is gone), ``ms`` is cleared, and the
    layers are added back in id order, the filled mesh at the old id, with one-vertex
    placeholder layers added and deleted where ids are missing, up to the id counter as it
    was: every id names the same layer as before and the next new layer gets the id it would
    have had. Copies keep geometry, normals, colours, quality, selections and custom
    attributes; names, visibility, transformation matrices and textures are put back.
    pymeshlab's own filter-script record (``ms.save_filter_script``) is put back as it was,
    without the internal steps (deleting layers, matrices, selections) used here.

    The other layers are all copied before ``ms`` is touched, and compared; when one would
    not come back the same, nothing is rebuilt and the filled layer goes last with a new id,
    as it would with rasters in the MeshSet (see ``note`` below).

    Returns
    -------
    mesh_id : int
        The filled layer's id: the old one, unless the layers could not be rebuilt.
    note : str or None
        Why the filled layer got a new id and went last, when it did: the MeshSet holds
        rasters (which pymeshlab cannot copy; ``MeshSet.clear`` would drop them), or another
        layer has per-vertex normals that ``add_mesh`` would recompute (it recomputes them on
        every copy; normals computed by pymeshlab on loading survive, a file's own or a
        filter's do not). Every other layer is then left untouched.

    The filled layer is loaded from a binary PLY file written here (:func:`.layer_ply.write_layer_ply`),
    which gives the layer ``pymeshlab.Mesh(...)`` and ``add_mesh`` would give, bit for bit
    (positions, faces, colours, quality, texture coordinates, and the normals pymeshlab
    computes), except that it has per-vertex colour and quality only where the old layer had
    them (as after MeshLab's own filters; ``pymeshlab.Mesh`` always adds both), at about half
    the cost: ``pymeshlab.Mesh`` builds the mesh and then copies it inside its constructor,
    and ``add_mesh`` copies it again, while loading builds it once, in its layer. At 3.6M
    faces that is 1.45 s instead of 2.4 s (process time) and a peak of 370 MB instead of
    836 MB above the arrays. The file is written before the old layer is touched and removed
    once the layer is in place; where it cannot be written (no temporary folder, disk full)
    the layer is built with ``pymeshlab.Mesh``.
    One trace of the file stays: a project saved later (``ms.save_project``) names it as the
    layer's file, where a layer built from arrays names none. The file goes to ``/dev/shm``, held
    in memory, where that has room for it twice over, else to the temporary folder
    (:func:`.scratch_folder.scratch_folder`): at 2.7M faces writing it takes 0.08 s there and
    0.27 s to a local disk. The
    layer's selections go into the file as the elements' flags (:data:`.layer_ply.SELECTED_FLAG`)
    rather than as a conditional selection after loading (at 2.7M faces: 0.09 s for the selection, 0.04 s
    more to read the flags).

    Memory: the file is written in blocks of rows; the old layer goes before the filled one
    is loaded; the other layers are held twice while they are copied (a MeshSet of one layer
    costs what it did). Should loading the filled mesh fail, the old layer is put back from
    ``arrays`` before the error propagates.
    """
    target = arrays.mesh_id
    record = filter_record(ms)
    visible = bool(ms.is_mesh_visible(target))
    selections = _selections(arrays, face_attrs, select_faces, len(V2), len(F2))
    size = layer_ply_bytes(len(V2), len(F2), vertex_attrs, face_attrs, wedge, *selections)
    with scratch_folder(size) as tmp:
        source = _layer_source(tmp, V2, F2, vertex_attrs, face_attrs, wedge, selections)
        ms.set_current_mesh(target)
        ms.delete_current_mesh()
        try:
            return _put_layer(ms, arrays, source, selections, visible)
        finally:
            _restore_filter_record(ms, record)


def _layer_source(folder, V, F, vertex_attrs, face_attrs, wedge, selections):
    """What the filled layer is built from: a PLY file in ``folder`` (its path), else the arrays themselves.

    The arrays when there is no folder, and when a face repeats a vertex: pymeshlab's PLY reader
    drops such faces, which ``pymeshlab.Mesh`` keeps (and the originals must stay as they are).
    ``selections`` (:func:`_selections`) go into the file; from arrays they are set after building the layer.
    """
    if folder is None or has_repeated_corners(F):
        return (V, F, vertex_attrs, face_attrs, wedge)
    path = os.path.join(folder, "filled.ply")
    try:
        write_layer_ply(path, V, F, vertex_attrs, face_attrs, wedge, *selections)
    except OSError:  # no space, or no temporary folder: pymeshlab.Mesh builds the layer instead
        return (V, F, vertex_attrs, face_attrs, wedge)
    return path


def _selections(arrays, face_attrs, select_faces, n_vertices, n_faces):
    """(vertex mask, face mask) of the filled layer, each None when nothing is selected.

    The old layer's selected vertices and faces, new vertices unselected, and ``select_faces`` selected.
    """
    vertex_mask = None
    if arrays.vertex_selected is not None and arrays.vertex_selected.any():
        vertex_mask = np.zeros(n_vertices, bool)
        vertex_mask[:len(arrays.vertex_selected)] = arrays.vertex_selected
    face_mask = face_attrs.get("selected", np.zeros((n_faces, 1))).ravel() > 0
    if select_faces is not None and len(select_faces):
        face_mask = face_mask.copy()
        face_mask[np.asarray(select_faces)] = True
    return vertex_mask, (face_mask if face_mask.any() else None)


def layer_kept_note(ms):
    """Why a filled layer cannot keep its id in ``ms`` (None when it can)."""
    if ms.raster_number():
        return ("the MeshSet holds rasters, which pymeshlab cannot copy back after clearing it: the filled layer "
                "got a new id and was put last")
    return None


def mesh_ids(ms):
    """Ids of the layers of ``ms``, in order (pymeshlab lists ids only one by one)."""
    ids, i, n = [], 0, ms.mesh_number()
    while len(ids) < n:
        if ms.mesh_id_exists(i):
            ids.append(i)
        i += 1
    return ids


_PLACEHOLDER = None


def _placeholder():
    global _PLACEHOLDER
    if _PLACEHOLDER is None:
        _PLACEHOLDER = pymeshlab.Mesh(vertex_matrix=np.zeros((1, 3)))
    return _PLACEHOLDER


def _next_mesh_id(ms):
    """The id pymeshlab's counter gives the next layer (found by adding a placeholder layer and deleting it)."""
    current = ms.current_mesh_id() if ms.mesh_number() else None
    ms.add_mesh(_placeholder(), "placeholder", set_as_current=True)
    nxt = ms.current_mesh_id()
    ms.delete_current_mesh()
    if current is not None:
        ms.set_current_mesh(current)
    return nxt


def _put_layer(ms, arrays, mesh, selections, visible):
    """Add the filled ``mesh`` back at ``arrays.mesh_id`` (see :func:`replace_current_mesh`)."""
    target = arrays.mesh_id
    note = layer_kept_note(ms)
    if note:
        new_id, error = _add_filled_layer(ms, arrays, mesh, selections, visible)
        if error is not None:
            raise error
        return new_id, note
    scratch = pymeshlab.MeshSet()
    kept = {}  # id -> (position in scratch, label, visible, transform, textures)
    for position, i in enumerate(mesh_ids(ms)):
        m = ms.mesh(i)
        scratch.add_mesh(m, m.label(), set_as_current=False)
        if not np.array_equal(scratch.mesh(position).vertex_normal_matrix(), m.vertex_normal_matrix()):
            # add_mesh recomputes per-vertex normals: a layer with its own (a scan's, a filter's) would lose them
            scratch.clear()
            note = (f"layer {i} ('{m.label()}') has per-vertex normals that pymeshlab's copy would recompute, so "
                    "the MeshSet could not be rebuilt with the filled layer in its place: it got a new id and was "
                    "put last")
            new_id, error = _add_filled_layer(ms, arrays, mesh, selections, visible)
            if error is not None:
                raise error
            return new_id, note
        kept[i] = (position, m.label(), bool(ms.is_mesh_visible(i)), np.array(m.transform_matrix(), np.float64),
                   dict(m.textures()))
    counter = max(_next_mesh_id(ms), target + 1)
    ms.clear()  # resets the id counter to 0
    error = None
    for i in range(counter):
        if i == target:
            _, error = _add_filled_layer(ms, arrays, mesh, selections, visible)
        elif i in kept:
            position, label, shown, transform, textures = kept[i]
            ms.add_mesh(scratch.mesh(position), label, set_as_current=True)
            _restore_textures(ms, textures)
            if not np.array_equal(transform, np.eye(4)):
                ms.set_matrix(transformmatrix=transform, compose=False, freeze=False)
            if not shown:
                ms.set_current_mesh_visibility(False)
            scratch.set_current_mesh(position)
            scratch.delete_current_mesh()
        else:  # an id whose layer was deleted earlier: keep it unused, as pymeshlab would
            ms.add_mesh(_placeholder(), "placeholder", set_as_current=True)
            ms.delete_current_mesh()
        if (i in kept or i == target) and ms.current_mesh_id() != i:
            raise RuntimeError(f"layer {i} came back as id {ms.current_mesh_id()}")  # pymeshlab changed its ids
    ms.set_current_mesh(target)
    if error is not None:
        raise error
    return target, None


def _add_filled_layer(ms, arrays, source, selections, visible):
    """(layer id, None) once the filled layer is added; (id, error) when it could not be, the old layer added instead.

    The MeshSet is then whole again (the old layer rebuilt from ``arrays`` in the filled one's
    place) when the caller raises the error.
    """
    layers = ms.mesh_number()
    try:
        new_id = _add_layer(ms, arrays, source, selections)
        error = None
    except BaseException as exc:  # e.g. out of memory while loading: the user keeps the mesh they had
        error = exc
        if ms.mesh_number() > layers:  # the layer went in and a later step failed
            ms.delete_current_mesh()
        original = (arrays.V, arrays.F, arrays.vertex_attrs, arrays.face_attrs, arrays.wedge_texcoords)
        new_id = _add_layer(ms, arrays, original, _selections(arrays, arrays.face_attrs, None, len(arrays.V),
                                                                  len(arrays.F)))
    if not visible:
        ms.set_current_mesh_visibility(False)
    return new_id, error


def filter_record(ms):
    """pymeshlab's own filter-script record of ``ms`` (.mlx bytes), or None when it cannot be read."""
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "record.mlx")
            ms.save_filter_script(path)
            with open(path, "rb") as f:
                return f.read()
    except Exception:
        return None


def _restore_filter_record(ms, record):
    """Put back pymeshlab's record saved by :func:`filter_record` (pymeshlab's loader, its chatter silenced)."""
    if record is None:
        return
    load = getattr(pymeshlab.MeshSet.load_filter_script, "pymeshlab_original", pymeshlab.MeshSet.load_filter_script)
    clear = getattr(pymeshlab.MeshSet.clear_filter_script, "pymeshlab_original", pymeshlab.MeshSet.clear_filter_script)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "record.mlx")
        with open(path, "wb") as f:
            f.write(record)
        with _quiet_stderr():  # the C++ loader prints every filter name it reads
            clear(ms)
            if b"<filter" in record:
                load(ms, path)


@contextlib.contextmanager
def _quiet_stderr():
    """Send file descriptor 2 to /dev/null for a moment (C++ output Python cannot redirect otherwise)."""
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError):
        yield
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def _new_mesh(V, F, vertex_attrs, face_attrs, wedge):
    """A pymeshlab.Mesh with the per-vertex, per-face and wedge attributes the layer had."""
    kwargs = {"vertex_matrix": np.asarray(V, np.float64), "face_matrix": np.asarray(F, np.int32)}
    if "color" in vertex_attrs:
        kwargs["v_color_matrix"] = unit_range(vertex_attrs["color"])
    if "quality" in vertex_attrs:
        kwargs["v_scalar_array"] = vertex_attrs["quality"].ravel()
    if "texcoord" in vertex_attrs:
        kwargs["v_tex_coords_matrix"] = vertex_attrs["texcoord"]
    if "color" in face_attrs:
        kwargs["f_color_matrix"] = unit_range(face_attrs["color"])
    if "quality" in face_attrs:
        kwargs["f_scalar_array"] = face_attrs["quality"].ravel()
    if wedge is not None:
        kwargs["w_tex_coords_matrix"] = wedge
    return pymeshlab.Mesh(**kwargs)


def load_layer_file(ms, path, label):
    """Load a file :func:`write_layer_ply` wrote as the new current layer of ``ms``, named ``label``."""
    ms.load_new_mesh(path)
    ms.current_mesh().set_label(label)


def _add_layer(ms, arrays, source, selections):
    """Add a layer with the old layer's name, textures, matrix and selections, from ``source``.

    ``source``: a pymeshlab.Mesh, the path of a file :func:`write_layer_ply` wrote, or
    (V, F, vertex_attrs, face_attrs, wedge) arrays for :func:`_new_mesh`; ``selections`` the layer's
    (:func:`_selections`), which a file already carries.
    """
    if isinstance(source, str):
        load_layer_file(ms, source, arrays.label)
    else:
        mesh = source if isinstance(source, pymeshlab.Mesh) else _new_mesh(*source)
        ms.add_mesh(mesh, arrays.label, set_as_current=True)
        del mesh
    _restore_textures(ms, arrays.textures)
    if not np.array_equal(arrays.transform, np.eye(4)):
        # the layer's placement in the scene (V is in the layer's own frame)
        ms.set_matrix(transformmatrix=arrays.transform, compose=False, freeze=False)
    if not isinstance(source, str):  # a file carries its selections
        vertex_mask, face_mask = selections
        if vertex_mask is not None:
            set_selection(ms, vertex_mask, "vertex")
        if face_mask is not None:
            set_selection(ms, face_mask)
    return ms.current_mesh_id()


def _restore_textures(ms, textures):
    """Re-attach texture images (pymeshlab.Mesh cannot take them in its constructor)."""
    if not textures:
        return
    with tempfile.TemporaryDirectory() as tmp:
        for name, image in textures.items():
            path = os.path.join(tmp, os.path.basename(name) or "texture.png")
            image.save(path)
            ms.set_texture_per_mesh(textname=path)


_WRITABLE = {}  # extension -> error text or None, from a trial save


def check_mesh_output_path(path):
    """Refuse, before any work, an output path pymeshlab could not write a mesh to.

    Raises
    ------
    ValueError
        No extension, or one pymeshlab cannot save (found by saving a triangle in a scratch
        folder once per extension), or a folder that does not exist or is not writable.
    """
    folder = os.path.dirname(os.path.abspath(path)) or "."
    ext = os.path.splitext(path)[1].lower()
    if not ext:
        raise ValueError(f"output '{path}' has no extension: give a mesh format, e.g. .ply, .obj, .stl, .off")
    if ext not in _WRITABLE:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.eye(3), face_matrix=np.array([[0, 1, 2]], np.int32)), "check")
        with tempfile.TemporaryDirectory() as tmp:
            try:
                ms.save_current_mesh(os.path.join(tmp, "check" + ext))
                _WRITABLE[ext] = None
            except Exception as exc:  # pymeshlab: "Unknown format for save: ..."
                _WRITABLE[ext] = str(exc)
    if _WRITABLE[ext] is not None:
        raise ValueError(f"output '{path}': pymeshlab cannot write '{ext}' files ({_WRITABLE[ext]})")
    if not os.path.isdir(folder):
        raise ValueError(f"output '{path}': folder '{folder}' does not exist")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"output '{path}': folder '{folder}' is not writable")
