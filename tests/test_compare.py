"""Tests of the comparison: hole cutting, metrics on cases with known answers, isolation, report."""
from __future__ import annotations

import csv
import json
import os

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import meshlab_holefill
from meshlab_holefill.evaluation import cut_holes as cmp
from meshlab_holefill.evaluation.comparison import Filler, IsolatedRunner, MeshCase, parse_fillers, prepare_case, run_comparison
from meshlab_holefill.core.holes import boundary_halfedges, boundary_loops
from meshlab_holefill.evaluation.metrics import mesh_checks

from conftest import cut_disks, grid as unit_grid, mesh_arrays

SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")


def grid(n=24, equilateral=False):
    """Flat triangulated square (z = 0) with n x n cells; equilateral rows when asked."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    x = i + (0.5 * (j % 2) if equilateral else 0.0)
    y = j * (np.sqrt(3) / 2 if equilateral else 1.0)
    V = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1).astype(np.float64)
    idx = lambda a, b: a * (n + 1) + b  # noqa: E731
    F = []
    for a in range(n):
        for b in range(n):
            p, q, r, s = idx(a, b), idx(a + 1, b), idx(a + 1, b + 1), idx(a, b + 1)
            if equilateral and b % 2 == 0:
                F += [[p, q, s], [q, r, s]]
            else:
                F += [[p, q, r], [p, r, s]]
    return V, np.asarray(F, np.int64)


def sphere(subdiv=4):
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def _hole_setup(V, F, removed):
    """Mesh with the removed faces taken out, the hole's loop/border and its ground truth."""
    case = prepare_case(MeshCase("t", V, F, removed=removed))
    assert len(case.holes) == 1
    return case, case.holes[0]


# ------------------------------------------------------------------- metrics, known answers

def test_flat_hole_filled_flat_has_zero_distance_and_no_crease():
    V, F = grid()
    removed = np.linalg.norm(V[F].mean(axis=1)[:, :2] - 12.0, axis=1) < 5.0
    case, hole = _hole_setup(V, F, removed)
    # A different flat triangulation of the same hole: a fan from a new centre vertex.
    centre = case.V0[hole.loop].mean(axis=0)
    V1 = np.vstack([case.V0, centre])
    k = len(hole.loop)
    # loop is in patch orientation: a patch face holds (loop[i], loop[i+1])
    patch = np.stack([np.full(k, len(case.V0)), hole.loop, hole.loop[np.r_[1:k, 0]]], axis=1)
    metrics, arrays = cmp.hole_metrics(case.V0, case.F0, V1, patch, hole.loop, hole.border, hole.ground_truth,
                                       case.diag)
    # MeshLab's sampler works in single precision
    assert metrics["dist_patch_to_gt_max"] < 1e-6 * case.diag and metrics["dist_gt_to_patch_max"] < 1e-6 * case.diag
    assert metrics["normal_dev_max_deg"] < 1e-6
    assert metrics["border_dihedral_max_deg"] < 1e-6 and metrics["border_dihedral_excess_deg"] < 1e-6
    assert np.all(arrays["face_distance"] < 1e-9)
    assert metrics["new_vertices"] == 1 and metrics["faces"] == k


def test_equilateral_triangle_has_quality_one_and_density_ratio_one():
    V, F = grid(8, equilateral=True)
    tri = V[F]
    lengths = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2)
    assert np.allclose(lengths, 1.0)
    removed = np.zeros(len(F), bool)
    removed[len(F) // 2 + 3] = True  # one interior triangle: a 3-edge hole
    case, hole = _hole_setup(V, F, removed)
    patch = hole.ground_truth[1]  # filled exactly with the removed triangle
    metrics, _ = cmp.hole_metrics(case.V0, case.F0, case.V0, patch, hole.loop, hole.border, hole.ground_truth,
                                  case.diag)
    assert metrics["quality_mean"] == pytest.approx(1.0) and metrics["quality_min"] == pytest.approx(1.0)
    assert metrics["quality_share07"] == 1.0 and metrics["quality_hist"][-1] == 1
    assert metrics["edge_ratio"] == pytest.approx(1.0)
    assert metrics["dist_patch_to_gt_max"] < 1e-12


def test_lifted_patch_distance_and_normal_deviation_known():
    """A flat patch lifted by h over a flat hole: distance h, then a flipped patch deviates 180 degrees."""
    V, F = grid()
    removed = np.linalg.norm(V[F].mean(axis=1)[:, :2] - 12.0, axis=1) < 5.0
    case, hole = _hole_setup(V, F, removed)
    gV, gF = hole.ground_truth
    n0 = len(case.V0)
    h = 0.25
    centre = case.V0[hole.loop].mean(axis=0) + [0, 0, h]
    V1 = np.vstack([case.V0, centre])
    k = len(hole.loop)
    fan = np.stack([np.full(k, n0), hole.loop, hole.loop[np.r_[1:k, 0]]], axis=1)
    d, _, _ = cmp.closest_faces(V1[[n0]], gV, gF)
    assert d[0] == pytest.approx(h)
    flipped = fan[:, ::-1]
    metrics, _ = cmp.hole_metrics(case.V0, case.F0, V1, flipped, hole.loop, hole.border, hole.ground_truth,
                                  case.diag)
    assert metrics["normal_dev_mean_deg"] > 170.0


def test_border_dihedral_of_a_right_angle_fold():
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, -1, 0], [0.5, 0, 1.0]])
    F_mesh = np.array([[0, 2, 1]])  # traverses edge (1, 0)
    he = np.array([[1, 0]])
    patch = np.array([[0, 1, 3]])  # traverses (0, 1): the opposite direction, as a patch must
    angle = cmp.border_dihedrals(V, F_mesh, he, np.array([0]), patch)
    assert angle[0] == pytest.approx(90.0)
    assert np.isnan(cmp.border_dihedrals(V, F_mesh, he, np.array([0]), patch[:, ::-1])[0])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000))
