import numpy as np
import pymeshlab

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
