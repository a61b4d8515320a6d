"""evaluation.reference_targets: where a filter stands against the reference figures, and the table."""
from __future__ import annotations

from types import SimpleNamespace

from meshlab_holefill.evaluation.comparison import parse_fillers
from meshlab_holefill.evaluation.reference_targets import REFERENCES, reference_table, standing, versus_variant


def _row(**kw):
    row = {"ground_truth": True, "size_class": "small", "closed": True, "quality_mean": 0.9, "quality_min": 0.4,
           "quality_bound": 1.0, "dist_patch_to_gt_mean_permille": 0.1, "originals_changed": 0,
           "intersecting_new_faces": 0, "seconds": 0.01, "boundary_edges": 20}
    row.update(kw)
    return row


def _as_dict(result):
    return {name: (text, ok) for name, text, ok in result}


def test_standing_passes_and_fails():
    reference = REFERENCES["meshing_close_holes_curve_unfolding"]
    base = [_row(dist_patch_to_gt_mean_permille=0.2)]
    good = _as_dict(standing([_row()], base, reference))
    assert all(ok in (True, None) for _, ok in good.values()), good
    bad = _as_dict(standing([_row(dist_patch_to_gt_mean_permille=0.3, quality_min=0.1, seconds=0.9)], base, reference))
    assert bad["patch→GT ‰, small (vs baseline)"][1] is False
    assert bad["quality min (≥ 0.3)"][1] is False
    assert bad["holes with min < 0.3 not forced by a sharp border corner"] == ("1 (0 forced)", False)
    assert bad["median s per hole ≤ 150 edges (< 0.5)"][1] is False


def test_forced_minimum_quality_is_not_held_against_a_filter():
    reference = REFERENCES["meshing_close_holes_differential_evolution"]
    rows = [_row(ground_truth=False, size_class="natural", quality_min=0.17, quality_bound=0.17),
            _row(ground_truth=False, size_class="outline", closed=False)]
    got = _as_dict(standing(rows, [], reference))
    assert got["holes with min < 0.3 not forced by a sharp border corner"] == ("0 (1 forced)", True)
    assert got["natural holes closed (island outlines apart)"] == ("1/1", True)
    assert got["island outlines capped (not holes)"] == ("0/1", None)


def test_open_hole_fails_the_distance_figure():
    reference = REFERENCES["meshing_close_holes_lssvm_poisson"]
    rows = [_row(), _row(closed=False)]
    got = _as_dict(standing(rows, [_row(dist_patch_to_gt_mean_permille=0.5)] * 2, reference))
    assert got["cut holes closed"] == ("1/2", False)
    assert got["patch→GT ‰, small (vs baseline)"][1] is False
    assert got["original elements changed"][1] is None  # Xu's border split is allowed


def test_versus_variant_compares_on_the_named_cases_only():
    ours = [_row(case="sphere", dist_patch_to_gt_mean_permille=0.1), _row(case="cow.obj", dist_patch_to_gt_mean_permille=9.0)]
    zero = [_row(case="sphere", dist_patch_to_gt_mean_permille=0.2), _row(case="cow.obj", dist_patch_to_gt_mean_permille=0.1)]
    name, text, ok = versus_variant(ours, zero, ("sphere", "torus"))
    assert ok is True and text == "0.100 vs 0.200"
    assert versus_variant(zero, ours, ("sphere",))[2] is False


def test_capped_island_outline_quality_is_not_judged():
    reference = REFERENCES["meshing_close_holes_curve_unfolding"]
    rows = [_row(), _row(ground_truth=False, size_class="outline", quality_min=0.01)]
    got = _as_dict(standing(rows, [_row(dist_patch_to_gt_mean_permille=0.2)], reference))
    assert got["quality min (≥ 0.3)"] == ("0.400", True)
    assert got["holes with min < 0.3 not forced by a sharp border corner"] == ("0 (0 forced)", True)


def test_reference_table_judges_option_sets_but_not_the_comparison_variant():

    fillers = parse_fillers("lssvm_poisson,lssvm_poisson:laplacian_prediction=zero:poisson_boundary=dirichlet,"
                            "min_angle_bilateral:fairing=thinplate,meshing_close_holes:maxholesize=all")
    labels = [f.label for f in fillers]
    holes = [dict(_row(case="sphere"), filler=lab) for lab in labels]
    header, rows, _ = reference_table(SimpleNamespace(fillers=fillers, holes=holes), labels[-1])
    assert header == ["reference figure", "`lssvm_poisson`", "`min_angle_bilateral (fairing=thinplate)`"]
    versus = [r for r in rows if r[0].startswith("patch→GT ‰ on sphere")]
    assert versus and versus[0][1].endswith("✓") and versus[0][2] == ""  # only the default is compared with it