def test_closest_point_on_triangle_beats_dense_sampling(seed):
    rng = np.random.default_rng(seed)
    T = rng.normal(size=(3, 3))
    X = rng.normal(size=(1, 3)) * 2
    P = cmp.closest_point_on_triangles(X, T[[0]], T[[1]], T[[2]])[0]
    s, t = np.meshgrid(np.linspace(0, 1, 120), np.linspace(0, 1, 120))
    ok = s + t <= 1
    samples = T[0] + s[ok, None] * (T[1] - T[0]) + t[ok, None] * (T[2] - T[0])
    sampled = np.linalg.norm(samples - X, axis=1).min()
    exact = np.linalg.norm(P - X[0])
    assert exact <= sampled + 1e-12
    assert exact >= sampled - 0.03 * np.linalg.norm(T - T.mean(axis=0), axis=1).max()


# --------------------------------------------------------------------------- hole cutting

def test_cut_holes_simple_apart_with_ground_truth():
    V, F = sphere(4)
    plan = cmp.hole_plan(4, ("small", "medium"))
    F_cut, holes = cmp.cut_holes(V, F, sizes=[p[0] for p in plan], shapes=[p[1] for p in plan], seed=3)
    assert [h.shape for h in holes] == ["compact", "irregular", "compact", "irregular"]
    loops = boundary_loops(F_cut)
    assert len(loops) == 4 and not any(lp.pinched for lp in loops)
    for h in holes:
        target = cmp.SIZE_CLASSES[h.size_class]
        assert 0.8 * target <= h.boundary_edges <= 1.5 * target
    # holes are apart: no two holes share a vertex
    sets = [set(np.unique(h.removed_faces)) for h in holes]
    assert all(not (a & b) for i, a in enumerate(sets) for b in sets[i + 1:])
    # removed + remaining faces are the original mesh
    assert sum(len(h.removed_faces) for h in holes) + len(F_cut) == len(F)


def test_prepared_ground_truth_closes_the_mesh():
    V, F = sphere(4)
    case = prepare_case(MeshCase("s", V, F), holes=2, sizes=("small", "medium"), seed=1)
    assert case.kind == "cut holes" and len(case.holes) == 2
    for hole in case.holes:
        gV, gF = hole.ground_truth
        assert np.allclose(gV[: len(case.V0)], case.V0)
        he, _ = boundary_halfedges(np.concatenate([case.F0, gF]))
        assert not np.isin(he, hole.loop).all(axis=1).any()  # the ground truth closes its hole exactly


# ------------------------------------------------------------------------- fillers, isolation

def test_parse_fillers():
    fillers = parse_fillers("min_angle_bilateral:iterations=2:fairing=none,meshing_close_holes:maxholesize=all,"
                            "refinehole=true")
    assert fillers[0].filter == "meshing_close_holes_min_angle_bilateral"
    assert fillers[0].params == {"iterations": 2, "fairing": "none"}
    assert fillers[1].params == {"maxholesize": "all", "refinehole": True}
    default = parse_fillers(None)
    assert {f.filter for f in default} == set(meshlab_holefill.filter_list()) | {"meshing_close_holes"}
    assert len(parse_fillers(None, refinehole=True)) == len(default) + 1
    with pytest.raises(ValueError, match="unknown filter 'no_such_filter'"):
        parse_fillers("no_such_filter")


