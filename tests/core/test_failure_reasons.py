"""core.failure_reasons: what a failed hole's reason says about the mesh beside it."""
import os

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.array_api import algorithm_names, fill_holes
from meshlab_holefill.core import examples
from meshlab_holefill.core.failure_reasons import explain_folded_surroundings
from meshlab_holefill.core.holes import vertex_face_incidence
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.metrics import mesh_checks
from meshlab_holefill.evaluation.noisy import normal_noise


def test_only_failed_holes_beside_folds_get_the_note():
    V, F, loop = examples.bowl_with_hole(n=21)
    folded = V + np.random.default_rng(0).normal(0.0, 0.05, V.shape)  # half an edge of jitter folds the rings
    incidence = vertex_face_incidence(F, len(V))
    loops = {0: loop}
    for mesh, status, noted in ((folded, "failed", True), (folded, "closed", False), (V, "failed", False)):
        report = [{"hole": 0, "status": status, "reason": "patch would intersect the mesh (3 faces)"}]
        explain_folded_surroundings(mesh, F, loops, report, incidence)
        assert ("already crosses itself" in report[0]["reason"]) == noted
        assert report[0]["reason"].startswith("patch would intersect the mesh (3 faces)")


@pytest.fixture(scope="module")
def noisy_cow():
    """A noisy scan (cow.obj Loop-subdivided twice, 0.3 mean edges of normal noise) with holes cut (seed 9);
    the rings of its 69-edge hole fold over themselves."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes", "cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V = normal_noise(ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix(), 0.3, seed=9)
    F, _ = cut_holes(V, ms.current_mesh().face_matrix().astype(np.int64), seed=9, strict=False)
    return V, F


def test_a_hole_that_fails_beside_a_folded_surface_says_so(noisy_cow):
    """Every patch of the 69-edge hole crosses the folds, and the reason names them; the hole beside clean rings closes."""
    V, F = noisy_cow
    _, _, result = fill_holes(V, F, "min_angle_bilateral", maxholesize=70, workers=1)
    tried = {h["boundary_edges"]: h for h in result["holes"] if h["status"] != "skipped"}
    assert tried[22]["status"] == "closed"
    assert tried[69]["status"] == "failed"
    assert "the mesh beside this hole already crosses itself (7 faces within 2 rings" in tried[69]["reason"]


@pytest.mark.parametrize("name", algorithm_names())
def test_with_the_check_off_every_filter_closes_the_hole_beside_the_folds(noisy_cow, name):
    """``selfintersection=False``, as MeshLab's Close Holes with its check off: the hole closes, its patch crossing
    the mesh, and the original vertices stay as they were."""
    V, F = noisy_cow
    V2, F2, result = fill_holes(V, F, name, maxholesize=70, workers=1, selfintersection=False)
    hole = next(h for h in result["holes"] if h["boundary_edges"] == 69)
    assert hole["status"] == "closed"
    np.testing.assert_array_equal(V2[:len(V)], V)
    if not result.get("split_boundary_edges"):  # LS-SVM's Sec. 3.1 splits long border edges' faces in two
        np.testing.assert_array_equal(F2[:len(F)], F)
    assert mesh_checks(V, F, V2, F2)["intersecting_new_faces"] > 0
