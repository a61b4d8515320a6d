"""evaluation.creased and the crease metric: CAD-like cases with holes a crease runs through, interpenetrating
parts, metrics.crease_metrics on analytic folds, and crossing counts that ignore crossings the mesh already had."""
from __future__ import annotations

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.evaluation.comparison import Filler, MeshCase, evaluate_run, prepare_case
from meshlab_holefill.evaluation.creased import (CAD_TESSELLATED_PARTS, CREASED_CASES, ball_hole, cad_tessellation_case,
                                                 creased_case, random_crease_holes, rotation)
from meshlab_holefill.evaluation.metrics import compact_mesh, crease_metrics, edge_dihedrals, mesh_checks
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.meshlab.mesh_files import boolean_mesh, generated_mesh, remeshed

from evaluation_meshes import grid

FIXTURE_EDGE = 0.08  # coarse versions of the benchmark cases: about 1-3k faces each


@functools.lru_cache(maxsize=None)
def fixture(name, seed=0):
    return prepare_case(creased_case(name, FIXTURE_EDGE, seed=seed))


def folded_grid(theta, n=12, equilateral=False):
    """A flat n x n grid folded by theta degrees about the line x = n/2 (its grid edges there are the crease)."""
    V, F = grid(n, equilateral)
    V = V.copy()
    c = n / 2 if not equilateral else None
    right = V[:, 0] > c + 1e-9
    d = V[right, 0] - c
    a = np.radians(theta)
    V[right, 0] = c + d * np.cos(a)
    V[right, 2] = d * np.sin(a)
    return V, F


def test_edge_dihedrals_are_signed_convex_positive():
    V, F = generated_mesh("create_cube", size=1.0)
    _, angles = edge_dihedrals(V, F)
    assert np.allclose(np.sort(np.abs(angles))[-12:], 90.0) and (angles > -1e-9).all()
    _, inverted = edge_dihedrals(V, F[:, ::-1])
    assert np.allclose(np.sort(inverted)[:12], -90.0)


@settings(max_examples=15, deadline=None)
@given(theta=st.floats(35.0, 150.0), axis=st.sampled_from("xyz"), turn=st.floats(-180.0, 180.0),
       shift=st.tuples(*[st.floats(-5.0, 5.0)] * 3))
def test_crease_metric_exact_patch_scores_zero_flat_cap_scores_the_angle(theta, axis, turn, shift):
    R, t = rotation(axis, turn), np.asarray(shift)
    gV, gF = folded_grid(theta)
    gV = gV @ R.T + t
    exact = crease_metrics(gV, gF, gV, gF)
    assert exact["crease_edges"] == 12 and exact["crease_error_mean_deg"] < 1e-6
    assert exact["crease_gt_deg"] == pytest.approx(theta, abs=1e-4)
    # the same folded surface triangulated with the other diagonals still has the crease edges
    cells = gF.reshape(-1, 2, 3)  # cell (p, q, r, s) as faces (p, q, r), (p, r, s): use (p, q, s), (q, r, s)
    p, q, r, s = cells[:, 0, 0], cells[:, 0, 1], cells[:, 0, 2], cells[:, 1, 2]
    other = np.concatenate([np.stack([p, q, s], 1), np.stack([q, r, s], 1)])
    assert crease_metrics(gV, gF, gV, other)["crease_error_mean_deg"] < 1e-6
    # a flat cap over the same place: no fold anywhere, the error is the crease angle
    fV, fF = grid(12)
    fV = fV @ R.T + t
    flat = crease_metrics(gV, gF, fV, fF)
    assert flat["crease_error_mean_deg"] == pytest.approx(theta, abs=1e-4)
    assert flat["crease_patch_deg"] == pytest.approx(0.0, abs=1e-4)


def test_crease_metric_gentle_fold_or_flat_ground_truth_has_no_crease():
    assert crease_metrics(*folded_grid(20.0), *grid(12)) == {}
    assert crease_metrics(*grid(12), *folded_grid(90.0)) == {}


def test_crease_metric_half_fold_scores_half():
    gV, gF = folded_grid(90.0)
    pV, pF = folded_grid(45.0)
    assert crease_metrics(gV, gF, pV, pF)["crease_error_mean_deg"] == pytest.approx(45.0, abs=1e-4)


