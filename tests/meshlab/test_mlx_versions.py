"""MeshLab versions of .mlx scripts: the 2020.09 tables, reading and writing 2020.09 scripts."""
import xml.etree.ElementTree as ET
from xml.sax.saxutils import quoteattr

import numpy as np
import pytest

import meshlab_holefill
from meshlab_holefill.meshlab.exceptions import pymeshlab_filter_list
from meshlab_holefill.meshlab.mlx import names as mlx_names
from meshlab_holefill.meshlab.mlx import versions
from meshlab_holefill.meshlab.mlx.script import MlxScriptError, read_filter_script, run_filter_script
from meshlab_holefill.meshlab.mlx.versions import MlxTargetError

from conftest import meshset_from_arrays, sphere_with_holes

TABLE = versions.filters_2020()
# 2020.09 parameters current MeshLab dropped (filter -> parameters), as the tables say.
DROPPED = {
    "Iso Parametrization: Main": {"AbsLoadName", "AbsSaveName"},
    "Set Texture": {"textDim"},
    "Simplification: Clustering Decimation": {"Selected"},
    "Transfer: Vertex Attributes to Texture (1 or 2 meshes)": {"assign"},
    "Transfer: Vertex Color to Texture": {"assign"},
}


def script(*filters):
    return "<!DOCTYPE FilterScript>\n<FilterScript>\n" + "\n".join(filters) + "\n</FilterScript>\n"


def default_params_xml(f2020):
    """Every parameter of a 2020.09 filter at its default (an existing file for an empty file name)."""
    def attrs(p):
        values = dict(p.default)
        if p.type in ("RichOpenFile", "RichSaveFile") and not values.get("value"):
            values["value"] = __file__
        return " ".join(f"{k}={quoteattr(v)}" for k, v in values.items())

    return "".join(f"<Param type={quoteattr(p.type)} name={quoteattr(p.name)} {attrs(p)}/>" for p in f2020.params)


def holed_meshset():
    V, F, _ = sphere_with_holes(subdiv=3)
    ms = meshset_from_arrays(V, F)
    ms.meshing_remove_unreferenced_vertices()
    return ms


# --- the tables ---------------------------------------------------------------------------


def test_the_2020_09_table_lists_every_filter_of_its_meshlabserver():
    assert len(TABLE) == 266
    assert sum(len(f.params) for f in TABLE.values()) == 844
    close = TABLE["Close Holes"]
    assert [(p.name, p.type) for p in close.params] == [
        ("MaxHoleSize", "RichInt"), ("Selected", "RichBool"), ("NewFaceSelected", "RichBool"),
        ("SelfIntersection", "RichBool")]


def test_every_2020_09_filter_with_a_current_counterpart_maps_to_a_pymeshlab_filter():
    builtins = set(pymeshlab_filter_list())
    unmapped = {name for name, f in TABLE.items() if f.python_name is None}
    assert all(TABLE[name].note for name in unmapped)
    assert unmapped == {"Compact faces", "Compact vertices", "CSG Operation", "Change Visibility of layer(s)",
                        "Change the current layer", "Delaunay Triangulation", "Vertex Color Noise",
                        "Directional Geom. Preserv.", "Cross Field Creation", "Global registration"}
    assert {f.python_name for f in TABLE.values() if f.python_name} <= builtins
    for name, f in TABLE.items():
        if f.python_name:
            assert mlx_names.resolve_filter(name).python_name == f.python_name, name


def test_the_2020_09_and_current_tables_agree_where_the_names_are_unchanged():
    current = {display: python for python, display in mlx_names.builtin_display_names().items()}
    same = [name for name in TABLE if name in current]
    assert len(same) > 200
    assert [n for n in same if TABLE[n].python_name != current[n]] == []


def test_2020_09_parameters_have_current_counterparts_but_the_listed_dropped_ones():
    dropped = {}
    for name, f in TABLE.items():
        if f.python_name is None:
            continue
        kinds = mlx_names.builtin_param_kinds(f.python_name)
        missing = {p.name for p in f.params if f.python_param(p.name) not in kinds}
        if missing:
            dropped[name] = missing
    assert dropped == DROPPED


# --- reading ------------------------------------------------------------------------------


@pytest.mark.parametrize("name, method", [("Repair non Manifold Edges by removing faces", 0),
                                          ("Repair non Manifold Edges by splitting vertices", 1),
                                          ("Remove T-Vertices by Edge Collapse", 0),
                                          ("Remove T-Vertices by Edge Flip", 1)])
def test_a_2020_09_name_reads_as_the_current_filter_with_its_implied_parameter(name, method):
    step, = read_filter_script(script(f"<filter name={quoteattr(name)}>{default_params_xml(TABLE[name])}</filter>")).steps
    assert step.how == "MeshLab 2020.09 name"
    assert step.kwargs["method"] == method


def test_every_2020_09_filter_and_parameter_name_is_read():
    unreadable = []
    for name, f in TABLE.items():
        if f.python_name is None or any(p.type == "RichShotf" for p in f.params):
            continue  # a camera shot, which pymeshlab cannot set
        try:
            read_filter_script(script(f"<filter name={quoteattr(name)}>{default_params_xml(f)}</filter>"))
        except MlxScriptError as exc:
            unreadable.append(str(exc))
    assert unreadable == []