def test_runner_survives_crash_and_hang():
    with IsolatedRunner() as runner:
        crashed = runner.run({"kind": "call", "function": "os._exit", "kwargs": {"status": 3}}, timeout=30)
        assert crashed["status"] == "crashed" and "3" in crashed["error"]
        hung = runner.run({"kind": "call", "function": "time.sleep", "args": [30]}, timeout=1.0)
        assert hung["status"] == "timeout"
        ok = runner.run({"kind": "call", "function": "math.hypot", "args": [3, 4]}, timeout=30)
        assert ok["status"] == "ok" and ok["value"] == 5.0


def test_failing_filter_is_reported_and_others_run():
    V, F = sphere(3)
    fillers = [Filler("broken", "meshing_close_holes_min_angle_bilateral", {"no_such_param": 1}),
               Filler("close all", "meshing_close_holes", {"maxholesize": "all"})]
    result = run_comparison([MeshCase("s", V, F)], holes=2, sizes=("small",), filters=fillers, progress=False)
    runs = {r["filler"]: r for r in result.runs}
    assert runs["broken"]["status"] == "error" and "no_such_param" in runs["broken"]["error"]
    assert runs["close all"]["status"] == "ok" and runs["close all"]["closed_holes"] == 2
    assert all(not r["closed"] and r["reason"].startswith("error") for r in result.holes if r["filler"] == "broken")


# ----------------------------------------------------------------------------------- report

def test_compare_report_end_to_end(tmp_path):
    V, F = sphere(4)
    case = MeshCase("sphere", V, F, analytic=lambda X: np.linalg.norm(X, axis=1) - 1.0)
    result = meshlab_holefill.evaluation.cut_holes([case, os.path.join(SAMPLES, "bunny10k_textured.obj")],
                                      report=str(tmp_path), holes=2, sizes=("small", "medium"),
                                      filters="min_angle_bilateral,baseline", progress=False)
    labels = [f.label for f in result.fillers]
    assert len(labels) == 3
    n_holes = 2 + 5
    assert len(result.holes) == n_holes * 3
    for name in ["report.md", "report.html", "results.json", "results.csv", "metrics.png",
                 "quality_histograms.png", "error_time_vs_size.png"]:
        assert (tmp_path / name).stat().st_size > 0, name
    assert len(list((tmp_path / "holes").glob("*.png"))) == n_holes
    rows = list(csv.DictReader(open(tmp_path / "results.csv")))
    assert len(rows) == n_holes * 3
    data = json.load(open(tmp_path / "results.json"))
    assert len(data["holes"]) == n_holes * 3
    md, page = (tmp_path / "report.md").read_text(), (tmp_path / "report.html").read_text()
    for c in result.cases:
        assert c["case"] in md and c["case"] in page
    assert md.count("| sphere |") == page.count("<td>sphere</td>") + page.count("<td class='best'>sphere</td>") == 2
    by = {(r["case"], r["hole"], r["filler"]): r for r in result.holes}
    hu = "meshing_close_holes_min_angle_bilateral"
    # Ground truth and analytic metrics on the cut holes. Measured: 1.81 and 7.47 per mille from
    # the ground truth, 0.0117 and 0.0320 from the unit sphere; the bounds leave ~1.6x slack.
    for h, (gt_permille, analytic) in enumerate([(3.0, 0.02), (12.0, 0.05)]):
        r = by[("sphere", h, hu)]
        assert r["closed"] and r["dist_patch_to_gt_mean_permille"] < gt_permille and r["analytic_dist_mean"] < analytic
    # Measured 0.774 on the bunny's 38-edge hole (1.5x slack on the shortfall from 1); MeshLab's own
    # Close Holes, an unrefined triangulation, reaches only 0.55 there.
    natural = by[("bunny10k_textured.obj", 0, hu)]
    assert natural["closed"] and "dist_patch_to_gt_mean" not in natural and natural["quality_mean"] > 0.65
    default = [r for r in result.holes if r["filler"] == "meshing_close_holes (default)" and r["boundary_edges"] >= 30]
    assert default and all("maxholesize" in r["reason"] for r in default)


def test_cli_compare(tmp_path, capsys):
    from meshlab_holefill.cli import main

    code = main(["compare", os.path.join(SAMPLES, "bone.ply"), "--holes", "1", "--sizes", "small",
                 "--filters", "meshing_close_holes", "--report", str(tmp_path), "--quiet", "--no-pictures"])
    assert code == 0
    out = capsys.readouterr().out
    assert "meshing_close_holes" in out and "1/1" in out
    assert "meshlab-holefill compare" in (tmp_path / "report.md").read_text()


