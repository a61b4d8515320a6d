"""The report's acceptance helpers: corner quality bound, island outlines, the issues' criteria."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.evaluation.reference_targets import TARGETS, criteria
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core.holes import OUTLINE_RATIO, boundary_loops, outline_ratios
from meshlab_holefill.evaluation.metrics import corner_quality_bound

from test_compare import grid, sphere


def _iso_quality(theta):
    return 8 * np.sin(theta / 2) * np.sin((np.pi - theta) / 4) ** 2


def test_iso_formula_is_the_quality_of_the_isosceles_triangle():
    for theta in np.radians([5.0, 9.6, 30.0, 60.0, 90.0, 150.0]):
        V = np.array([[0.0, 0, 0], [np.cos(-theta / 2), np.sin(-theta / 2), 0], [np.cos(theta / 2), np.sin(theta / 2), 0]])
        assert triangle_quality(V, np.array([[0, 1, 2]]))[0] == pytest.approx(_iso_quality(theta), abs=1e-12)
    assert _iso_quality(np.radians(9.3)) < 0.3 < _iso_quality(np.radians(9.4))


def test_square_hole_in_a_grid_is_bounded_by_a_fan_of_two_triangles():
    V, F = grid(10)
    centre = V[F].mean(axis=1)
    inside = np.all(np.abs(centre[:, :2] - 5.0) < 2.0, axis=1)  # a 4 x 4 square of cells
    F = F[~inside]
    hole = [lp for lp in boundary_loops(F) if len(lp) == 16][0]
    # equal edges at 90 degrees: a fan of two 45-degree isosceles triangles beats the single right triangle
    assert corner_quality_bound(V, F, hole.vertices) == pytest.approx(_iso_quality(np.pi / 4))
    assert _iso_quality(np.pi / 4) > _iso_quality(np.pi / 2)


@settings(max_examples=25, deadline=None)
@given(face=st.integers(0, 1279), stretch=st.floats(1.0, 12.0))
def test_removed_face_never_beats_the_bound(face, stretch):
    """A one-face hole: the removed face itself is a non-folding patch, so its quality <= bound."""
    V, F = sphere(3)
    V = V * np.array([stretch, 1.0, 1.0])
    keep = np.ones(len(F), bool)
    keep[face] = False
    bound = corner_quality_bound(V, F[keep], F[face])
    q = triangle_quality(V, F[[face]])[0]
    assert q <= bound + 1e-9
    # a sharp face (stretched sphere) gives a bound below the equilateral's
    if q < 0.5:
        assert bound < 1.0


def test_outline_ratios_separate_islands_from_holes():
    V, F = grid(12)
    centre = V[F].mean(axis=1)
    F = F[~np.all(np.abs(centre[:, :2] - 6.0) < 2.0, axis=1)]  # an interior hole
    k = len(V)
    V = np.concatenate([V, [[20, 0, 0], [21, 0, 0], [20, 1, 0]]])
    F = np.concatenate([F, [[k, k + 1, k + 2]]])  # a lone triangle (its outline is no hole)
    loops = boundary_loops(F)
    ratios = outline_ratios(V, F, loops)
    by_size = {len(lp): r for lp, r in zip(loops, ratios)}
    assert by_size[16] < 0.2  # the hole: 16 of 144 - 16 cells
    assert by_size[48] >= OUTLINE_RATIO  # the grid's own border outlines its component
    assert by_size[3] == pytest.approx(1.0)


def test_sphere_cap_hole_is_not_an_outline():
    V, F = sphere(3)
    F = F[V[F].mean(axis=1)[:, 2] < 0.7]
    assert outline_ratios(V, F, boundary_loops(F))[0] < 0.2


def _row(**kw):
    row = {"ground_truth": True, "size_class": "small", "closed": True, "quality_mean": 0.9, "quality_min": 0.4,
           "quality_bound": 1.0, "dist_patch_to_gt_mean_permille": 0.1, "originals_changed": 0,
           "intersecting_new_faces": 0, "seconds": 0.01, "boundary_edges": 20}
    row.update(kw)
    return row


def _as_dict(result):
    return {name: (text, ok) for name, text, ok in result}


def test_criteria_pass_and_fail():
    target = TARGETS["meshing_close_holes_curve_unfolding"]
    base = [_row(dist_patch_to_gt_mean_permille=0.2)]
    good = _as_dict(criteria([_row()], base, target))
    assert all(ok in (True, None) for _, ok in good.values()), good
    bad = _as_dict(criteria([_row(dist_patch_to_gt_mean_permille=0.3, quality_min=0.1, seconds=0.9)], base, target))
    assert bad["patch→GT ‰, small (vs baseline)"][1] is False
    assert bad["quality min (≥ 0.3)"][1] is False
    assert bad["holes with min < 0.3 not forced by a sharp border corner"] == ("1 (0 forced)", False)
    assert bad["median s per hole ≤ 150 edges (< 0.5)"][1] is False


def test_forced_minimum_quality_is_not_held_against_a_filter():
    target = TARGETS["meshing_close_holes_differential_evolution"]
    rows = [_row(ground_truth=False, size_class="natural", quality_min=0.17, quality_bound=0.17),
            _row(ground_truth=False, size_class="outline", closed=False)]
    got = _as_dict(criteria(rows, [], target))
    assert got["holes with min < 0.3 not forced by a sharp border corner"] == ("0 (1 forced)", True)
    assert got["natural holes closed (island outlines apart)"] == ("1/1", True)
    assert got["island outlines capped (not holes)"] == ("0/1", None)


def test_open_hole_fails_the_distance_criterion():
    target = TARGETS["meshing_close_holes_lssvm_poisson"]
    rows = [_row(), _row(closed=False)]
    got = _as_dict(criteria(rows, [_row(dist_patch_to_gt_mean_permille=0.5)] * 2, target))
    assert got["cut holes closed"] == ("1/2", False)
    assert got["patch→GT ‰, small (vs baseline)"][1] is False
    assert got["original elements changed"][1] is None  # Xu's border split is allowed


def test_fan_formula_matches_triangle_quality():
    from meshlab_holefill.evaluation.metrics import fan_triangle_quality

    rng = np.random.default_rng(3)
    for angle, rho in zip(rng.uniform(0.05, 3.0, 20), rng.uniform(0.2, 5.0, 20)):
        V = np.array([[0.0, 0, 0], [1.0, 0, 0], [rho * np.cos(angle), rho * np.sin(angle), 0]])
        assert fan_triangle_quality(angle, rho) == pytest.approx(triangle_quality(V, np.array([[0, 1, 2]]))[0])


def test_short_edge_beside_a_long_one_at_a_sharp_corner_lowers_the_bound():
    """bunny10k_textured.obj's 8-edge hole: 29.8 degree corner between edges of ratio 4.15."""
    import pymeshlab

    from conftest import sample

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    (hole,) = [lp for lp in boundary_loops(F) if len(lp) == 8]
    bound = corner_quality_bound(V, F, hole.vertices)
    assert bound == pytest.approx(0.146, abs=0.002)
    assert bound < _iso_quality(np.radians(29.8))