@pytest.mark.parametrize("name", [n for n in CREASED_CASES if n != "interpenetrating"])
def test_creased_cases_have_holes_a_crease_runs_through(name):
    case = fixture(name)
    assert len(case.holes) >= 3 and not case.notes
    for hole in case.holes:
        assert hole.size_class == "crease"
        gV, gF = compact_mesh(*hole.ground_truth)
        m = crease_metrics(gV, gF, gV, gF)  # the removed surface holds a crease, reproduced exactly: 0
        assert m["crease_edges"] >= 1 and m["crease_gt_deg"] > 40.0 and m["crease_error_mean_deg"] == 0.0


def _holds_a_crease(hole):
    gV, gF = compact_mesh(*hole.ground_truth)
    return crease_metrics(gV, gF, gV, gF).get("crease_edges", 0) >= 1


@pytest.mark.parametrize("name", ["creased_box", "cylinder_rims", "union"])
def test_another_seed_cuts_other_holes_at_random_crease_points_and_the_same_ones_each_time(name):
    by_hand = creased_case(name, FIXTURE_EDGE)
    seeded, again = creased_case(name, FIXTURE_EDGE, seed=1), creased_case(name, FIXTURE_EDGE, seed=1)
    assert np.array_equal(seeded.removed, again.removed)
    assert not np.array_equal(seeded.removed, by_hand.removed)
    assert not np.array_equal(seeded.removed, creased_case(name, FIXTURE_EDGE, seed=2).removed)
    case = fixture(name, 1)
    assert len(case.holes) >= 3 and not case.notes and {h.size_class for h in case.holes} == {"crease"}
    assert sum(map(_holds_a_crease, case.holes)) >= len(case.holes) - 1  # the last is drawn anywhere


def test_random_crease_holes_centre_all_but_the_last_on_a_crease_and_take_any_point_without_creases():
    V, F = remeshed(*generated_mesh("create_cube", size=1.0), FIXTURE_EDGE)
    for seed in range(5):
        # a 12-edge hole on a crease, then a smaller one anywhere (most of a cube is flat)
        removed = random_crease_holes(V, F, [12, 6], np.random.default_rng(seed))
        case = prepare_case(MeshCase("cube", V, F, removed=removed, given_class="crease"))
        assert _holds_a_crease(max(case.holes, key=lambda h: h.boundary_edges))
    sphere = generated_mesh("create_sphere", subdiv=3)
    assert random_crease_holes(*sphere, [12, 12], np.random.default_rng(0)).any()  # no crease: holes anywhere


@pytest.mark.parametrize("seed", [0, 1])
def test_interpenetrating_case_holes_next_to_crossings_whose_ground_truth_crosses_nothing(seed):
    case = fixture("interpenetrating", seed)
    V0, F0 = case.V0, case.F0
    everything = np.arange(len(F0))
    assert len(faces_intersecting(V0, F0, everything, everything)) > 20  # parts cross before any fill
    assert len(case.holes) >= 3 and {h.size_class for h in case.holes} == {"crossing"}
    for hole in case.holes:
        gV, gF = hole.ground_truth
        F1 = np.concatenate([F0, gF])
        new = np.arange(len(F0), len(F1))
        assert len(faces_intersecting(gV, F1, new, np.arange(len(F1)))) == 0
        # ... but the hole lies next to a crossing: within 3 hole radii of a face that crosses another part
        centre = V0[hole.loop].mean(axis=0)
        radius = np.linalg.norm(V0[hole.loop] - centre, axis=1).max()
        crossing = faces_intersecting(V0, F0, everything, everything)
        assert np.linalg.norm(V0[F0[crossing]].mean(axis=1) - centre, axis=1).min() < 3 * radius


def test_crossing_count_ignores_old_crossings_and_counts_new_faces_crossing_them():
    case = fixture("interpenetrating")
    V0, F0 = case.V0, case.F0
    everything = np.arange(len(F0))
    old = faces_intersecting(V0, F0, everything, everything)
    hole = case.holes[0]
    gV, gF = hole.ground_truth
    # the ground truth as the patch: nothing new crosses, though the mesh has crossing faces
    checks = mesh_checks(V0, F0, gV, np.concatenate([F0, gF]))
    assert checks["intersecting_new_faces"] == 0
    # a new face that is an old crossing face lifted a little off it crosses what that face crossed
    f = F0[old[0]]
    T = V0[f]
    n = np.cross(T[1] - T[0], T[2] - T[0])
    lifted = T + 1e-4 * n / np.linalg.norm(n)
    V1 = np.concatenate([gV, lifted])
    F1 = np.concatenate([F0, gF, [np.arange(len(gV), len(gV) + 3)]])
    checks, hits = mesh_checks(V0, F0, V1, F1, return_hits=True)
    assert checks["intersecting_new_faces"] == 1 and hits.tolist() == [len(F1) - 1]