def test_patch_distance_does_not_depend_on_its_triangulation():
    """The same flat cap, as 2 triangles or split 4-fold, is the same distance from a curved truth."""
    from meshlab_holefill.evaluation.metrics import hausdorff_one_way

    coarse_V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    coarse_F = np.array([[0, 1, 2], [0, 2, 3]])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(coarse_V, coarse_F))
    ms.meshing_surface_subdivision_midpoint(iterations=2, threshold=pymeshlab.PercentageValue(0))
    fine_V, fine_F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    assert len(fine_F) == 32
    gt_V, gt_F = grid(20)[0] / 20.0, grid(20)[1]
    gt_V[:, 2] = 0.2 * np.sin(np.pi * gt_V[:, 0]) * np.sin(np.pi * gt_V[:, 1])  # a bump sharing the border
    coarse = hausdorff_one_way(coarse_V, coarse_F, gt_V, gt_F)["mean"]
    fine = hausdorff_one_way(fine_V, fine_F, gt_V, gt_F)["mean"]
    assert coarse == pytest.approx(fine, rel=0.03)
    # the surface mean of 0.2 sin(pi x) sin(pi y) over the unit square is 0.8 / pi^2 (distance ~ height here)
    assert 0.6 * 0.8 / np.pi ** 2 < coarse < 1.05 * 0.8 / np.pi ** 2


def test_patch_distance_depends_only_on_the_two_surfaces():
    """Same figures whatever was sampled before (MeshLab's sampler has one unseedable generator)."""
    from meshlab_holefill.evaluation.metrics import closest_faces, hausdorff_one_way, sample_surface

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms.create_sphere(subdiv=4)
    W, G = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    first = hausdorff_one_way(V, F, W, G)
    ms.get_hausdorff_distance(sampledmesh=0, targetmesh=1)  # advances MeshLab's generator
    hausdorff_one_way(W, G, V, F, samples=777)
    assert hausdorff_one_way(V, F, W, G) == first
    assert hausdorff_one_way(V, F, W, G, seed=1) != first
    # exact distances of the seeded samples (numpy closest points, nearest-centroid candidates)
    d, _, _ = closest_faces(sample_surface(V, F, 20000), W, G)
    assert first["mean"] == pytest.approx(d.mean(), rel=1e-5)
    assert first["max"] == pytest.approx(d.max(), rel=1e-5)


def test_surface_samples_are_spread_by_area():
    from meshlab_holefill.evaluation.metrics import sample_surface

    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [3, 0, 0], [3, 1, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])  # unit square, then a 2x1 rectangle
    X = sample_surface(V, F, 30000, seed=3)
    assert np.all((X[:, 0] >= 0) & (X[:, 0] <= 3) & (X[:, 1] >= 0) & (X[:, 1] <= 1) & (X[:, 2] == 0))
    assert np.mean(X[:, 0] < 1) == pytest.approx(1 / 3, abs=0.01)
    assert np.mean(X[:, 1] < 0.5) == pytest.approx(0.5, abs=0.01)  # uniform inside each triangle too
    assert sample_surface(V, F[:0], 10).shape == (0, 3)


def test_patch_info_becomes_info_columns():
    from meshlab_holefill.evaluation.comparison import _patch_info

    entry = {"hole": 3, "status": "closed", "seconds": 0.1, "new_faces": 9, "restarts": 2,
             "unfolding_seconds": 0.01, "method": "annealed", "history": [1, 2]}
    assert _patch_info(entry) == {"info_restarts": 2, "info_unfolding_seconds": 0.01, "info_method": "annealed"}
    assert _patch_info(None) == {}


# ---------------------------------------------------------------------------- mesh_checks

def _grid_with_two_cell_holes():
    """7 x 7 vertices in the unit square (spacing 1/6) with two one-cell holes: loops of 24, 4 and 4 edges."""
    V, F = unit_grid(7, 7)
    _, F, _ = cut_disks(V, F, [(0.25, 0.25, 0), (0.75, 0.75, 0)], 0.05)
    assert [lp.vertices.tolist() for lp in boundary_loops(F)][1:] == [[8, 9, 16, 15], [32, 33, 40, 39]]
    return V, F


