"""pymeshlab's listings and exceptions know our filters; built-ins behave as before."""
import pymeshlab
import pytest

import meshlab_holefill
from meshlab_holefill.meshlab.exceptions import MeshSetFilterParameterError
from meshlab_holefill.meshlab.mlx.names import _capture_stdout
from meshlab_holefill.meshlab.mlx.script import MlxScriptError, read_filter_script

OURS = "meshing_close_holes_min_angle_bilateral"


def test_filter_list_has_pymeshlabs_filters_in_its_order_then_ours():
    builtins = pymeshlab.filter_list.pymeshlab_original()
    listed = pymeshlab.filter_list()
    assert listed[:len(builtins)] == list(builtins)
    assert listed[len(builtins):] == meshlab_holefill.filter_list()
    assert OURS in listed and "meshing_close_holes" in listed


def test_print_filter_list_prints_pymeshlabs_listing_then_ours(capfd):
    pymeshlab.print_filter_list()
    text = capfd.readouterr().out
    original = _capture_stdout(pymeshlab.print_filter_list.pymeshlab_original)
    assert text.startswith(original)
    assert f"\t{OURS}\n" in text[len(original):]


def test_filter_parameter_values_gives_our_defaults_and_pymeshlabs_unchanged():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    ours = ms.filter_parameter_values(OURS)
    assert ours["maxholesize"] == 1000 and ours["sigma_c"] == 0.1
    builtin = ms.filter_parameter_values("meshing_close_holes")
    assert builtin == ms.filter_parameter_values.pymeshlab_original(ms, "meshing_close_holes")
    assert builtin["maxholesize"] == 30 and builtin["refinehole"] is False
    with pytest.raises(pymeshlab.PyMeshLabException, match="Failed to get default falues of filter: nope"):
        ms.filter_parameter_values("nope")


def test_our_parameter_errors_are_pymeshlab_exceptions_and_value_errors():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    with pytest.raises(pymeshlab.PyMeshLabException, match=f"filter '{OURS}' has no parameter 'bogus'") as info:
        getattr(ms, OURS)(bogus=1)
    assert isinstance(info.value, ValueError) and isinstance(info.value, meshlab_holefill.FilterParameterError)
    assert isinstance(info.value, MeshSetFilterParameterError)
    with pytest.raises(pymeshlab.PyMeshLabException, match="unknown filter 'nope'"):
        meshlab_holefill.apply_filter(ms, "nope")
    with pytest.raises(pymeshlab.PyMeshLabException, match="expected a number"):
        meshlab_holefill.apply_filter(ms, "meshing_close_holes", maxholesize="many")


def test_script_errors_are_pymeshlab_exceptions_and_value_errors():
    with pytest.raises(pymeshlab.PyMeshLabException, match="filter 'Close Holez': unknown filter") as info:
        read_filter_script('<FilterScript><filter name="Close Holez"/></FilterScript>')
    assert isinstance(info.value, ValueError) and isinstance(info.value, MlxScriptError)
