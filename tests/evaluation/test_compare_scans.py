"""compare on meshes with holes of their own (scans), the report's dependencies, progress and logging.

``--report`` checks for matplotlib before any run; a scan's report has no ground-truth rows or
text, pictures every hole, colours each hole's panels on one scale of its own, and numbers holes
as ``holes`` and ``fill`` do.
"""
from __future__ import annotations

import io
import logging
import re
import sys

import numpy as np
import pytest

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.evaluation import compare as compare_module
from meshlab_holefill.evaluation.compare import compare
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case
from meshlab_holefill.evaluation.report.render import distance_norm

from conftest import sample
from evaluation_meshes import grid

FAST = "min_angle_bilateral,baseline"


def holed_grid():
    """A flat 40 x 40 grid with 12 square holes of 4 to 16 edges; its outer border (160 edges) is loop 0."""
    V, F = grid(40)
    n = 40
    remove = np.zeros(len(F), bool)
    for idx, (a, b) in enumerate((a, b) for a in (3, 12, 21, 30) for b in (3, 15, 27)):
        k = 1 + idx % 4
        for i in range(a, a + k):
            for j in range(b, b + k):
                cell = i * n + j
                remove[2 * cell:2 * cell + 2] = True
    return MeshCase("holed_grid", V, F[~remove])


@pytest.fixture(scope="module")
def scan_report(tmp_path_factory):
    out = tmp_path_factory.mktemp("scan_report")
    result = compare([holed_grid()], report=str(out), filters=FAST, maxholesize=100, progress=False)
    return result, out


# ------------------------------------------------------------------------------ item 5

def test_report_without_matplotlib_fails_before_any_run(monkeypatch, tmp_path):
    # Before: every filler ran, then the plotting module raised ModuleNotFoundError.
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    ran = []
    monkeypatch.setattr(compare_module, "run_comparison", lambda *a, **k: ran.append(1))
    with pytest.raises(ModuleNotFoundError, match=re.escape('pip install "meshlab_holefill[bench]"')):
        compare([sample("bone.ply")], report=str(tmp_path), filters="meshing_close_holes")
    assert ran == [] and not any(tmp_path.iterdir())


def test_cli_report_without_matplotlib(monkeypatch, tmp_path, capsys):
    from meshlab_holefill.cli import main

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setattr(compare_module, "run_comparison", lambda *a, **k: pytest.fail("ran before the check"))
    code = main(["compare", sample("bone.ply"), "--report", str(tmp_path / "r"), "--filters", "meshing_close_holes"])
    assert code == 2
    err = capsys.readouterr().err
    assert 'pip install "meshlab_holefill[bench]"' in err and "--no-pictures" in err


def test_tables_only_report_needs_no_matplotlib(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    compare([sample("bone.ply")], report=str(tmp_path), pictures=False, holes=1, sizes="small",
            filters="meshing_close_holes", progress=False)
    assert (tmp_path / "report.md").exists() and not (tmp_path / "holes").exists()


# ------------------------------------------------------------------------------ item 8

def test_hole_numbers_are_boundary_loop_indices(scan_report):
    # Before: holes were numbered 0, 1, ... over the evaluated loops, so skipping loop 0 (the
    # 160-edge outer border, > maxholesize) shifted every number by one against `holes` / `fill`.
    result, _ = scan_report
    case = holed_grid()
    loops = boundary_loops(case.F)
    numbers = sorted({r["hole"] for r in result.holes})
    assert numbers == list(range(1, 13)) and len(loops[0]) == 160
    for r in result.holes:
        assert r["boundary_edges"] == len(loops[r["hole"]])
    prepared = prepare_case(case, maxholesize=100)
    assert [h.index for h in prepared.holes] == [h.loop_index for h in prepared.holes] == numbers


def test_hole_numbers_match_the_holes_command_and_fill(tmp_path, capsys):
    import pymeshlab

    from meshlab_holefill.cli import main
    from meshlab_holefill.meshlab.registration import apply_filter

    case = holed_grid()
    path = str(tmp_path / "holed_grid.ply")
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(case.V, case.F))
    ms.save_current_mesh(path)
    assert main(["holes", path]) == 0
    listed = {}
    for line in capsys.readouterr().out.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].isdigit():
            listed[int(parts[0])] = int(parts[1])
    fill = apply_filter(ms, "meshing_close_holes_min_angle_bilateral", maxholesize=100)
    filled = {h["hole"]: h["boundary_edges"] for h in fill["holes"]}
    result = compare([path], filters="min_angle_bilateral", maxholesize=100, progress=False)
    compared = {r["hole"]: r["boundary_edges"] for r in result.holes}
    assert compared and all(listed[i] == filled[i] == edges for i, edges in compared.items())


