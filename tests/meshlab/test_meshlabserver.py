"""Scripts written for MeshLab 2020.09 run through its real meshlabserver and through run_filter_script alike."""
import os
import shutil
import subprocess

import numpy as np
import pymeshlab
import pytest

import meshlab_holefill
from meshlab_holefill.meshlab.mlx.script import run_filter_script

from conftest import meshset_from_arrays, sample, sphere_with_holes

pytestmark = pytest.mark.skipif(
    not (shutil.which("meshlabserver") and shutil.which("xvfb-run")),
    reason="needs MeshLab 2020.09's meshlabserver and xvfb-run (Debian packages meshlab and xvfb; "
           "scripts/test installs them when run as root)")

WORKFLOWS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "filters")


def meshlabserver(mesh, out, script):
    """Run a script through the real meshlabserver under xvfb-run; its output text."""
    run = subprocess.run(["xvfb-run", "-a", "meshlabserver", "-i", str(mesh), "-o", str(out), "-s", str(script)],
                         capture_output=True, text=True, timeout=300)
    text = run.stdout + run.stderr
    assert run.returncode == 0 and os.path.exists(out), f"meshlabserver failed ({run.returncode}):\n{text[-2000:]}"
    return text


def assert_same_mesh(path, ms):
    """Same counts, coordinates equal to PLY float precision, same faces up to the rotation of their corners."""
    theirs = pymeshlab.MeshSet()
    theirs.load_new_mesh(str(path))
    a, b = ms.current_mesh(), theirs.current_mesh()
    assert (a.vertex_number(), a.face_number()) == (b.vertex_number(), b.face_number())
    scale = np.linalg.norm(np.ptp(a.vertex_matrix(), axis=0))
    np.testing.assert_allclose(b.vertex_matrix(), a.vertex_matrix(), rtol=0, atol=1e-6 * scale)

    def rotated(F):
        F = np.asarray(F)
        shift = np.argmin(F, axis=1)
        return np.array([np.roll(f, -s) for f, s in zip(F, shift)])

    assert np.array_equal(rotated(a.face_matrix()), rotated(b.face_matrix()))


@pytest.fixture
def holed_ply(tmp_path):
    V, F, _ = sphere_with_holes(subdiv=3)
    ms = meshset_from_arrays(V, F)
    ms.meshing_remove_unreferenced_vertices()
    path = tmp_path / "holed.ply"
    ms.save_current_mesh(str(path))
    return path


def test_a_script_written_for_2020_09_runs_the_same_in_meshlabserver_and_run_filter_script(holed_ply, tmp_path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(holed_ply))
    for name, kwargs in (("meshing_remove_duplicate_vertices", {}), ("meshing_repair_non_manifold_edges", {}),
                         ("meshing_close_holes", {"maxholesize": 100}),
                         ("apply_coord_laplacian_smoothing", {"stepsmoothnum": 2, "selected": True}),
                         ("compute_selection_bad_faces", {"usear": False}),
                         ("compute_matrix_from_translation", {"axisx": 0.25}),
                         ("meshing_invert_face_orientation", {})):
        meshlab_holefill.apply_filter(ms, name, **kwargs)
    script = meshlab_holefill.save_filter_script(ms, tmp_path / "written.mlx", target="meshlab-2020.09")
    text = meshlabserver(holed_ply, tmp_path / "meshlab.ply", script)
    assert "Closed 2 holes" in text
    ours = pymeshlab.MeshSet()
    ours.load_new_mesh(str(holed_ply))
    run_filter_script(ours, script)
    assert_same_mesh(tmp_path / "meshlab.ply", ours)


def test_the_shipped_2020_09_baseline_runs_the_same_in_meshlabserver(tmp_path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    bunny = tmp_path / "bunny.ply"  # MeshLab 2020.09's OBJ reader refuses this OBJ
    ms.save_current_mesh(str(bunny), save_wedge_texcoord=False)
    script = os.path.join(WORKFLOWS, "meshlab_close_holes_2020.09.mlx")
    meshlabserver(bunny, tmp_path / "meshlab.ply", script)
    ours = pymeshlab.MeshSet()
    ours.load_new_mesh(str(bunny))
    run_filter_script(ours, script)
    assert_same_mesh(tmp_path / "meshlab.ply", ours)


def test_scripts_for_current_meshlab_fail_in_meshlabserver_2020_09_at_the_renamed_filter(holed_ply, tmp_path):
    run = subprocess.run(["xvfb-run", "-a", "meshlabserver", "-i", str(holed_ply), "-o", str(tmp_path / "x.ply"),
                          "-s", os.path.join(WORKFLOWS, "meshlab_close_holes.mlx")],
                         capture_output=True, text=True, timeout=300)
    assert "filter Repair non Manifold Edges not found" in run.stdout + run.stderr
