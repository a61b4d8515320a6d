import json
import logging

import pymeshlab
import pytest

import meshlab_holefill
from meshlab_holefill.cli import main

from conftest import sample


def test_fill_writes_a_closed_mesh(tmp_path, capsys):
    out = tmp_path / "filled.ply"
    code = main(["fill", sample("bunny10k_textured.obj"), str(out), "--filter",
                 "meshing_close_holes_min_angle_bilateral", "--iterations", "2"])
    assert code == 0
    assert "closed_holes=5" in capsys.readouterr().out
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(out))
    assert ms.get_topological_measures()["boundary_edges"] == 0


def test_fill_with_a_builtin_filter(tmp_path):
    out = tmp_path / "filled.ply"
    assert main(["fill", sample("bunny10k_textured.obj"), str(out), "--filter", "meshing_close_holes",
                 "--maxholesize", "50"]) == 0
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(out))
    topo = ms.get_topological_measures()
    assert topo["boundary_edges"] == 0 and topo["non_two_manifold_edges"] == 0


def test_holes_table_lists_every_loop(capsys):
    assert main(["holes", sample("bunny10k_textured.obj")]) == 0
    text = capsys.readouterr().out
    assert "5 boundary loops" in text
    rows = [line.split() for line in text.splitlines()[2:]]
    assert [int(r[1]) for r in rows] == [38, 22, 22, 19, 8]


def test_filters_lists_parameters_and_defaults(capsys):
    assert main(["filters"]) == 0
    text = capsys.readouterr().out
    assert "meshing_close_holes_min_angle_bilateral" in text and "sigma_c : float, default 0.1" in text


def test_bad_parameter_is_a_clear_error(tmp_path, capsys):
    code = main(["fill", sample("bunny10k_textured.obj"), str(tmp_path / "x.ply"), "--alpha", "-3"])
    assert code == 2
    assert "alpha" in capsys.readouterr().err


def test_missing_input_file_is_a_clear_error(tmp_path, capsys):
    code = main(["holes", str(tmp_path / "nope.ply")])
    assert code == 2
    assert capsys.readouterr().err.startswith("meshlab-holefill: error:")


def test_holes_table_marks_island_outlines(capsys):
    """face000.ply: the loose fragments of the scan are outlines, not holes."""
    assert main(["holes", sample("rangemaps/face000.ply")]) == 0
    rows = capsys.readouterr().out.splitlines()[2:]
    outline = {int(r.split()[1]) for r in rows if "outline of a whole component" in r}
    inner = [int(r.split()[1]) for r in rows if "outline" not in r]
    assert {256, 64, 53} <= outline
    assert 227 in inner and 142 in inner


def test_fill_with_a_builtin_filter_reports_a_bad_value_or_name_clearly(tmp_path, capsys):
    out = tmp_path / "filled.ply"
    for args, message in ((["--maxholesize", "abc"], "parameter 'maxholesize': expected a number, got 'abc'"),
                          (["--maxholesiz", "30"], "unknown parameter 'maxholesiz' (known: maxholesize,")):
        assert main(["fill", sample("bunny10k_textured.obj"), str(out), "--filter", "meshing_close_holes"]
                    + args) == 2
        assert message in capsys.readouterr().err
    assert not out.exists()


# --- exit codes, progress, --report, output checked first, one hole numbering ---------------------------

import csv
import io
BUNNY = sample("bunny10k_textured.obj")
FAST = ["--filter", "meshing_close_holes_min_angle_bilateral", "--iterations", "1", "--workers", "1"]


def _one_hole_fails(monkeypatch):
    """Make the 8-edge hole of the bunny fail, as holes do on scans."""
    import importlib

    from meshlab_holefill.errors import HoleFillError
    from meshlab_holefill.meshlab.registration import FILTERS

    module = importlib.import_module(FILTERS["meshing_close_holes_min_angle_bilateral"].extra["module"])
    real = module.fill

    def fill(ctx, **kw):
        if len(ctx.loop) == 8:
            raise HoleFillError("made to fail by the test")
        return real(ctx, **kw)

    monkeypatch.setattr(module, "fill", fill)


