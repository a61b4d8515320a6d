"""MeshLab .mlx filter scripts: names, parameter types, validation, recording, the shipped workflows, the CLI."""
import gc
import os
import re
import weakref
import xml.etree.ElementTree as ET

import numpy as np
import pymeshlab
import pytest

import meshlab_holefill
from meshlab_holefill.meshlab.mlx import names as mlx_names
from meshlab_holefill.meshlab import registration as registry
from meshlab_holefill.cli import main
from meshlab_holefill.algorithms import ALGORITHMS
from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.meshlab.mlx.script import MlxRunError, MlxScriptError, read_filter_script, run_filter_script

from conftest import mesh_arrays, meshset_from_arrays, sample, sphere_with_holes

WORKFLOWS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "filters")
BUNNY = sample("bunny10k_textured.obj")
OURS = "Close Holes: Minimum Angle + Bilateral"


def script(*filters):
    return "<!DOCTYPE FilterScript>\n<FilterScript>\n" + "\n".join(filters) + "\n</FilterScript>\n"


LAPLACIAN = '<filter name="Laplacian Smooth"><Param type="RichInt" name="stepSmoothNum" value="2"/></filter>'


@pytest.fixture(scope="module")
def holed_sphere(tmp_path_factory):
    """A sphere (subdiv 3) with two holes, as a .ply file."""
    V, F, _ = sphere_with_holes(subdiv=3)
    ms = meshset_from_arrays(V, F)
    ms.meshing_remove_unreferenced_vertices()
    path = str(tmp_path_factory.mktemp("mlx") / "holed_sphere.ply")
    ms.save_current_mesh(path)
    return path


def load(path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path)
    return ms


def meshes(ms):
    """(vertices, faces, vertex colours) of every layer, by mesh id."""
    out = {}
    for i in range(ms.mesh_number() + 8):
        if ms.mesh_id_exists(i):
            m = ms.mesh(i)
            out[i] = (m.vertex_matrix(), m.face_matrix(), m.vertex_color_matrix())
    return out


def assert_same_meshes(a, b):
    ma, mb = meshes(a), meshes(b)
    assert ma.keys() == mb.keys()
    for i in ma:
        for x, y in zip(ma[i], mb[i]):
            np.testing.assert_array_equal(x, y)


def pymeshlab_run(path_or_text, start, tmp_path):
    """pymeshlab's own runner: load_filter_script + apply_filter_script on a MeshSet loaded from ``start``."""
    if path_or_text.lstrip().startswith("<"):
        path = tmp_path / "pymeshlab_input.mlx"
        path.write_text(path_or_text)
        path_or_text = str(path)
    ms = load(start)
    ms.load_filter_script(path_or_text)
    ms.apply_filter_script()
    return ms


def without_last_filters(path, count):
    """The XML of a script file with its last ``count`` filters removed."""
    root = ET.parse(path).getroot()
    for element in [e for e in root if e.tag == "filter"][-count:]:
        root.remove(element)
    return ET.tostring(root, encoding="unicode")


# --- names ----------------------------------------------------------------------------------


def test_the_display_name_table_agrees_with_pymeshlab_and_reads_back():
    assert mlx_names.check_filter_table() == {"missing": [], "unknown": [], "duplicate_display_names": []}
    for python_name, display in mlx_names.builtin_display_names().items():
        understood = mlx_names.resolve_filter(display)
        assert (understood.python_name, understood.ours, understood.how) == (python_name, False, "display name")


def test_names_and_parameter_names_agree_with_what_pymeshlab_writes(holed_sphere, tmp_path):
    ms = load(holed_sphere)
    ms.meshing_remove_duplicate_vertices()
    ms.meshing_close_holes(maxholesize=30)
    ms.apply_coord_taubin_smoothing(stepsmoothnum=2)
    ms.compute_matrix_from_rotation(rotaxis="custom axis", customaxis=np.array([0, 0.6, 0.8]), angle=17.0)
    ms.compute_selection_by_condition_per_face(condselect="fi < 50")
    ms.set_color_per_vertex(color1=pymeshlab.Color(200, 10, 20, 255))
    ms.compute_normal_per_vertex()
    ms.apply_selection_dilatation()
    ms.meshing_repair_non_manifold_vertices()
    ms.create_dodecahedron_sym()
    applied = ["meshing_remove_duplicate_vertices", "meshing_close_holes", "apply_coord_taubin_smoothing",
               "compute_matrix_from_rotation", "compute_selection_by_condition_per_face", "set_color_per_vertex",
               "compute_normal_per_vertex", "apply_selection_dilatation", "meshing_repair_non_manifold_vertices",
               "create_dodecahedron_sym"]
    ms.save_filter_script(str(tmp_path / "written.mlx"))
    written = ET.parse(tmp_path / "written.mlx").getroot().findall("filter")
    assert [mlx_names.builtin_display_names()[n] for n in applied] == [f.get("name") for f in written]
    for name, element in zip(applied, written):
        kinds = mlx_names.builtin_param_kinds(name)
        assert {mlx_names.python_param_name(p.get("name")) for p in element} == set(kinds)


