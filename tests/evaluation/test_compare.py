"""evaluation.compare: compare() and ``meshlab-holefill compare`` end to end, report files included."""
from __future__ import annotations

import csv
import json

import numpy as np

from meshlab_holefill.evaluation.compare import compare
from meshlab_holefill.evaluation.comparison import MeshCase

from conftest import sample
from evaluation_meshes import sphere


def test_compare_report_end_to_end(tmp_path):
    V, F = sphere(4)
    case = MeshCase("sphere", V, F, analytic=lambda X: np.linalg.norm(X, axis=1) - 1.0)
    result = compare([case, sample("bunny10k_textured.obj")],
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
    # Holes are numbered by boundary loop (largest first), so they are looked up by size class.
    sphere_rows = {r["size_class"]: r for r in result.holes if r["case"] == "sphere" and r["filler"] == hu}
    for size, (gt_permille, analytic) in zip(("small", "medium"), [(3.0, 0.02), (12.0, 0.05)]):
        r = sphere_rows[size]
        assert r["closed"] and r["dist_patch_to_gt_mean_permille"] < gt_permille and r["analytic_dist_mean"] < analytic
    # Measured 0.774 on the bunny's 38-edge hole (1.5x slack on the shortfall from 1); MeshLab's own
    # Close Holes, an unrefined triangulation, reaches only 0.55 there.
    natural = by[("bunny10k_textured.obj", 0, hu)]
    assert natural["closed"] and "dist_patch_to_gt_mean" not in natural and natural["quality_mean"] > 0.65
    default = [r for r in result.holes if r["filler"] == "meshing_close_holes (default)" and r["boundary_edges"] >= 30]
    assert default and all("maxholesize" in r["reason"] for r in default)


def test_cli_compare(tmp_path, capsys):
    from meshlab_holefill.cli import main

    code = main(["compare", sample("bone.ply"), "--holes", "1", "--sizes", "small",
                 "--filters", "meshing_close_holes", "--report", str(tmp_path), "--quiet", "--no-pictures"])
    assert code == 0
    out = capsys.readouterr().out
    assert "meshing_close_holes" in out and "1/1" in out
    assert "meshlab-holefill compare" in (tmp_path / "report.md").read_text()