def test_a_failed_hole_is_exit_0_and_listed_and_strict_makes_it_1(tmp_path, capsys, monkeypatch):
    """Reproduced first: fill exited 1 whenever a hole failed, with out.ply written."""
    _one_hole_fails(monkeypatch)
    out = tmp_path / "out.ply"
    assert main(["fill", BUNNY, str(out)] + FAST) == 0
    text = capsys.readouterr().out
    assert "failed_holes=1" in text and "made to fail by the test" in text and out.exists()
    assert main(["fill", BUNNY, str(out), "--strict"] + FAST) == 1


def test_errors_are_exit_2(tmp_path, capsys):
    assert main(["fill", str(tmp_path / "nope.ply"), str(tmp_path / "o.ply")]) == 2
    assert main(["fill", BUNNY, str(tmp_path / "o.ply"), "stray"]) == 2
    assert "unexpected argument 'stray'" in capsys.readouterr().err
    assert main(["run", "filters/close_holes_min_angle_bilateral.mlx", BUNNY]) == 2
    assert "INPUT and OUTPUT are required" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="2"):
        main(["fill", BUNNY])  # argparse: OUTPUT missing


def test_output_is_checked_before_filling(tmp_path, capsys, monkeypatch):
    """Reproduced first: an unwritable output was found only after the whole fill."""
    from meshlab_holefill.meshlab import registration

    monkeypatch.setattr(registration, "apply_filter", lambda *a, **k: pytest.fail("filled before the check"))
    for output, message in ((tmp_path / "out.txt", "cannot write '.txt'"),
                            (tmp_path / "missing" / "out.ply", "does not exist"),
                            (tmp_path / "out", "has no extension")):
        assert main(["fill", BUNNY, str(output)]) == 2
        assert message in capsys.readouterr().err
    assert main(["fill", BUNNY, str(tmp_path / "out.ply"), "--report", str(tmp_path / "holes.txt")]) == 2
    assert "give a .json or .csv file" in capsys.readouterr().err
    with pytest.raises(ValueError, match="cannot write '.xyz2'"):
        from meshlab_holefill.meshlab.meshset_io import check_mesh_output_path
        check_mesh_output_path(str(tmp_path / "o.xyz2"))


def test_report_json_and_csv_with_the_numbering_of_holes(tmp_path, capsys):
    assert main(["fill", BUNNY, str(tmp_path / "o.ply"), "--report", str(tmp_path / "holes.json")] + FAST) == 0
    doc = json.loads((tmp_path / "holes.json").read_text())
    assert doc["filter"] == "meshing_close_holes_min_angle_bilateral" and doc["closed_holes"] == 5
    assert [h["boundary_edges"] for h in doc["holes"]] == [38, 22, 22, 19, 8]
    assert {"centroid", "perimeter", "diameter", "area", "size_class"} <= set(doc["holes"][0])
    assert main(["fill", BUNNY, str(tmp_path / "o.ply"), "--report", str(tmp_path / "holes.csv")] + FAST) == 0
    rows = list(csv.DictReader(open(tmp_path / "holes.csv")))
    assert [int(r["hole"]) for r in rows] == [0, 1, 2, 3, 4] and rows[0]["status"] == "closed"
    capsys.readouterr()
    assert main(["holes", BUNNY]) == 0
    table = [line.split() for line in capsys.readouterr().out.splitlines()[2:]]
    for row, hole in zip(table, doc["holes"]):
        assert int(row[0]) == hole["hole"] and int(row[1]) == hole["boundary_edges"] and row[2] == hole["size_class"]
        assert float(row[3]) == pytest.approx(hole["perimeter"], rel=1e-3)
        assert float(row[5]) == pytest.approx(hole["area"], rel=1e-3)