def test_versus_variant_compares_on_the_named_cases_only():
    from meshlab_holefill.evaluation.reference_targets import versus_variant

    ours = [_row(case="sphere", dist_patch_to_gt_mean_permille=0.1), _row(case="cow.obj", dist_patch_to_gt_mean_permille=9.0)]
    zero = [_row(case="sphere", dist_patch_to_gt_mean_permille=0.2), _row(case="cow.obj", dist_patch_to_gt_mean_permille=0.1)]
    name, text, ok = versus_variant(ours, zero, ("sphere", "torus"))
    assert ok is True and text == "0.100 vs 0.200"
    assert versus_variant(zero, ours, ("sphere",))[2] is False


def test_capped_island_outline_quality_is_not_judged():
    target = TARGETS["meshing_close_holes_curve_unfolding"]
    rows = [_row(), _row(ground_truth=False, size_class="outline", quality_min=0.01)]
    got = _as_dict(criteria(rows, [_row(dist_patch_to_gt_mean_permille=0.2)], target))
    assert got["quality min (≥ 0.3)"] == ("0.400", True)
    assert got["holes with min < 0.3 not forced by a sharp border corner"] == ("0 (0 forced)", True)


def test_targets_table_judges_option_sets_but_not_the_comparison_variant():
    from types import SimpleNamespace

    from meshlab_holefill.evaluation.reference_targets import targets_table
    from meshlab_holefill.evaluation.comparison import parse_fillers

    fillers = parse_fillers("lssvm_poisson,lssvm_poisson:laplacian_prediction=zero,"
                            "min_angle_bilateral:fairing=thinplate,meshing_close_holes:maxholesize=all")
    labels = [f.label for f in fillers]
    holes = [dict(_row(case="sphere"), filler=lab) for lab in labels]
    header, rows, _ = targets_table(SimpleNamespace(fillers=fillers, holes=holes), labels[-1])
    assert header == ["criterion", "`lssvm_poisson`", "`min_angle_bilateral (fairing=thinplate)`"]
    versus = [r for r in rows if r[0].startswith("patch→GT ‰ on sphere")]
    assert versus and versus[0][1].endswith("✓") and versus[0][2] == ""  # only the default is compared with it