def test_meshlab_parameter_name_rule():
    rule = mlx_names.python_param_name
    assert rule("MaxHoleSize") == "maxholesize"
    assert rule("lambda") == "lambda_"  # Taubin's parameter: a python keyword
    assert rule("Remove Isolated pieces (wrt Face Num.)") == "remove_isolated_pieces_wrt_face_num"
    assert rule("Transform: Rotate Camera or set of cameras") == "transform_rotate_camera_or_set_of_cameras"
    assert rule("Re-Orient all faces coherentely") == "re_orient_all_faces_coherentely"


@pytest.mark.parametrize("name, python_name, how", [
    ("Re-Orient all faces coherentely", "meshing_re_orient_faces_coherently", "MeshLab 2020.09 name"),
    ("re-orient all faces coherentely", "meshing_re_orient_faces_coherently", "old display name"),
    ("remove_duplicate_vertices", "meshing_remove_duplicate_vertices", "old python name"),
    ("laplacian_smooth", "apply_coord_laplacian_smoothing", "old python name"),
    ("snapshot", "save_snapshot", "old python name"),
    ("Ambient Occlusion", "compute_scalar_ambient_occlusion_gpu", "display name"),  # today's name wins
    ("meshing_close_holes", "meshing_close_holes", "python name"),
    ("close holes", "meshing_close_holes", "display name"),
    (OURS, "meshing_close_holes_min_angle_bilateral", "display name"),
    ("meshing_close_holes_min_angle_bilateral", "meshing_close_holes_min_angle_bilateral", "python name"),
])
def test_filter_names_old_and_new(name, python_name, how):
    understood = mlx_names.resolve_filter(name)
    assert (understood.python_name, understood.how) == (python_name, how)


def test_a_script_with_old_names_runs_like_the_current_names(holed_sphere, tmp_path):
    old = script('<filter name="remove_duplicate_vertices"/>',
                 '<filter name="close_holes"><Param type="RichInt" name="MaxHoleSize" value="100"/></filter>',
                 '<filter name="Re-Orient all faces coherentely"/>',
                 '<filter name="laplacian_smooth"><Param type="RichInt" name="stepSmoothNum" value="2"/></filter>')
    ms = load(holed_sphere)
    assert [r.get("closed_holes") for r in run_filter_script(ms, old)] == [None, 2, None, None]
    current = (old.replace("remove_duplicate_vertices", "Remove Duplicate Vertices")
               .replace('"close_holes"', '"Close Holes"').replace("laplacian_smooth", "Laplacian Smooth")
               .replace("coherentely", "coherently"))
    assert_same_meshes(ms, pymeshlab_run(current, holed_sphere, tmp_path))


# --- parameter types ------------------------------------------------------------------------