def test_holes_and_fill_agree_on_a_scan_with_outlines(tmp_path, capsys):
    scan = sample("rangemaps/face000.ply")
    assert main(["holes", scan]) == 0
    classes = {int(r.split()[0]): r.split()[2] for r in capsys.readouterr().out.splitlines()[2:]}
    assert main(["fill", scan, str(tmp_path / "o.ply"), "--report", str(tmp_path / "h.json"), "--quiet",
                 "--maxholesize", "30"] + FAST) == 0
    holes = json.loads((tmp_path / "h.json").read_text())["holes"]
    assert {h["hole"]: h["size_class"] for h in holes if "size_class" in h} == \
        {i: c for i, c in classes.items() if c in ("hole", "outline")}


def test_no_progress_and_no_log_when_stderr_is_not_a_terminal(tmp_path, capsys):
    assert main(["fill", BUNNY, str(tmp_path / "o.ply")] + FAST) == 0
    assert capsys.readouterr().err == ""


class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_on_a_terminal_and_quiet_turns_it_off(tmp_path, monkeypatch, capsys):
    terminal = _Terminal()
    monkeypatch.setattr("sys.stderr", terminal)
    assert main(["fill", BUNNY, str(tmp_path / "o.ply")] + FAST) == 0
    assert "filling holes" in terminal.getvalue() and "/5 [" in terminal.getvalue()
    terminal.seek(0)
    terminal.truncate()
    capsys.readouterr()
    assert main(["fill", BUNNY, str(tmp_path / "o.ply"), "--quiet"] + FAST) == 0
    assert terminal.getvalue() == "" and capsys.readouterr().out == ""


def test_verbose_logs_one_line_per_hole(tmp_path, capsys):
    assert main(["fill", BUNNY, str(tmp_path / "o.ply"), "--verbose"] + FAST) == 0
    lines = [line for line in capsys.readouterr().err.splitlines() if line.startswith("meshlab-holefill: hole ")]
    assert len(lines) == 5 and "hole 4 (8 edges): closed" in lines[4]
    assert logging.getLogger("meshlab_holefill").handlers == []  # taken off again


def test_the_package_logger_reports_each_hole_to_library_users(caplog):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(BUNNY)
    with caplog.at_level(logging.INFO, logger="meshlab_holefill"):
        ms.meshing_close_holes_min_angle_bilateral(iterations=1, workers=1)
    assert [r.name for r in caplog.records].count("meshlab_holefill.core.pipeline") == 5


def test_version_and_help_name_the_exit_codes(capsys):
    with pytest.raises(SystemExit, match="0"):
        main(["--version"])
    assert capsys.readouterr().out.strip() == f"meshlab-holefill {meshlab_holefill.__version__}"
    for command in ("fill", "run"):
        with pytest.raises(SystemExit, match="0"):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "exit status: 0 when the run completed" in text and "--strict" in text and "--verbose" in text


def test_run_exits_0_with_a_failed_hole_and_1_with_strict(tmp_path, capsys, monkeypatch):
    _one_hole_fails(monkeypatch)
    script = "filters/close_holes_min_angle_bilateral.mlx"
    assert main(["run", script, BUNNY, str(tmp_path / "o.ply")]) == 0
    assert "made to fail by the test" in capsys.readouterr().out
    assert main(["run", script, BUNNY, str(tmp_path / "o.ply"), "--strict"]) == 1


def test_compile_rejects_a_bad_process_count(capsys):
    assert main(["compile", "--processes", "0"]) == 2
    assert "--processes must be at least 1" in capsys.readouterr().err


def test_compile_lists_every_algorithm(capsys):
    assert main(["compile", "--processes", "1"]) == 0
    out = capsys.readouterr().out
    for name in meshlab_holefill.algorithm_names():
        assert name in out
