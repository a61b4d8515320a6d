"""evaluation.report: the tables of a comparison, their Markdown and HTML, and the files written."""
from __future__ import annotations

import csv
import json
from types import SimpleNamespace

from meshlab_holefill.evaluation.comparison import Filler
from meshlab_holefill.evaluation.report.labels import aggregate, short_label
from meshlab_holefill.evaluation.report.tables import markdown_table, size_table, summary_table, to_html, to_markdown
from meshlab_holefill.evaluation.report.write import write_report


def _comparison():
    """Two fillers on two cut holes: A closes both and is closer, B closes one."""
    fillers = [Filler("meshing_close_holes_a", "meshing_close_holes_a"), Filler("meshing_close_holes", "meshing_close_holes")]
    holes = []
    for f, dists in zip(fillers, ([0.1, 0.3], [0.2, None])):
        for h, d in enumerate(dists):
            row = {"case": "m", "hole": h, "filler": f.label, "filter": f.filter, "size_class": ("small", "medium")[h],
                   "shape": "compact", "boundary_edges": 20 + 40 * h, "ground_truth": True, "quality_bound": 1.0,
                   "closed": d is not None, "reason": "" if d is not None else "skipped: too large"}
            if d is not None:
                row.update(dist_patch_to_gt_mean_permille=d, quality_mean=0.9, faces=10, seconds=0.01)
            holes.append(row)
    runs = [{"case": "m", "filler": f.label, "filter": f.filter, "status": "ok", "seconds": 0.5, "originals_changed": 0}
            for f in fillers]
    settings = {"holes": 2, "sizes": ["small", "medium"], "seed": 0, "timeout": 1.0, "cores": 2,
                "fillers": [{"label": f.label, "filter": f.filter, "params": {}} for f in fillers]}
    cases = [{"case": "m", "faces": 100, "holes": [{}, {}], "kind": "cut holes", "bbox_diagonal": 1.0, "notes": []}]
    return SimpleNamespace(fillers=fillers, holes=holes, runs=runs, settings=settings, cases=cases, wall_seconds=1.0,
                           render={})


def test_labels_and_aggregates_count_closed_holes_only():
    rows = _comparison().holes
    assert short_label("meshing_close_holes_a") == "a" and short_label("meshing_close_holes (x)") == "close_holes (x)"
    assert aggregate([r for r in rows if r["filler"] == "meshing_close_holes"], "dist_patch_to_gt_mean_permille",
                     "mean") == 0.2
    assert aggregate([r for r in rows if not r["closed"]], "faces", "sum") is None


def test_summary_and_size_tables_bold_the_best():
    header, rows, bold = summary_table(_comparison())
    assert rows[0][:2] == ["`meshing_close_holes_a`", "2/2"] and rows[1][:2] == ["`meshing_close_holes`", "1/2"]
    header, rows, bold = size_table(_comparison())
    assert rows == [["small (1)", "0.100 (1/1)", "0.200 (1/1)"], ["medium (1)", "0.300 (1/1)", "– (0/1)"]]
    assert bold == [{1}, {1}]


def test_markdown_and_html_of_the_same_blocks():
    blocks = [("h", 2, "T"), ("table", ["a", "b"], [["1", "`x`"]], [{0}])]
    assert markdown_table(["a", "b"], [["1", "2"]], [{1}]) == "| a | b |\n|---|---|\n| 1 | **2** |"
    assert "| **1** | `x` |" in to_markdown(blocks)
    page = to_html(blocks, "t")
    assert "<td class='best'>1</td>" in page and "<code>x</code>" in page


def test_write_report_without_pictures(tmp_path):
    path = write_report(_comparison(), str(tmp_path), pictures=False, command="cmd")
    assert path.endswith("report.md") and "`cmd`" in open(path).read()
    assert len(json.load(open(tmp_path / "results.json"))["holes"]) == 4
    assert len(list(csv.DictReader(open(tmp_path / "results.csv")))) == 4
    assert "skipped: too large" in (tmp_path / "report.html").read_text()
