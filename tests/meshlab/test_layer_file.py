"""layer_ply.write_layer_ply: a filled layer loaded from its PLY file is the layer pymeshlab.Mesh + add_mesh builds
(less the per-vertex colour and quality pymeshlab.Mesh adds where the arrays have none)."""
import os

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.meshlab.layer_ply import layer_ply_bytes, write_layer_ply
from meshlab_holefill.meshlab.meshset_io import _new_mesh, load_layer_file
from meshlab_holefill.meshlab.selection import set_selection

GETTERS = ("vertex_matrix", "face_matrix", "vertex_color_matrix", "face_color_matrix", "vertex_scalar_array",
           "face_scalar_array", "vertex_tex_coord_matrix", "wedge_tex_coord_matrix", "vertex_normal_matrix",
           "face_normal_matrix", "vertex_selection_array", "face_selection_array")
# pymeshlab.Mesh's per-vertex colour and quality (white and 0) where the arrays have none
ADDED_BY_MESH = {"vertex_color_matrix": "color", "vertex_scalar_array": "quality"}
FLAGS = ("has_vertex_color", "has_vertex_scalar", "has_vertex_tex_coord", "has_face_color", "has_face_scalar",
         "has_wedge_tex_coord")


def _grid(n=12, seed=0, repeated_corner=False):
    """A bumpy grid with an unreferenced vertex and zero-area faces (collinear corners, one corner twice) at the end."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    V = np.column_stack([x.ravel(), y.ravel(), rng.normal(scale=0.3, size=n * n)])
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).ravel()
    F = np.concatenate([np.column_stack([a, a + 1, a + n + 1]), np.column_stack([a, a + n + 1, a + n])])
    V = np.vstack([V, [[100.0, 100.0, 100.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [2.0, 0.0, 0.0]]])
    F = np.vstack([F, [[n * n + 1, n * n + 2, n * n + 3]]])  # vertex n * n is referenced by no face
    if repeated_corner:
        F = np.vstack([F, [[0, 1, 0]]])
    return V, F.astype(np.int32)


def _attributes(kind, V, F, rng):
    n, m = len(V), len(F)
    vertex, face, wedge = {}, {}, None
    if kind in ("vertex", "all"):
        vertex["color"] = rng.uniform(-0.2, 1.2, (n, 4))  # out of range too: clipped as pymeshlab needs
        vertex["quality"] = rng.normal(size=(n, 1))
    if kind in ("face", "all"):
        face["color"] = rng.uniform(0, 1, (m, 4))
        face["quality"] = rng.normal(size=(m, 1))
    if kind in ("texture", "all"):
        vertex["texcoord"] = rng.uniform(0, 1, (n, 2))
        wedge = rng.uniform(0, 1, (3 * m, 2))
    face["selected"] = np.zeros((m, 1), bool)  # not a layer attribute: set by selection afterwards
    return vertex, face, wedge


def _matrices(m):
    out = {}
    for getter in GETTERS:
        try:
            out[getter] = getattr(m, getter)()
        except pymeshlab.MissingComponentException:
            out[getter] = "missing"
    return out


@pytest.mark.parametrize("selected", [False, True])
@pytest.mark.parametrize("kind", ["plain", "vertex", "face", "texture", "all"])
def test_the_loaded_layer_equals_the_built_one_bit_for_bit(tmp_path, kind, selected):
    V, F = _grid()
    rng = np.random.default_rng(1)
    vertex, face, wedge = _attributes(kind, V, F, rng)
    masks = (rng.random(len(V)) < 0.3, rng.random(len(F)) < 0.5) if selected else (None, None)
    built = pymeshlab.MeshSet()
    built.add_mesh(_new_mesh(V, F, vertex, face, wedge), "layer")
    if selected:  # the way a layer built from arrays gets its selections
        set_selection(built, masks[0], "vertex")
        set_selection(built, masks[1])
    loaded = pymeshlab.MeshSet()
    path = str(tmp_path / "filled.ply")
    write_layer_ply(path, V, F, vertex, face, wedge, *masks)
    assert os.path.getsize(path) - layer_ply_bytes(len(V), len(F), vertex, face, wedge, *masks) < 1024
    load_layer_file(loaded, path, "layer")
    a, b = built.current_mesh(), loaded.current_mesh()
    assert b.label() == "layer" and b.vertex_number() == len(V) and b.face_number() == len(F)
    # pymeshlab.Mesh always adds per-vertex colour and quality; the file carries those the arrays have
    assert a.has_vertex_color() and a.has_vertex_scalar()
    assert (b.has_vertex_color(), b.has_vertex_scalar()) == ("color" in vertex, "quality" in vertex)
    assert [getattr(a, f)() for f in FLAGS[2:]] == [getattr(b, f)() for f in FLAGS[2:]]
    ma, mb = _matrices(a), _matrices(b)
    for getter in GETTERS:
        if getter in ADDED_BY_MESH and ADDED_BY_MESH[getter] not in vertex:
            continue  # only the built layer has it
        if isinstance(ma[getter], str) or isinstance(mb[getter], str):
            assert ma[getter] == mb[getter], getter
        else:
            assert ma[getter].dtype == mb[getter].dtype and np.array_equal(ma[getter], mb[getter]), getter


def test_a_layer_file_is_written_in_blocks(tmp_path, monkeypatch):
    from meshlab_holefill.meshlab import layer_ply

    V, F = _grid(20)
    vertex, face, wedge = _attributes("all", V, F, np.random.default_rng(2))
    whole, blocks = str(tmp_path / "whole.ply"), str(tmp_path / "blocks.ply")
    masks = (np.arange(len(V)) % 3 == 0, np.arange(len(F)) % 4 == 1)
    write_layer_ply(whole, V, F, vertex, face, wedge, *masks)
    monkeypatch.setattr(layer_ply, "PLY_BLOCK_ROWS", 7)  # blocks ending inside both elements
    write_layer_ply(blocks, V, F, vertex, face, wedge, *masks)
    with open(whole, "rb") as a, open(blocks, "rb") as b:
        assert a.read() == b.read()


def test_a_face_naming_a_vertex_twice_keeps_the_layer_built_from_arrays():
    from meshlab_holefill.meshlab.layer_ply import has_repeated_corners
    from meshlab_holefill.meshlab.meshset_io import replace_current_mesh, current_mesh_arrays

    V, F = _grid(repeated_corner=True)
    assert has_repeated_corners(F) and not has_repeated_corners(_grid()[1])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F), "grid")
    arrays = current_mesh_arrays(ms)
    replace_current_mesh(ms, arrays, V, F, arrays.vertex_attrs, arrays.face_attrs, None)
    m = ms.current_mesh()  # PLY's reader would have dropped the last face
    assert m.face_number() == len(F) and np.array_equal(m.face_matrix(), F) and m.label() == "grid"