EVERY_TYPE = script(
    '<filter name="Close Holes"><Param type="RichInt" name="MaxHoleSize" value="7"/>'
    '<Param type="RichBool" name="RefineHole" value="TRUE"/>'
    '<Param type="RichAbsPerc" name="RefineHoleEdgeLen" value="0.25" min="0" max="3"/></filter>',
    '<filter name="Close Holes"><Param type="RichPercentage" name="RefineHoleEdgeLen" value="0.5"/></filter>',
    '<filter name="Taubin Smooth"><Param type="RichFloat" name="lambda" value="0.4"/></filter>',
    '<filter name="Transform: Translate, Center, set Origin">'
    '<Param type="RichEnum" name="traslMethod" value="3" enum_cardinality="4"/>'
    '<Param type="RichDynamicFloat" name="axisX" value="1.5" min="-10" max="10"/>'
    '<Param type="RichPosition" name="newOrigin" x="0.1" y="0.2" z="0.3"/></filter>',
    '<filter name="Transform: Rotate"><Param type="RichDirection" name="customAxis" x="0" y="0.6" z="0.8"/></filter>',
    '<filter name="Matrix: Set/Copy Transformation"><Param type="RichMatrix44f" name="TransformMatrix" '
    + " ".join(f'val{i}="{i + 1}"' for i in range(16)) + "/></filter>",
    '<filter name="Conditional Face Selection"><Param type="RichString" name="condSelect" value="fi &lt; 5"/></filter>',
    '<filter name="Vertex Color Filling">'
    '<Param type="RichColor" name="color1" r="200" g="10" b="20" a="128"/></filter>',
    '<filter name="Hausdorff Distance"><Param type="RichMesh" name="SampledMesh" value="1"/></filter>',
    f'<filter name="{OURS}"><Param type="RichInt" name="MaxHoleSize" value="50"/>'
    '<Param type="RichBool" name="SelfIntersection" value="false"/><Param type="RichFloat" name="alpha" value="1.25"/>'
    '<Param type="RichEnum" name="fairing" value="1" enum_cardinality="3"/></filter>',
    f'<filter name="{OURS}"><Param type="RichString" name="fairing" value="thinplate"/></filter>',
)


