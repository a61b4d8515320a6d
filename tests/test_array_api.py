"""meshlab_holefill.fill_holes: the pipeline on (V, F) arrays, the same meshes as the MeshSet filters."""
import numpy as np
import pytest
import pymeshlab

import meshlab_holefill
from conftest import meshset_from_arrays, sphere_with_holes
from meshlab_holefill.array_api import algorithm_names, fill_holes
from meshlab_holefill.core.examples import bowl_with_hole
from meshlab_holefill.core.holes import boundary_loops


@pytest.fixture(scope="module")
def holed_sphere():
    V, F, _ = sphere_with_holes(subdiv=3)
    return V, F


@pytest.mark.parametrize("name", meshlab_holefill.algorithm_names())
def test_the_arrays_get_the_same_mesh_as_the_meshset_filter(holed_sphere, name):
    V, F = holed_sphere
    V2, F2, result = meshlab_holefill.fill_holes(V, F, name)
    assert result["closed_holes"] == 2 and len(boundary_loops(F2)) == 0
    np.testing.assert_array_equal(V2[:len(V)], V)
    ms = meshset_from_arrays(V, F)
    getattr(ms, meshlab_holefill.algorithms.find_algorithm(name).filter_name)()
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(), V2)
    np.testing.assert_array_equal(ms.current_mesh().face_matrix(), F2)


def test_the_filter_name_is_accepted_too_and_parameters_are_validated(holed_sphere):
    V, F = holed_sphere
    _, _, result = meshlab_holefill.fill_holes(V, F, "meshing_close_holes_curve_unfolding", maxholesize=5)
    assert [h["status"] for h in result["holes"]] == ["skipped", "skipped"]
    with pytest.raises(meshlab_holefill.FilterParameterError, match="has no parameter 'sigma'"):
        meshlab_holefill.fill_holes(V, F, "min_angle_bilateral", sigma=1)
    with pytest.raises(meshlab_holefill.FilterParameterError, match="unknown algorithm 'liepa'; valid: min_angle"):
        meshlab_holefill.fill_holes(V, F, "liepa")


def test_selected_faces_choose_the_holes(holed_sphere):
    V, F = holed_sphere
    loops = boundary_loops(F)
    selected = np.zeros(len(F), bool)
    selected[loops[0].border_faces] = True
    _, _, result = meshlab_holefill.fill_holes(V, F, selected_faces=selected, selected=True)
    assert [h["status"] for h in result["holes"]] == ["closed", "skipped"]
    with pytest.raises(ValueError, match="selected_faces has 3 entries"):
        meshlab_holefill.fill_holes(V, F, selected_faces=[True, False, True])


@pytest.mark.parametrize("V, F, message", [
    (np.zeros((4, 2)), np.array([[0, 1, 2]]), r"V must be an \(n, 3\) array"),
    (np.zeros((4, 3)), np.array([[0, 1]]), r"F must be an \(m, 3\) array"),
    (np.zeros((4, 3)), np.zeros((0, 3), int), "no faces"),
    (np.zeros((4, 3)), np.array([[0, 1, 7]]), "F refers to vertex 7, outside 0..3"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), np.array([[0, 1, 2]]), "1 vertices with NaN"),
    (np.zeros((4, 3)), np.array([[0.0, 1.0, 2.0]]), "vertex indices"),
])
def test_bad_arrays_are_refused_naming_the_problem(V, F, message):
    with pytest.raises(ValueError, match=message):
        meshlab_holefill.fill_holes(V, F)


def test_non_manifold_edges_are_refused_and_the_arrays_are_untouched():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    before = F.copy()
    with pytest.raises(meshlab_holefill.MeshTopologyError, match="non-manifold edges"):
        meshlab_holefill.fill_holes(V, F)
    np.testing.assert_array_equal(F, before)


def test_a_face_that_uses_a_vertex_twice_is_refused_by_name_on_arrays_and_on_a_meshset():
    from meshlab_holefill.core.examples import bowl_with_hole

    V, F, _ = bowl_with_hole()
    F = np.vstack([F, [[5, 5, 6]]])
    with pytest.raises(meshlab_holefill.MeshTopologyError, match=r"1 faces that use a vertex twice .*\[5, 5, 6\]"):
        meshlab_holefill.fill_holes(V, F)
    res = refused_on_a_meshset_until_repaired(V, F, "meshing_remove_null_faces")
    assert res["closed_holes"] == 1


@pytest.mark.parametrize("orientation", [1, -1])
def test_a_face_stored_twice_is_refused_by_name_on_arrays_and_on_a_meshset(orientation):
    from meshlab_holefill.core.examples import bowl_with_hole

    V, F, _ = bowl_with_hole()
    F = np.vstack([F, F[7][::orientation]])
    with pytest.raises(meshlab_holefill.MeshTopologyError,
                       match=rf"1 faces stored twice \(e.g. faces \[7, {len(F) - 1}\] on vertices"):
        meshlab_holefill.fill_holes(V, F)
    res = refused_on_a_meshset_until_repaired(V, F, "meshing_remove_duplicate_faces")
    assert res["closed_holes"] == 1


