"""core.failure_reasons: what a failed hole's reason says about the mesh beside it."""
import os

import numpy as np
import pymeshlab

from meshlab_holefill.array_api import fill_holes
from meshlab_holefill.core import examples
from meshlab_holefill.core.failure_reasons import explain_folded_surroundings
from meshlab_holefill.core.holes import vertex_face_incidence
from meshlab_holefill.evaluation.cut_holes import cut_holes
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


def test_a_hole_that_fails_beside_a_folded_surface_says_so():
    """A noisy scan (cow.obj Loop-subdivided twice, 0.3 mean edges of normal noise) whose 69-edge hole's rings fold over
    themselves: every patch crosses them, and the reason names the folds; the hole beside clean rings closes."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes", "cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V = normal_noise(ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix(), 0.3, seed=9)
    F, _ = cut_holes(V, ms.current_mesh().face_matrix().astype(np.int64), seed=9, strict=False)
    _, _, result = fill_holes(V, F, "min_angle_bilateral", maxholesize=70, workers=1)
    tried = {h["boundary_edges"]: h for h in result["holes"] if h["status"] != "skipped"}
    assert tried[22]["status"] == "closed"
    assert tried[69]["status"] == "failed"
    assert "the mesh beside this hole already crosses itself (7 faces within 2 rings" in tried[69]["reason"]