def test_every_meshlab_parameter_type_is_converted():
    steps = read_filter_script(EVERY_TYPE).steps
    kw = [s.kwargs for s in steps]
    assert kw[0]["maxholesize"] == 7 and kw[0]["refinehole"] is True
    assert isinstance(kw[0]["refineholeedgelen"], pymeshlab.PureValue) and kw[0]["refineholeedgelen"].value() == 0.25
    assert kw[1]["refineholeedgelen"].value() == 0.5  # RichPercentage: an absolute value too
    assert kw[2] == {"lambda_": 0.4}
    assert kw[3]["traslmethod"] == 3 and kw[3]["axisx"] == 1.5
    np.testing.assert_array_equal(kw[3]["neworigin"], [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(kw[4]["customaxis"], [0, 0.6, 0.8])
    np.testing.assert_array_equal(kw[5]["transformmatrix"], np.arange(1, 17).reshape(4, 4))  # row-major
    assert kw[6] == {"condselect": "fi < 5"}
    color = kw[7]["color1"]
    assert (color.red(), color.green(), color.blue(), color.alpha()) == (200, 10, 20, 128)
    assert kw[8] == {"sampledmesh": 1}
    assert kw[9] == {"maxholesize": 50, "selfintersection": False, "alpha": 1.25, "fairing": "membrane"}
    assert kw[10] == {"fairing": "thinplate"}
    assert [s.ours for s in steps] == [False] * 9 + [True] * 2


def test_meshlab_2016_xmlfilter_elements_are_read_with_the_parameter_types():
    text = script('<xmlfilter name="Conditional Face Selection"><xmlparam name="condSelect" value="fi &lt; 5"/>'
                  '</xmlfilter>',
                  '<xmlfilter name="Close Holes"><xmlparam name="MaxHoleSize" value="30"/>'
                  '<xmlparam name="Selected" value="false"/></xmlfilter>',
                  f'<xmlfilter name="{OURS}"><xmlparam name="fairing" value="membrane"/>'
                  '<xmlparam name="alpha" value="2"/></xmlfilter>')
    assert [s.kwargs for s in read_filter_script(text).steps] == [
        {"condselect": "fi < 5"}, {"maxholesize": 30, "selected": False}, {"fairing": "membrane", "alpha": 2.0}]


def test_builtin_only_script_matches_pymeshlab_apply_filter_script(holed_sphere, tmp_path):
    # The script is written by pymeshlab itself: MeshLab's format, every type pymeshlab can run.
    ms = load(holed_sphere)
    ms.meshing_remove_duplicate_vertices()
    ms.meshing_close_holes(maxholesize=30, refinehole=True, refineholeedgelen=pymeshlab.PureValue(0.05))
    ms.apply_coord_taubin_smoothing(lambda_=0.4, mu=-0.45, stepsmoothnum=3)
    ms.compute_matrix_from_translation(traslmethod="Set new Origin", neworigin=np.array([0.1, 0.2, 0.3]))
    ms.compute_matrix_from_translation(axisx=0.25)
    ms.compute_matrix_from_rotation(rotaxis="custom axis", customaxis=np.array([0, 0.6, 0.8]), angle=17.0)
    M = np.eye(4)
    M[0, 3], M[1, 0] = 0.5, 0.25
    ms.set_matrix(transformmatrix=M)
    ms.compute_selection_by_condition_per_face(condselect="fi < 50")
    ms.compute_selection_transfer_face_to_vertex()
    ms.set_color_per_vertex(color1=pymeshlab.Color(200, 10, 20, 255), onselected=True)
    ms.generate_copy_of_current_mesh()
    ms.apply_coord_laplacian_smoothing(stepsmoothnum=1)
    ms.get_hausdorff_distance(sampledmesh=1, targetmesh=0)
    path = str(tmp_path / "builtin.mlx")
    ms.save_filter_script(path)
    types = {p.get("type") for p in ET.parse(path).getroot().iter("Param")}
    assert {"RichInt", "RichFloat", "RichBool", "RichString", "RichAbsPerc", "RichDynamicFloat", "RichEnum",
            "RichColor", "RichPosition", "RichDirection", "RichMatrix44f", "RichMesh"} <= types

    ours = load(holed_sphere)
    results = run_filter_script(ours, path)
    assert len(results) == 13 and results[1]["closed_holes"] == 2
    assert ours.mesh_number() == 2
    assert_same_meshes(ours, pymeshlab_run(path, holed_sphere, tmp_path))


def test_pymeshlab_sample_filter_script_runs(holed_sphere, tmp_path):
    path = sample("sample_filter_script.mlx")
    ms = load(holed_sphere)
    results = run_filter_script(ms, path)
    assert len(results) == 3 and ms.mesh_number() == 2  # Box/Cube adds a layer, then two subdivisions
    assert_same_meshes(ms, pymeshlab_run(path, holed_sphere, tmp_path))


# --- validation -----------------------------------------------------------------------------

ERROR_CASES = {
    "unknown filter": (script(LAPLACIAN, '<filter name="Close Holez"/>'), 4, "Close Holez", None,
                       "unknown filter.*did you mean 'Close Holes'"),
    "unknown parameter": (script(LAPLACIAN, '<filter name="Close Holes">\n<Param type="RichInt" name="MaxHoleSise" '
                                            'value="3"/></filter>'), 5, "Close Holes", "MaxHoleSise",
                          "unknown parameter.*maxholesize"),
    "unparsable int": (script(LAPLACIAN, '<filter name="Close Holes"><Param type="RichInt" name="MaxHoleSize" '
                                         'value="abc"/></filter>'), 4, "Close Holes", "MaxHoleSize", "not an integer"),
    "unparsable bool": (script(LAPLACIAN, '<filter name="Close Holes"><Param type="RichBool" name="Selected" '
                                          'value="yes"/></filter>'), 4, "Close Holes", "Selected", "'true' or 'false'"),
    "non-finite float": (script(LAPLACIAN, '<filter name="Taubin Smooth"><Param type="RichFloat" name="lambda" '
                                           'value="nan"/></filter>'), 4, "Taubin Smooth", "lambda", "not finite"),
    "incomplete colour": (script(LAPLACIAN, '<filter name="Vertex Color Filling"><Param type="RichColor" '
                                            'name="color1" r="1" b="2"/></filter>'), 4, "Vertex Color Filling",
                          "color1", "no 'g' attribute"),
    "incomplete matrix": (script(LAPLACIAN, '<filter name="Matrix: Set/Copy Transformation"><Param '
                                            'type="RichMatrix44f" name="TransformMatrix" val0="1"/></filter>'), 4,
                          "Matrix: Set/Copy Transformation", "TransformMatrix", "no 'val1' attribute"),
    "enum out of range": (script(LAPLACIAN, '<filter name="Transform: Translate, Center, set Origin"><Param '
                                            'type="RichEnum" name="traslMethod" value="4" enum_cardinality="4"/>'
                                            '</filter>'), 4, "Transform: Translate, Center, set Origin",
                          "traslMethod", r"not in \[0, 4\)"),
    "wrong type": (script(LAPLACIAN, '<filter name="Close Holes"><Param type="RichBool" name="MaxHoleSize" '
                                     'value="true"/></filter>'), 4, "Close Holes", "MaxHoleSize", "does not fit"),
    "ours below minimum": (script(LAPLACIAN, f'<filter name="{OURS}"><Param type="RichInt" name="MaxHoleSize" '
                                             'value="2"/></filter>'), 4, OURS, "MaxHoleSize", "below the minimum 3"),
    "ours bad choice": (script(LAPLACIAN, f'<filter name="{OURS}"><Param type="RichString" name="fairing" '
                                          'value="biharmonic"/></filter>'), 4, OURS, "fairing", "expected one of"),
    "missing input file": (script(LAPLACIAN, '<filter name="Set Texture"><Param type="RichOpenFile" name="textName" '
                                             'value="no_such_texture.png"/></filter>'), 4, "Set Texture", "textName",
                           "file not found"),
    "untyped Param": (script(LAPLACIAN, '<filter name="Close Holes"><Param name="MaxHoleSize" value="3"/></filter>'),
                      4, "Close Holes", "MaxHoleSize", "without a type"),
    "parameter twice": (script(LAPLACIAN, '<filter name="Close Holes"><Param type="RichInt" name="MaxHoleSize" '
                                          'value="3"/>\n<Param type="RichInt" name="maxholesize" value="4"/></filter>'),
                        5, "Close Holes", "maxholesize", "given twice"),
    "malformed XML": (script(LAPLACIAN, '<filter name="Close Holes">'), 5, None, None, "malformed XML"),
    "not a filter script": ("<Project>\n<MeshGroup/>\n</Project>", 1, None, None, "root element is <Project>"),
}


@pytest.mark.parametrize("case", list(ERROR_CASES))
def test_invalid_scripts_give_one_clear_error_and_leave_the_meshset_untouched(case, holed_sphere):
    text, line, filter_name, parameter, message = ERROR_CASES[case]
    ms = load(holed_sphere)
    before = meshes(ms)
    with pytest.raises(MlxScriptError) as info:
        run_filter_script(ms, text)
    assert len(info.value.problems) == 1
    problem = info.value.problems[0]
    assert (problem.line, problem.filter, problem.parameter) == (line, filter_name, parameter)
    assert re.search(message, str(info.value)), str(info.value)
    assert f"<string>:{line}" in str(info.value)
    after = meshes(ms)
    assert after.keys() == before.keys()
    for i in before:  # the Laplacian Smooth before the bad filter did not run
        np.testing.assert_array_equal(after[i][0], before[i][0])
    assert registry.filter_history(ms) == []


def test_all_problems_are_reported_together_and_a_missing_script_is_named(tmp_path):
    text = script('<filter name="Close Holez"/>',
                  '<filter name="Close Holes"><Param type="RichInt" name="MaxHoleSize" value="x"/></filter>')
    with pytest.raises(MlxScriptError) as info:
        read_filter_script(text)
    assert [p.line for p in info.value.problems] == [3, 4]
    missing = str(tmp_path / "nowhere.mlx")
    with pytest.raises(MlxScriptError, match="nowhere.mlx: filter script file not found"):
        read_filter_script(missing)


def test_pymeshlab_itself_runs_half_a_script_before_failing(holed_sphere, tmp_path):
    """The behaviour the validation prevents: pymeshlab changes the mesh, then fails."""
    text = script(LAPLACIAN, '<filter name="Close Holez"/>')
    ms = load(holed_sphere)
    V0 = ms.current_mesh().vertex_matrix()
    path = tmp_path / "half.mlx"
    path.write_text(text)
    ms.load_filter_script(str(path))
    with pytest.raises(pymeshlab.PyMeshLabException, match="Something really bad happened"):
        ms.apply_filter_script()
    assert not np.array_equal(ms.current_mesh().vertex_matrix(), V0)


def test_a_runtime_failure_names_the_step_and_keeps_earlier_results(holed_sphere):
    text = script(LAPLACIAN, '<filter name="Hausdorff Distance"><Param type="RichMesh" name="SampledMesh" '
                             'value="7"/></filter>')
    ms = load(holed_sphere)
    with pytest.raises(MlxRunError, match=r"<string>:4: filter #2 'Hausdorff Distance'.*no mesh with id 7") as info:
        run_filter_script(ms, text)
    assert info.value.results == [{}] and info.value.step.index == 2


# --- our filters inside workflows ------------------------------------------------------------

ALGORITHM_WORKFLOWS = {
    "close_holes_min_angle_bilateral.mlx": "meshing_close_holes_min_angle_bilateral",
    "close_holes_curve_unfolding.mlx": "meshing_close_holes_curve_unfolding",
    "close_holes_lssvm_poisson.mlx": "meshing_close_holes_lssvm_poisson",
    "close_holes_differential_evolution.mlx": "meshing_close_holes_differential_evolution",
}


def assert_all_five_closed(result, who):
    """The bunny scan's five natural holes are all closed (the project's target for every filter)."""
    reasons = [h.get("reason") for h in result["holes"] if h["status"] != "closed"]
    assert result["closed_holes"] == 5 and not reasons, f"{who} did not close every hole: {reasons}"


def require_filter(python_name):
    if python_name not in meshlab_holefill.filter_list():
        pytest.skip(f"{python_name} is not registered yet (add it to meshlab_holefill.algorithms.ALGORITHMS)")


# Presets: an algorithm's workflow with some of its options (beyond the paper) switched on.
PRESET_WORKFLOWS = {
    "close_holes_min_angle_bilateral_faired.mlx": ("meshing_close_holes_min_angle_bilateral",
                                                   {"iterations": 0, "fairing": "thinplate", "smoothing": 10}),
    "close_holes_curve_unfolding_developed.mlx": ("meshing_close_holes_curve_unfolding", {"domain": "development"}),
    "close_holes_differential_evolution_smoothest.mlx": ("meshing_close_holes_differential_evolution",
                                                         {"layouts": "smoothest"}),
}


def test_every_workflow_is_documented_and_every_filter_has_one():
    files = sorted(f for f in os.listdir(WORKFLOWS) if f.endswith(".mlx"))
    assert (set(ALGORITHM_WORKFLOWS) | set(PRESET_WORKFLOWS)
            | {"scan_repair.mlx", "meshlab_close_holes.mlx", "meshlab_close_holes_2020.09.mlx"}
            == set(files))
    for name in files:
        with open(os.path.join(WORKFLOWS, name)) as f:
            text = f.read()
        comment = re.search(r"<!--(.*?)-->", text, re.S)
        assert comment and name in comment.group(1) and "meshlab-holefill run" in comment.group(1)
    by_python_name = {python_name: workflow for workflow, python_name in ALGORITHM_WORKFLOWS.items()}
    for row in ALGORITHMS:  # a registered filter's workflow names it by its display name
        assert row.filter_name in by_python_name
        step = read_filter_script(os.path.join(WORKFLOWS, by_python_name[row.filter_name])).steps[-1]
        assert (step.mlx_name, step.filter) == (row.display_name, row.filter_name)


@pytest.mark.parametrize("workflow", list(ALGORITHM_WORKFLOWS) + list(PRESET_WORKFLOWS))
def test_algorithm_workflow_cleans_closes_every_hole_and_selects_the_new_faces(workflow):
    python_name = ALGORITHM_WORKFLOWS.get(workflow) or PRESET_WORKFLOWS[workflow][0]
    require_filter(python_name)
    path = os.path.join(WORKFLOWS, workflow)
    steps = read_filter_script(path).steps
    assert steps[-1].filter == python_name and steps[-1].ours
    ms = load(BUNNY)
    results = run_filter_script(ms, path)
    assert len(results) == len(steps)
    closing = results[-1]
    assert_all_five_closed(closing, python_name)
    V, F = mesh_arrays(ms)
    assert boundary_loops(F) == []
    assert ms.current_mesh().selected_face_number() == closing["new_faces"]
    cleaned = load(BUNNY)
    run_filter_script(cleaned, without_last_filters(path, 1))
    V0, F0 = mesh_arrays(cleaned)  # the clean mesh is kept bit-exact, new vertices and faces come after
    np.testing.assert_array_equal(V[:len(V0)], V0)
    # Xu et al.'s boundary pre-treatment (Sec. 3.1) may split border faces: each split rewrites
    # one original row in place and appends its other half before the patch.
    split = closing.get("split_boundary_edges", 0)
    changed = np.flatnonzero(np.any(F[:len(F0)] != F0, axis=1))
    assert len(changed) <= split
    assert len(F) - len(F0) == closing["new_faces"] + split


def test_preset_workflow_is_the_filter_with_its_options():
    """The preset runs the same filter call as the Python options it names, to the same mesh."""
    for workflow, (python_name, options) in PRESET_WORKFLOWS.items():
        path = os.path.join(WORKFLOWS, workflow)
        step = read_filter_script(path).steps[-1]
        assert step.filter == python_name
        assert {name: step.kwargs[name] for name in options} == options
        scripted = load(BUNNY)
        run_filter_script(scripted, path)
        direct = load(BUNNY)
        run_filter_script(direct, without_last_filters(path, 1))
        getattr(direct, python_name)(maxholesize=1000, **options)
        for a, b in zip(mesh_arrays(scripted), mesh_arrays(direct)):
            np.testing.assert_array_equal(a, b)


def check_scan_repair(text_or_path, base_path):
    ms = load(BUNNY)
    results = run_filter_script(ms, text_or_path)
    closing = results[-2]
    assert_all_five_closed(closing, "the scan-repair chain's hole filler")
    V, F = mesh_arrays(ms)
    assert boundary_loops(F) == []
    unsmoothed = load(BUNNY)
    run_filter_script(unsmoothed, without_last_filters(base_path, 1))
    V1, F1 = mesh_arrays(unsmoothed)
    np.testing.assert_array_equal(F, F1)
    n = len(V) - closing["new_vertices"]
    np.testing.assert_array_equal(V[:n], V1[:n])  # the scan and the hole borders did not move
    assert np.abs(V[n:] - V1[n:]).max() > 0  # the new vertices were smoothed


def test_scan_repair_workflow():
    require_filter("meshing_close_holes_differential_evolution")
    path = os.path.join(WORKFLOWS, "scan_repair.mlx")
    check_scan_repair(path, path)


def test_scan_repair_chain_smooths_only_the_new_faces(tmp_path):
    """The same chain with the filter that exists today in place of HPDE."""
    with open(os.path.join(WORKFLOWS, "scan_repair.mlx")) as f:
        text = f.read().replace("Close Holes: Differential Evolution (HPDE)", OURS)
    path = tmp_path / "scan_repair_min_angle.mlx"
    path.write_text(text)
    check_scan_repair(str(path), str(path))


def test_meshlab_baseline_workflow_matches_pymeshlab(tmp_path):
    path = os.path.join(WORKFLOWS, "meshlab_close_holes.mlx")
    ms = load(BUNNY)
    results = run_filter_script(ms, path)
    assert results[-1]["closed_holes"] == 5
    assert boundary_loops(mesh_arrays(ms)[1]) == []
    assert_same_meshes(ms, pymeshlab_run(path, BUNNY, tmp_path))


# --- recording ------------------------------------------------------------------------------


def test_record_write_run_gives_the_same_mesh(tmp_path):
    ms = load(BUNNY)
    meshlab_holefill.apply_filter(ms, "meshing_remove_duplicate_vertices")
    meshlab_holefill.apply_filter(ms, "meshing_merge_close_vertices")  # default: a mesh-dependent length
    meshlab_holefill.apply_filter(ms, "compute_matrix_from_translation", axisx=0.1234567891234)
    ms.meshing_close_holes_min_angle_bilateral(maxholesize=100, alpha=1.3, fairing="membrane")
    meshlab_holefill.apply_filter(ms, "apply_coord_taubin_smoothing", lambda_=0.41234567, selected=True)
    first = str(tmp_path / "recorded.mlx")
    meshlab_holefill.save_filter_script(ms, first)

    params = {p.get("name"): p for p in ET.parse(first).getroot().findall("filter")[3]}
    assert ET.parse(first).getroot().findall("filter")[3].get("name") == OURS
    assert {name: p.get("type") for name, p in params.items()} == {
        "MaxHoleSize": "RichInt", "MaxHoleDiameter": "RichAbsPerc", "Selected": "RichBool",
        "NewFaceSelected": "RichBool", "SelfIntersection": "RichBool", "FillOutlines": "RichBool", "Workers": "RichInt",
        "TimeLimit": "RichFloat", "alpha": "RichFloat", "sigma_c": "RichFloat", "sigma_s": "RichFloat",
        "iterations": "RichInt", "fairing": "RichEnum", "smoothing": "RichInt", "relaxation": "RichEnum",
        "neighbourhood": "RichEnum", "fallback": "RichBool", "filter_guard": "RichFloat"}
    assert params["alpha"].get("value") == "1.3"
    assert (params["fairing"].get("value"), params["fairing"].get("enum_cardinality")) == ("1", "3")
    pymeshlab.MeshSet().load_filter_script(first)  # MeshLab's reader accepts it

    replay = load(BUNNY)
    results = run_filter_script(replay, first)
    assert results[3]["closed_holes"] == 5
    assert_same_meshes(replay, ms)
    second = meshlab_holefill.filter_script_xml(replay)
    with open(first) as f:
        assert second == f.read()  # the replay records the same script


def test_history_dies_with_its_meshset_and_direct_builtin_calls_are_not_recorded():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=1)
    ms.meshing_remove_duplicate_vertices()  # pymeshlab's own method: not through our API
    assert registry.filter_history(ms) == []
    meshlab_holefill.apply_filter(ms, "meshing_remove_duplicate_vertices")
    assert registry.filter_history(ms) == [("meshing_remove_duplicate_vertices", {})]
    gc.collect()
    alive = len(registry._HISTORY)
    ref = weakref.ref(ms)
    del ms
    gc.collect()
    assert ref() is None and len(registry._HISTORY) == alive - 1


def test_builtins_applied_inside_our_filter_are_not_steps_of_the_script():
    def run(ms, **params):
        registry.apply_filter(ms, "meshing_remove_duplicate_vertices")
        return {"inner": 1}

    spec = registry.FilterSpec("test_mlx_nested_filter", "Test: nested", "test only", [], run)
    registry.register(spec)
    try:
        ms = pymeshlab.MeshSet()
        ms.create_sphere(subdiv=1)
        ms.test_mlx_nested_filter()
        assert registry.filter_history(ms) == [("test_mlx_nested_filter", {})]
    finally:
        registry.FILTERS.pop("test_mlx_nested_filter")
        delattr(pymeshlab.MeshSet, "test_mlx_nested_filter")


# --- command line ---------------------------------------------------------------------------


def test_cli_run_check_record_and_error(tmp_path, capsys):
    path = os.path.join(WORKFLOWS, "close_holes_min_angle_bilateral.mlx")
    out, record = str(tmp_path / "out.ply"), str(tmp_path / "record.mlx")
    assert main(["run", path, BUNNY, out, "--record", record]) == 0
    assert "closed_holes=5" in capsys.readouterr().out
    assert boundary_loops(mesh_arrays(load(out))[1]) == []
    assert len(read_filter_script(record).steps) == 7
    assert main(["run", path, "--check"]) == 0
    assert "7 filter(s), no problems" in capsys.readouterr().out
    bad = tmp_path / "bad.mlx"
    bad.write_text(script(LAPLACIAN, '<filter name="Close Holez"/>'))
    assert main(["run", str(bad), BUNNY, out]) == 2
    assert f"{bad}:4: filter 'Close Holez': unknown filter" in capsys.readouterr().err


def test_pymeshlab_load_and_apply_filter_script_run_our_filters(tmp_path):
    """pymeshlab's own script door: load_filter_script + apply_filter_script, our filter among MeshLab's."""
    direct = pymeshlab.MeshSet()
    direct.load_new_mesh(sample("bunny10k_textured.obj"))
    faired = os.path.join(WORKFLOWS, "close_holes_min_angle_bilateral_faired.mlx")
    run_filter_script(direct, faired)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    ms.load_filter_script(faired)
    ms.apply_filter_script()
    assert np.array_equal(ms.current_mesh().face_matrix(), direct.current_mesh().face_matrix())
    assert np.array_equal(ms.current_mesh().vertex_matrix(), direct.current_mesh().vertex_matrix())
    assert len(boundary_loops(ms.current_mesh().face_matrix())) == 0
    # an invalid script naming our filter is refused when loaded, naming the problem
    bad = tmp_path / "bad.mlx"
    bad.write_text(open(faired).read().replace('name="smoothing"', 'name="smoothness"'))
    with pytest.raises(MlxScriptError, match="smoothness"):
        ms.load_filter_script(str(bad))
    # scripts of MeshLab's filters only are pymeshlab's business, as before
    ms.clear_filter_script()
    ms.load_filter_script(os.path.join(WORKFLOWS, "meshlab_close_holes.mlx"))
    ms.apply_filter_script()
