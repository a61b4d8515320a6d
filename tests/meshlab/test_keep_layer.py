"""After one of our filters the filled layer keeps the current layer's id and place."""
import numpy as np
import pymeshlab
import pytest

import meshlab_holefill  # noqa: F401
from meshlab_holefill.meshlab.meshset_io import mesh_ids
from meshlab_holefill.meshlab.progress import reporting

from conftest import sample

NAME = "meshing_close_holes_min_angle_bilateral"


def _layers():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))  # 0: five holes
    ms.load_new_mesh(sample("colored_airplane.ply"))  # 1
    ms.compute_selection_by_condition_per_face(condselect="fi < 100")
    ms.set_matrix(transformmatrix=np.diag([2.0, 1.0, 1.0, 1.0]), compose=False, freeze=False)
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.arange(ms.current_mesh().vertex_number(), dtype=float),
                                                         "mine")
    ms.load_new_mesh(sample("bunny10k_textured.obj"))  # 2: textured, hidden
    ms.set_current_mesh_visibility(False)
    ms.set_current_mesh(0)
    return ms


def _snapshot(ms, i):
    m = ms.mesh(i)
    return {"label": m.label(), "V": m.vertex_matrix().copy(), "F": m.face_matrix().copy(),
            "visible": ms.is_mesh_visible(i), "T": m.transform_matrix().copy(),
            "face_selection": m.face_selection_array().copy(), "textures": sorted(m.textures()),
            "vertex_normals": m.vertex_normal_matrix().copy(), "face_normals": m.face_normal_matrix().copy(),
            "wedge": m.wedge_tex_coord_matrix().copy() if m.has_wedge_tex_coord() else None}


def _same(a, b):
    return all(np.array_equal(a[k], b[k]) if isinstance(a[k], np.ndarray) else a[k] == b[k] for k in a)


@pytest.mark.parametrize("name", meshlab_holefill.filter_list())
def test_filled_layer_keeps_its_id_and_place(name):
    """Reproduced first: layers 0, 1, 2 with 0 current became 1, 2, 3 and ms.mesh(0) raised 'Mesh ID 0 not found'."""
    ms = _layers()
    before = {i: _snapshot(ms, i) for i in (1, 2)}
    res = getattr(ms, name)(maxholesize=40)
    assert res["closed_holes"] >= 1
    assert mesh_ids(ms) == [0, 1, 2]
    assert ms.current_mesh_id() == 0 and res["mesh_id"] == 0 and "layer_note" not in res
    filled = ms.mesh(0)
    assert filled.face_number() == 9999 + res["new_faces"] + res.get("split_boundary_edges", 0) and filled.label() == "bunny10k_textured.obj"
    assert filled.texture_number() == 1
    for i in (1, 2):
        assert _same(before[i], _snapshot(ms, i)), i
    assert np.array_equal(ms.mesh(1).vertex_custom_scalar_attribute_array("mine"),
                          np.arange(ms.mesh(1).vertex_number(), dtype=float))
    ms.create_cube()
    assert ms.current_mesh_id() == 3  # the id counter goes on as pymeshlab's would


def test_ids_of_deleted_layers_stay_unused_and_the_record_is_as_it_was(tmp_path):
    ms = pymeshlab.MeshSet()
    ms.create_cube()  # 0, deleted below
    ms.load_new_mesh(sample("bunny10k_textured.obj"))  # 1
    ms.create_sphere()  # 2, deleted below
    ms.load_new_mesh(sample("colored_airplane.ply"))  # 3
    ms.set_current_mesh(0)
    ms.delete_current_mesh()
    ms.set_current_mesh(2)
    ms.delete_current_mesh()
    ms.set_current_mesh(1)
    ms.save_filter_script(str(tmp_path / "before.mlx"))
    res = getattr(ms, NAME)(iterations=1)
    assert res["mesh_id"] == 1 and mesh_ids(ms) == [1, 3] and ms.current_mesh_id() == 1
    assert ms.mesh(3).label() == "colored_airplane.ply"
    with pytest.raises(pymeshlab.PyMeshLabException, match="not found"):
        ms.mesh(0)
    ms.save_filter_script(str(tmp_path / "after.mlx"))
    # pymeshlab's own record holds no Delete Current Mesh or other internal step of ours
    assert (tmp_path / "before.mlx").read_text() == (tmp_path / "after.mlx").read_text()
    ms.create_cube()
    assert ms.current_mesh_id() == 4


def test_a_later_filter_naming_layers_by_id_still_finds_them():
    ms = _layers()
    getattr(ms, NAME)(iterations=1)
    ms.set_current_mesh(2)
    res = ms.get_hausdorff_distance(sampledmesh=2, targetmesh=0)
    assert res["max"] >= 0.0


def test_with_rasters_the_layer_gets_a_new_id_and_the_result_says_so():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    ms.load_new_mesh(sample("colored_airplane.ply"))
    ms.load_new_raster(sample("TextureDouble_A.png"))
    ms.set_current_mesh(0)
    res = getattr(ms, NAME)(iterations=1)
    assert ms.raster_number() == 1
    assert res["mesh_id"] == 2 == ms.current_mesh_id() and mesh_ids(ms) == [1, 2]
    assert "rasters" in res["layer_note"]


def test_nothing_to_fill_leaves_the_layer_where_it_is():
    ms = _layers()
    ms.create_sphere()  # 3, closed
    res = getattr(ms, NAME)()
    assert res["mesh_id"] == 3 and mesh_ids(ms) == [0, 1, 2, 3] and ms.current_mesh_id() == 3


def test_progress_reaches_the_pipeline_from_a_filter_call():
    calls = []
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    with reporting(lambda hole, total: calls.append((hole, total))):
        res = getattr(ms, NAME)(iterations=1, workers=1)
    closed = [h["hole"] for h in res["holes"] if h["status"] == "closed"]
    assert sorted(h for h, _ in calls) == sorted(closed) and {t for _, t in calls} == {len(closed)}
    getattr(ms, NAME)(iterations=1)  # outside the block: no callback
    assert len(calls) == len(closed)


def test_a_layer_whose_own_normals_a_copy_would_lose_is_left_alone_and_the_filled_layer_goes_last():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    ms.create_sphere()  # unit normals of its own; pymeshlab's add_mesh recomputes them (area-weighted)
    normals = ms.current_mesh().vertex_normal_matrix().copy()
    ms.set_current_mesh(0)
    res = getattr(ms, NAME)(iterations=1)
    assert res["mesh_id"] == 2 == ms.current_mesh_id() and mesh_ids(ms) == [1, 2]
    assert "per-vertex normals" in res["layer_note"]
    assert np.array_equal(ms.mesh(1).vertex_normal_matrix(), normals)