def test_a_triangle_soup_is_refused_by_name_and_the_repair_it_names_makes_it_fillable():
    """Every face with vertices of its own (an STL read without welding): each face is its own island."""
    from meshlab_holefill.core.examples import bowl_with_hole

    V, F, _ = bowl_with_hole()
    soup_V, soup_F = V[F.ravel()], np.arange(3 * len(F)).reshape(-1, 3)
    with pytest.raises(meshlab_holefill.MeshTopologyError, match=rf"triangle soup: its {len(F)} faces share no vertex"):
        meshlab_holefill.fill_holes(soup_V, soup_F)
    res = refused_on_a_meshset_until_repaired(soup_V, soup_F, "meshing_merge_close_vertices")
    assert res["closed_holes"] == 1


def refused_on_a_meshset_until_repaired(V, F, repair):
    """The filter on a MeshSet of (V, F) refuses it naming ``repair`` and loses nothing; after ``repair``
    it runs: its result."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
    with pytest.raises(meshlab_holefill.MeshTopologyError, match=repair):
        ms.meshing_close_holes_min_angle_bilateral()
    assert ms.mesh_number() == 1 and ms.current_mesh().face_number() == len(F)  # nothing lost
    getattr(ms, repair)()  # the repair the message names
    return ms.meshing_close_holes_min_angle_bilateral(maxholesize=100)


def test_two_faces_of_their_own_beside_a_welded_mesh_are_no_soup():
    from meshlab_holefill.core.examples import bowl_with_hole

    V, F, _ = bowl_with_hole()
    n = len(V)
    V2 = np.vstack([V, [[5, 5, 0], [6, 5, 0], [5, 6, 0]]])
    F2 = np.vstack([F, [[n, n + 1, n + 2]]])
    _, _, res = meshlab_holefill.fill_holes(V2, F2, maxholesize=100)
    assert res["closed_holes"] == 1 and "outlines a single face" in res["holes"][-1]["reason"]


def test_the_algorithms_warm_up_runs_once_before_any_hole_is_filled(holed_sphere, monkeypatch):
    # forked workers then inherit the loaded kernels instead of loading them within their first hole
    from meshlab_holefill.algorithms.xu2013 import lssvm_poisson

    calls = []
    monkeypatch.setattr(lssvm_poisson, "WARM_UP", lambda: calls.append("warm"))
    fill = lssvm_poisson.fill
    monkeypatch.setattr(lssvm_poisson, "fill", lambda ctx, **kw: (calls.append("fill"), fill(ctx, **kw))[1])
    V, F = holed_sphere
    _, _, result = meshlab_holefill.fill_holes(V, F, "lssvm_poisson", workers=1)
    assert result["closed_holes"] == 2 and calls == ["warm", "fill", "fill"]
    calls.clear()
    meshlab_holefill.fill_holes(V, F, "lssvm_poisson", maxholesize=3)  # no hole to fill: nothing to load
    assert calls == []


def test_compile_kernels_runs_every_algorithm_and_option_set():
    seconds = meshlab_holefill.compile_kernels(processes=1)
    assert set(seconds) == set(meshlab_holefill.algorithm_names()) | {
        "min_angle_bilateral (fairing=thinplate, iterations=0, smoothing=10)"}
    assert all(value >= 0.0 for value in seconds.values())


def test_kernel_example_has_two_holes_every_filter_closes():
    from meshlab_holefill.array_api import _kernel_example

    V, F = _kernel_example()
    assert len(meshlab_holefill.boundary_loops(F)) == 3  # the grid's border and two holes
    for name in meshlab_holefill.algorithm_names():
        _, _, result = meshlab_holefill.fill_holes(V, F, name, workers=1)
        assert result["closed_holes"] == 2, (name, result["holes"])


@pytest.mark.parametrize("algorithm", algorithm_names())
def test_a_time_limit_that_expires_inside_compiled_kernels_fails_the_hole_cleanly(algorithm):
    """The alarm can come while a numba kernel or its dispatcher runs: the hole fails, nothing else."""
    V, F, _ = bowl_with_hole(n=31, radius=0.6)
    fill_holes(V, F, algorithm, workers=1)  # kernels loaded: the limits below expire inside them
    for limit in np.geomspace(0.001, 0.1, 9):
        V2, F2, result = fill_holes(V, F, algorithm, workers=1, timelimit=limit)
        statuses = {(h["status"], "time limit" in (h.get("reason") or "")) for h in result["holes"]
                    if h["status"] != "skipped"}
        assert statuses <= {("closed", False), ("failed", True)}
        assert np.array_equal(V2[:len(V)], V) and np.all(np.isfinite(V2))
    unlimited = fill_holes(V, F, algorithm, workers=1)
    generous = fill_holes(V, F, algorithm, workers=1, timelimit=1000.0)
    assert np.array_equal(unlimited[0], generous[0]) and np.array_equal(unlimited[1], generous[1])