def test_scan_report_has_no_ground_truth_rows_or_text(scan_report):
    _, out = scan_report
    md = (out / "report.md").read_text()
    for absent in ("cut holes closed", "best distance on", "ground-truth surface", "removed", "GT", "0/0",
                   "holes per closed mesh"):
        assert absent not in md, absent
    assert "no true surface" in md and "numbered by boundary loop" in md
    assert "natural holes closed (island outlines apart)" in md  # the rows that do apply stay
    assert "holed_grid hole 1 " in md and "holed_grid hole 12 " in md


def test_every_hole_pictured_by_default(scan_report):
    # Before: only the 8 largest of a mesh's holes got a picture (an undocumented cap).
    result, out = scan_report
    pictures = sorted(p.name for p in (out / "holes").glob("*.png"))
    assert len(pictures) == 12 == len({r["hole"] for r in result.holes})
    assert "holed_grid_hole1.png" in pictures and "holed_grid_hole12.png" in pictures


def test_picture_cap_is_an_option(tmp_path):
    from meshlab_holefill.cli import main

    ply = tmp_path / "g.ply"
    import pymeshlab

    case = holed_grid()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(case.V, case.F))
    ms.save_current_mesh(str(ply))
    assert main(["compare", str(ply), "--report", str(tmp_path / "r"), "--filters", "meshing_close_holes",
                 "--maxholesize", "100", "--pictures", "3", "--quiet"]) == 0
    pictures = sorted(p.name for p in (tmp_path / "r" / "holes").glob("*.png"))
    # the three largest: loops are numbered by decreasing edges, 1-3 are the 16-edge holes
    assert pictures == ["g.ply_hole1.png", "g.ply_hole2.png", "g.ply_hole3.png"]
    assert "--pictures 3" in (tmp_path / "r" / "report.md").read_text()
    with pytest.raises(ValueError, match="max_pictures must be a whole number"):
        compare([str(ply)], report=str(tmp_path / "x"), max_pictures=-1)


def test_distance_scale_shared_and_legible():
    # Before: a linear scale from 0 to the worst panel's distances: 1.6 and 3.5 per mille looked alike
    # next to a filter at 40.
    rng = np.random.default_rng(0)
    panels = [1.6 * rng.uniform(0.8, 1.2, 200), 3.5 * rng.uniform(0.8, 1.2, 200), 40 * rng.uniform(0.8, 1.2, 200)]
    norm = distance_norm(panels)
    assert norm.vmax >= 40 and norm.vmin <= 1.6
    assert float(norm(3.5)) - float(norm(1.6)) > 0.15
    assert float(norm(0.0)) == 0.0 and float(norm(1e3)) == 1.0  # clipped, never masked


def test_each_hole_picture_has_one_colour_bar(monkeypatch, scan_report, tmp_path):
    import matplotlib.pyplot as plt

    from meshlab_holefill.evaluation.report import render

    result, _ = scan_report
    figures = []
    monkeypatch.setattr(plt, "close", lambda fig=None: figures.append(fig))
    key = next(iter(result.render))
    rows = [r for r in result.holes if (r["case"], r["hole"]) == key]
    labels = [f.label for f in result.fillers]
    render.hole_figure(key, result.render[key], rows, labels, 1.0, str(tmp_path / "h.png"))
    fig = figures[0]
    bars = [ax for ax in fig.axes if "one scale for all panels" in ax.get_xlabel()]
    assert len(fig.axes) == len(labels) + 1 and len(bars) == 1  # a panel per filler and one colour bar


# ------------------------------------------------------------------------------ progress

class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_on_a_terminal_quiet_otherwise_and_a_log_record_per_run(monkeypatch, caplog):
    case = holed_grid()
    quiet = io.StringIO()
    monkeypatch.setattr(sys, "stderr", quiet)
    with caplog.at_level(logging.INFO, logger="meshlab_holefill"):
        result = compare([case], filters=FAST, maxholesize=100)
    assert quiet.getvalue() == ""
    records = [r for r in caplog.records if r.name.startswith("meshlab_holefill") and "compare run" in r.getMessage()]
    assert len(records) == len(result.runs) == 3
    assert "compare run 1/3: holed_grid / meshing_close_holes_min_angle_bilateral: ok, 12/12" in records[0].getMessage()
    assert records[2].comparison_run["filler"] == "meshing_close_holes (all holes)"
    assert records[2].comparison_run["closed_holes"] == 12
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    compare([case], filters="meshing_close_holes", maxholesize=100)
    assert "1/1" in terminal.getvalue() and "run" in terminal.getvalue()