def test_evaluate_run_of_the_ground_truth_scores_zero_distance_crease_and_crossings():
    case = fixture("creased_box")
    hole = case.holes[0]
    gV, gF = hole.ground_truth
    reply = {"status": "ok", "seconds": 0.0, "V_new": gV[len(case.V0):], "F_new": gF, "result": {}}
    run, rows, _ = evaluate_run(case, Filler("truth", "truth"), reply, {})
    row = rows[0]
    assert row["closed"] and row["intersecting_new_faces"] == 0
    assert row["crease_error_mean_deg"] == 0.0 and row["dist_patch_to_gt_mean_permille"] < 1e-9
    assert all(not r["closed"] for r in rows[1:])


def test_ball_hole_and_case_errors():
    V, F = generated_mesh("create_sphere", subdiv=2)
    assert ball_hole(V, F, V[0], 10_000) is None  # no ball gives that many boundary edges
    region = ball_hole(V, F, V[0], 12)
    assert region is not None and len(region) > 3
    with pytest.raises(ValueError, match="unknown creased case 'teapot'"):
        creased_case("teapot")
    with pytest.raises(ValueError, match="not one of MeshLab's create_"):
        generated_mesh("load_new_mesh")
    with pytest.raises(ValueError, match="edge_length must be positive"):
        remeshed(V, F, 0.0)
    with pytest.raises(ValueError, match="operation must be union"):
        boolean_mesh("xor", (V, F), (V, F))


def test_a_boolean_comes_out_the_same_in_every_run():
    from meshlab_holefill.evaluation.creased import _box, _moved
    from meshlab_holefill.meshlab.mesh_files import canonical_face_order

    cutter = _moved(_box(1.2), rotation("z", 45.0))
    runs = [boolean_mesh("intersection", _box(), cutter) for _ in range(3)]
    for V, F in runs[1:]:
        assert np.array_equal(V, runs[0][0]) and np.array_equal(F, runs[0][1])
    V, F = runs[0]
    assert np.array_equal(canonical_face_order(F[::-1]), F)  # the order depends on the faces only
    assert np.all(F[:, 0] == F.min(axis=1))
    # Rotating a face keeps its orientation: the same directed edges.
    shuffled = np.roll(F[np.random.default_rng(0).permutation(len(F))], 1, axis=1)
    assert np.array_equal(canonical_face_order(shuffled), F)


@functools.lru_cache(maxsize=None)
def cad_part(name):
    return cad_tessellation_case(name)


@pytest.mark.parametrize("name", ["union", "drilled_box"])
def test_a_cad_tessellation_has_uneven_triangles_and_holes_at_creases(name):
    case = cad_part(name)
    V, F = case.V, case.F
    lengths = np.linalg.norm(V[F] - V[np.roll(F, -1, axis=1)], axis=2)  # (m, 3) edge lengths per face
    # the isotropic remeshing it starts from: 90th percentile of longest / shortest edge 1.4, edge lengths'
    # 95th / 5th percentile 1.5
    assert np.percentile(lengths.max(axis=1) / lengths.min(axis=1), 90) > 1.8
    assert np.percentile(lengths, 95) / np.percentile(lengths, 5) > 1.9
    prepared = prepare_case(case)
    assert len(prepared.holes) == len(CAD_TESSELLATED_PARTS[name][2]) and not prepared.notes
    creased = [bool(crease_metrics(*compact_mesh(*h.ground_truth), *compact_mesh(*h.ground_truth))) for h in prepared.holes]
    assert sum(creased) >= 3  # the drilled box's hole inside its bore has none


@pytest.mark.parametrize("algorithm", ["min_angle_bilateral", "curve_unfolding", "lssvm_poisson",
                                       "differential_evolution"])
def test_every_filter_closes_the_holes_of_a_cad_tessellation_cleanly(algorithm):
    from meshlab_holefill import fill_holes

    from conftest import assert_filled_cleanly

    case = cad_part("drilled_box")
    F0 = case.F[~case.removed]
    V2, F2, result = fill_holes(case.V, F0, algorithm, workers=1, maxholesize=200)
    assert result["closed_holes"] == len(CAD_TESSELLATED_PARTS["drilled_box"][2])
    assert_filled_cleanly(case.V, F0, V2, F2, faces_kept=algorithm != "lssvm_poisson")


def test_a_cad_part_by_an_unknown_name_is_refused():
    with pytest.raises(ValueError, match="unknown CAD part 'gear'"):
        cad_tessellation_case("gear")
