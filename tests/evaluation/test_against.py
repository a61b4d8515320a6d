"""evaluation.report.against: a run beside an earlier run's results.csv."""
import csv
import os

import pytest

from meshlab_holefill.evaluation.report.against import against_table, read_results_csv


def _row(case, hole, filler, size_class, closed=True, dist=1.0, crease=None, edges=20):
    return {"case": case, "hole": hole, "filler": filler, "size_class": size_class, "boundary_edges": edges,
            "closed": closed, "ground_truth": True, "dist_patch_to_gt_mean_permille": dist,
            "crease_error_mean_deg": crease}


def _write(path, rows):
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]) + ["seconds"])
        writer.writeheader()
        writer.writerows([dict(r, seconds=0.5) for r in rows])


def test_the_means_are_over_the_holes_both_runs_closed_and_a_hole_is_matched_by_case_number_and_edges(tmp_path):
    f = "meshing_close_holes_curve_unfolding"
    earlier = [_row("box", 0, f, "crease", dist=4.0, crease=50.0), _row("box", 1, f, "crease", dist=2.0, crease=None),
               _row("box", 2, f, "crease", closed=False, dist=None), _row("ball", 0, f, "small", dist=0.5),
               _row("ball", 1, f, "small", dist=9.0, edges=30)]
    _write(tmp_path / "results.csv", earlier)
    now = [_row("box", 0, f, "crease", dist=3.0, crease=40.0), _row("box", 1, f, "crease", dist=2.5),
           _row("box", 2, f, "crease", dist=7.0), _row("ball", 0, f, "small", dist=float("nan")),
           _row("ball", 1, f, "small", dist=1.0, edges=31),  # another hole where the cut fell otherwise
           _row("box", 0, "meshing_close_holes_lssvm_poisson", "crease", dist=1.0)]  # a filler run once only
    header, rows = against_table(read_results_csv(tmp_path / "results.csv"), now)
    assert header[:3] == ["filler", "holes", "closed before → now"]
    assert rows == [["`curve_unfolding`", "small (1)", "1 → 1", "–", "–"],
                    ["`curve_unfolding`", "crease (3)", "2 → 3", "3.000 → 2.750", "50.0 → 40.0"]]


def test_a_file_that_is_not_a_results_csv_is_refused_by_name(tmp_path):
    path = tmp_path / "other.csv"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match="other.csv' is not a results.csv of a comparison: no column case"):
        read_results_csv(path)


def test_the_benchmark_sets_its_suite_beside_an_earlier_run(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(os.path.join(os.path.dirname(__file__), "..", "..", "scripts"))
    import benchmark

    with pytest.raises(SystemExit):
        benchmark.main(["--against", str(tmp_path / "missing.csv"), "--cases", "sphere"])
    f = "meshing_close_holes_min_angle_bilateral"
    out = tmp_path / "out"
    benchmark.main(["--filters", f, "--cases", "sphere", "--holes", "2", "--no-pictures", "--out", str(out)])
    benchmark.main(["--filters", f, "--cases", "sphere", "--holes", "2", "--no-pictures", "--out", str(out),
                    "--against", str(out / "suite" / "results.csv")])
    text = (out / "benchmark.md").read_text()
    section = text.split("**Against an earlier run**", 1)[1]
    lines = [line for line in section.splitlines() if line.startswith("| `min_angle_bilateral`")]
    assert len(lines) == 2  # the sphere's two hole classes
    for line in lines:
        closed, dist = line.split(" | ")[2:4]
        before, now = dist.split(" → ")
        assert closed == "1 → 1" and before == now  # the same holes filled the same way