def test_mesh_checks_of_a_clean_fill():
    V0, F0 = _grid_with_two_cell_holes()
    F1 = np.concatenate([F0, [[8, 9, 16], [8, 16, 15], [32, 33, 40], [32, 40, 39]]])
    assert mesh_checks(V0, F0, V0, F0) == {
        "originals_changed": 0, "nonmanifold_edges": 0, "boundary_edges_left": 32,
        "intersecting_new_faces": 0, "new_faces": 0, "new_vertices": 0}
    checks, hits = mesh_checks(V0, F0, V0.copy(), F1, return_hits=True)
    assert checks == {"originals_changed": 0, "nonmanifold_edges": 0, "boundary_edges_left": 24,
                      "intersecting_new_faces": 0, "new_faces": 4, "new_vertices": 0}
    assert hits.dtype == np.int64 and len(hits) == 0


def test_mesh_checks_counts_each_defect_exactly():
    V0, F0 = _grid_with_two_cell_holes()
    n, m = len(V0), len(F0)
    V1, F1 = V0.copy(), F0.copy()
    V1[46, 2] += 0.01  # one original vertex moved (on the outer border, away from the new faces)
    corner = int(np.flatnonzero((F0 == 42).any(axis=1))[0])
    F1[corner] = np.roll(F1[corner], 1)  # one original face rewritten: the same triangle, but a changed row
    fill = [[8, 9, 16], [8, 16, 15]]  # the first hole closed, the second (4 edges) left open
    # A closed tetrahedron on the interior edge 11-12 (x 4/6..5/6, y 1/6), new vertices n, n + 1
    # up in the air: that edge gets 4 faces, every other tetrahedron edge 2, no new border.
    tetra_V = [[0.75, 1 / 6 + 0.05, 0.15], [0.75, 1 / 6 - 0.05, 0.15]]
    tetra = [[11, 12, n], [12, 11, n + 1], [11, n, n + 1], [12, n + 1, n]]
    # A lone upright triangle through the middle of one face (cell x 4/6..5/6, y 2/6..3/6): 3 border edges.
    pierce_V = [[0.77, 0.36, -0.05], [0.79, 0.36, -0.05], [0.78, 0.36, 0.05]]
    pierce = [[n + 2, n + 3, n + 4]]
    V1 = np.concatenate([V1, tetra_V, pierce_V])
    F1 = np.concatenate([F1, fill, tetra, pierce])
    checks, hits = mesh_checks(V0, F0, V1, F1, return_hits=True)
    assert checks == {"originals_changed": 2,  # 1 moved vertex + 1 changed face
                      "nonmanifold_edges": 1,  # 11-12
                      "boundary_edges_left": 24 + 4 + 3,  # outer border, open hole, lone triangle
                      "intersecting_new_faces": 1,  # only the upright triangle
                      "new_faces": 2 + 4 + 1, "new_vertices": 2 + 3}
    assert hits.tolist() == [m + 2 + 4]


@settings(max_examples=30, deadline=None)
@given(st.sets(st.integers(0, 48), max_size=10), st.sets(st.integers(0, 67), max_size=10),
       st.floats(1e-9, 0.5))
def test_mesh_checks_counts_every_moved_vertex_and_changed_face(moved, rotated, shift):
    V0, F0 = _grid_with_two_cell_holes()
    assert (len(V0), len(F0)) == (49, 68)
    V1, F1 = V0.copy(), F0.copy()
    V1[sorted(moved), 2] += shift  # any move counts, however small
    F1[sorted(rotated)] = np.roll(F1[sorted(rotated)], 1, axis=1)  # same triangles, rewritten rows
    checks = mesh_checks(V0, F0, V1, F1)
    assert checks["originals_changed"] == len(moved) + len(rotated)
    assert checks["new_faces"] == checks["new_vertices"] == checks["nonmanifold_edges"] == 0


def test_peak_memory_window_sees_a_freed_allocation():
    from meshlab_holefill.evaluation.isolation import peak_memory_since, reset_peak_memory

    start = reset_peak_memory()
    if start is None:
        pytest.skip("no /proc/self/clear_refs here: memory is not reported")
    block = np.ones(50_000_000)  # 400 MB, touched
    del block
    assert peak_memory_since(start) > 350
    assert peak_memory_since(reset_peak_memory()) < 50  # a new window forgets it


def test_filter_task_reports_its_memory(bunny_scan):
    from meshlab_holefill.evaluation.isolation import execute_task, reset_peak_memory

    if reset_peak_memory() is None:
        pytest.skip("no /proc/self/clear_refs here: memory is not reported")
    V, F = mesh_arrays(bunny_scan)
    reply = execute_task({"kind": "filter", "V": V, "F": F, "filter": "meshing_close_holes_min_angle_bilateral",
                          "params": {}})
    assert reply["status"] == "ok" and reply["result"]["closed_holes"] == 5
    assert 0.1 < reply["memory_mb"] < 500  # the MeshSet of a 10k-face scan and the fill