def test_renamed_and_dropped_2020_09_parameters():
    text = script('<filter name="Select Folded Faces"><Param type="RichDynamicFloat" name="AngleThreshold" '
                  'value="150" min="90" max="180"/></filter>',
                  '<filter name="Simplification: Clustering Decimation"><Param type="RichAbsPerc" name="Threshold" '
                  'value="0.05" min="0" max="1"/><Param type="RichBool" name="Selected" value="false"/></filter>')
    folded, clustering = read_filter_script(text).steps
    assert folded.kwargs == {"folded_faces_angle_threshold": 150.0, "usear": False, "usenf": False,
                             "select_folded_faces": True}
    assert list(clustering.kwargs) == ["threshold"]
    with pytest.raises(MlxScriptError, match=r"parameter 'Selected': a MeshLab 2020.09 parameter that current "
                                             r"MeshLab \(pymeshlab\) no longer has; only its 2020.09 default"):
        read_filter_script(text.replace('name="Selected" value="false"', 'name="Selected" value="true"'))


def test_a_2020_09_filter_current_meshlab_removed_is_named_with_the_reason():
    with pytest.raises(MlxScriptError, match=r"filter 'Compact faces': a MeshLab 2020.09 filter that current "
                                             r"MeshLab does not have: removed in MeshLab 2022"):
        read_filter_script(script('<filter name="Compact faces"/>'))


def test_pymeshlab_doors_run_a_2020_09_script(tmp_path):
    path = tmp_path / "old.mlx"
    path.write_text(script('<filter name="Repair non Manifold Edges by removing faces"/>',
                           '<filter name="Close Holes"><Param type="RichInt" name="MaxHoleSize" value="100"/>'
                           '<Param type="RichBool" name="Selected" value="false"/>'
                           '<Param type="RichBool" name="NewFaceSelected" value="true"/>'
                           '<Param type="RichBool" name="SelfIntersection" value="true"/></filter>'))
    ms = holed_meshset()
    ms.load_filter_script(str(path))
    ms.apply_filter_script()
    reference = holed_meshset()
    run_filter_script(reference, str(path))
    assert np.array_equal(ms.current_mesh().face_matrix(), reference.current_mesh().face_matrix())
    assert ms.current_mesh().face_number() > holed_meshset().current_mesh().face_number()


# --- writing ------------------------------------------------------------------------------


def recorded(*calls):
    ms = holed_meshset()
    for name, kwargs in calls:
        meshlab_holefill.apply_filter(ms, name, **kwargs)
    return ms


def filters_of(text):
    return [(f.get("name"), [p.get("name") for p in f]) for f in ET.fromstring(text).iter("filter")]


def test_the_2020_09_target_writes_its_names_and_parameter_sets():
    ms = recorded(("meshing_repair_non_manifold_edges", {"method": 1}), ("meshing_close_holes", {"maxholesize": 100}),
                  ("compute_selection_bad_faces", {"usear": False}))
    text = meshlab_holefill.filter_script_xml(ms, target="meshlab-2020.09")
    assert filters_of(text) == [
        ("Repair non Manifold Edges by splitting vertices", []),
        ("Close Holes", ["MaxHoleSize", "Selected", "NewFaceSelected", "SelfIntersection"]),
        ("Select 'problematic' faces", ["useAR", "ARatio", "useNF", "NFRatio"])]
    assert 'type="RichDynamicFloat" name="ARatio"' in text
    current = filters_of(meshlab_holefill.filter_script_xml(ms))
    assert current[0][0] == "Repair non Manifold Edges" and "RefineHole" in current[1][1]


def test_the_2020_09_target_refuses_what_meshlab_2020_09_cannot_run(tmp_path):
    ours = recorded(("meshing_close_holes_min_angle_bilateral", {}))
    with pytest.raises(MlxTargetError, match=r"filter 'meshing_close_holes_min_angle_bilateral' \('Close Holes: "
                                             r"Minimum Angle \+ Bilateral'\) is a meshlab_holefill filter"):
        meshlab_holefill.save_filter_script(ours, tmp_path / "x.mlx", target="meshlab-2020.09")
    refined = recorded(("meshing_close_holes", {"refinehole": True}))
    with pytest.raises(MlxTargetError, match="parameter 'refinehole' = True does not exist in MeshLab 2020.09"):
        meshlab_holefill.filter_script_xml(refined, target="meshlab-2020.09")
    with pytest.raises(ValueError, match="unknown MeshLab target 'meshlab-1.3'"):
        meshlab_holefill.filter_script_xml(refined, target="meshlab-1.3")
    assert not (tmp_path / "x.mlx").exists()


def test_a_2020_09_script_replays_to_the_same_mesh(tmp_path):
    calls = (("meshing_remove_duplicate_vertices", {}), ("meshing_close_holes", {"maxholesize": 100}),
             ("apply_coord_laplacian_smoothing", {"stepsmoothnum": 2, "selected": True}))
    ms = recorded(*calls)
    path = meshlab_holefill.save_filter_script(ms, tmp_path / "r.mlx", target="meshlab-2020.09")
    replay = holed_meshset()
    run_filter_script(replay, path)
    assert np.array_equal(replay.current_mesh().vertex_matrix(), ms.current_mesh().vertex_matrix())
