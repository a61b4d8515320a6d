"""MeshLab .mlx filter scripts that mix MeshLab's built-in filters with this package's.

pymeshlab's ``load_filter_script`` / ``apply_filter_script`` run in C++: they cannot reach a
Python filter, and a filter name they do not know fails only when it is reached, after the
filters before it have changed the meshes. This module reads the same XML, checks all of it
first, and runs each step through :func:`meshlab_holefill.apply_filter`, the door that knows
both kinds of filter (:mod:`.pymeshlab_doors` sends pymeshlab's two calls here for scripts
that name our filters).

Reading (:func:`read_filter_script`, :func:`run_filter_script`)
    ``<filter name="...">`` names a filter by its MeshLab display name ("Close Holes",
    "Close Holes: Minimum Angle + Bilateral"), or by a python name, or by a pre-2022 display
    or python name (pymeshlab's ``keys.txt``); see :func:`mlx_names.resolve_filter`.
    ``<Param name="..." type="..." .../>`` is translated by MeshLab's rule
    (:func:`mlx_names.python_param_name`) for built-ins, and by ``ParamSpec.mlx`` for ours.
    Values by type: RichInt, RichFloat, RichBool ("true"/"false"), RichString, RichAbsPerc
    and RichPercentage (absolute values, passed as ``pymeshlab.PureValue``), RichDynamicFloat,
    RichEnum (the index), RichColor (r, g, b, a), RichPosition / RichDirection / RichPoint3f
    (x, y, z), RichMatrix44f (val0..val15, row-major), RichMesh (a mesh id of the MeshSet),
    RichOpenFile / RichSaveFile (a path; relative paths are looked up in the working directory,
    then next to the script). MeshLab 2016's ``<xmlfilter>``/``<xmlparam>`` (untyped values)
    are read too. Parameters a script leaves out take the filter's defaults.

Validation
    Everything is checked before the first filter runs: XML well-formed, every filter known,
    every parameter known to its filter, every value parsable and of a type the parameter
    accepts, our filters' ranges and choices, input files present. All problems are reported
    together in one :class:`MlxScriptError`, each naming the line, the filter and the
    parameter; the MeshSet is untouched. What only the run can reveal (a filter's own
    precondition, e.g. "needs a raster", a bounded float out of its mesh-dependent bounds)
    raises :class:`MlxRunError`, naming the step, after the earlier steps ran.

Recording (:func:`save_filter_script`, :func:`filter_script_xml`)
    Writing the filters applied to a MeshSet back as a script lives in :mod:`mlx_write`;
    both functions are imported here so that ``meshlab_holefill.meshlab.mlx.script`` stays the one module
    for .mlx scripts.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from . import names as mlx_names
from . import versions as mlx_versions
from .. import registration as registry
from .values import ParamValueError, builtin_param_value, our_param_value
from ..meshset_io import current_mesh_exists
from .parse import MlxRunError, MlxScriptError, ScriptProblem, parse_xml
from .write import filter_script_xml, save_filter_script

__all__ = [
    "FilterScript", "MlxRunError", "MlxScriptError", "ScriptParam", "ScriptProblem", "ScriptStep",
    "filter_script_xml", "read_filter_script", "run_filter_script",
    "save_filter_script",
]


@dataclass
class ScriptParam:
    mlx_name: str
    mlx_type: str | None
    line: int
    name: str          # python keyword
    value: Any         # ready to pass to apply_filter


@dataclass
class ScriptStep:
    """One validated filter of a script.

    Attributes
    ----------
    index : int
        1-based position in the script.
    line : int
    mlx_name : str
        The filter name as written.
    filter : str
        Python filter name.
    ours : bool
    how : str
        How the name was understood ('display name', 'old python name', ...).
    params : list of ScriptParam
    """

    index: int
    line: int
    mlx_name: str
    filter: str
    ours: bool
    how: str
    params: list

    @property
    def kwargs(self):
        return {p.name: p.value for p in self.params}


@dataclass
class FilterScript:
    """A parsed and validated filter script: run it with :func:`run_filter_script`."""

    steps: list
    source: str = "<string>"


# --- reading ------------------------------------------------------------------------------


def _validate(root, source, base_dir):
    """Every ``<filter>`` of the script resolved and its values checked, or MlxScriptError listing every problem."""
    steps, problems, index = [], [], 0
    for element in root.children:
        if element.tag not in ("filter", "xmlfilter"):
            problems.append(ScriptProblem(source, element.line, None, None,
                                          f"unexpected element <{element.tag}> (expected <filter>)"))
            continue
        index += 1
        step = _read_step(element, index, source, base_dir, problems)
        if step is not None:
            steps.append(step)
    if problems:
        lines = "\n  ".join(map(str, problems))
        raise MlxScriptError(f"{len(problems)} problem(s) in filter script {source}; nothing was run:\n  {lines}",
                             problems)
    return FilterScript(steps, source)


def _resolve_filter(element, source, problems):
    """The filter a ``<filter name=...>`` names (mlx_names.resolve_filter), or None with the problem recorded."""
    name = element.name
    if not name:
        problems.append(ScriptProblem(source, element.line, None, None, "<filter> without a name attribute"))
        return None
    understood = mlx_names.resolve_filter(name)
    removed = mlx_versions.filter_2020(name) if understood is None else None
    if removed is not None:
        problems.append(ScriptProblem(source, element.line, name, None,
                                      f"a MeshLab 2020.09 filter that current MeshLab does not have: {removed.note}"))
        return None
    if understood is None:
        hint = mlx_names.suggest_filters(name)
        problems.append(ScriptProblem(
            source, element.line, name, None,
            "unknown filter: neither one of meshlab_holefill's "
            f"({', '.join(s.display_name for s in registry.FILTERS.values())}) nor a pymeshlab built-in"
            + (f"; did you mean {' or '.join(map(repr, hint))}?" if hint else "")))
    return understood


def _read_step(element, index, source, base_dir, problems):
    """One ``<filter>`` element as a ScriptStep, or None; every problem found is appended to ``problems``."""
    understood = _resolve_filter(element, source, problems)
    if understood is None:
        return None
    name = element.name
    spec = registry.FILTERS.get(understood.python_name) if understood.ours else None
    kinds = None if understood.ours else mlx_names.builtin_param_kinds(understood.python_name)
    params, seen = [], {}
    for child in element.children:
        param = _read_param(child, understood, spec, kinds, name, source, base_dir, problems)
        if param is None:
            continue
        if param.name in seen:
            problems.append(ScriptProblem(source, child.line, name, param.mlx_name,
                                          f"given twice (first on line {seen[param.name]})"))
            continue
        seen[param.name] = child.line
        params.append(param)
    problems.extend(_add_implied_params(understood, params, seen, source, element.line, name))
    return ScriptStep(index, element.line, name, understood.python_name, understood.ours, understood.how, params)


def _read_param(child, understood, spec, kinds, name, source, base_dir, problems):
    """One ``<Param>`` element as a ScriptParam with its Python name and value, or None (a problem, or a
    MeshLab 2020.09 parameter that current MeshLab dropped)."""
    param_name = child.name
    if child.tag not in ("Param", "xmlparam"):
        problems.append(ScriptProblem(source, child.line, name, None,
                                      f"unexpected element <{child.tag}> (expected <Param>)"))
        return None
    if not param_name:
        problems.append(ScriptProblem(source, child.line, name, None, "<Param> without a name attribute"))
        return None
    mlx_type = child.attrs.get("type") if child.tag == "Param" else None
    if child.tag == "Param" and not mlx_type:
        problems.append(ScriptProblem(source, child.line, name, param_name, "<Param> without a type attribute"))
        return None
    try:
        if understood.ours:
            python_name, value = our_param_value(spec, child, param_name, mlx_type, base_dir)
        elif _dropped_2020_param(understood, kinds, child):
            return None
        else:
            python_name, value = builtin_param_value(kinds, child, _param_name_2020(understood, param_name),
                                                     mlx_type, base_dir)
    except ParamValueError as exc:
        problems.append(ScriptProblem(source, child.line, name, param_name, str(exc)))
        return None
    return ScriptParam(param_name, mlx_type, child.line, python_name, value)


def _param_name_2020(understood, param_name):
    """The name to look a parameter up by: a renamed MeshLab 2020.09 parameter gets its current name."""
    f2020 = understood.meshlab_2020
    return f2020.renamed.get(param_name, param_name) if f2020 is not None else param_name


def _dropped_2020_param(understood, kinds, element):
    """Is this a MeshLab 2020.09 parameter that current MeshLab dropped, given at its default?

    Raises ParamValueError when it is one with another value.
    """
    f2020 = understood.meshlab_2020
    if f2020 is None or kinds is None or f2020.python_param(element.name) in kinds:
        return False
    problem = mlx_versions.dropped_param_problem(f2020, element.name, element.attrs)
    if problem:
        raise ParamValueError(problem)
    return problem == ""


def _add_implied_params(understood, params, seen, source, line, name):
    """Add the parameter values a MeshLab 2020.09 filter name implies; problems if the script contradicts them."""
    f2020 = understood.meshlab_2020
    if f2020 is None or understood.how != "MeshLab 2020.09 name":
        return []
    problems = []
    for python_name, value in f2020.implied.items():
        if python_name in seen:
            problems.append(ScriptProblem(source, seen[python_name], name, python_name,
                                          f"set by the MeshLab 2020.09 filter name itself ({python_name}={value!r})"))
            continue
        params.append(ScriptParam(python_name, None, line, python_name, value))
    return problems


def read_filter_script(path_or_xml):
    """Read and validate a MeshLab filter script.

    Parameters
    ----------
    path_or_xml : str, os.PathLike, bytes or FilterScript
        A path to an .mlx file, or the XML text itself (a string starting with '<').

    Returns
    -------
    FilterScript

    Raises
    ------
    MlxScriptError
        Missing file, malformed XML, unknown filter or parameter, unparsable value, missing
        input file: all problems, each with its line, filter and parameter.
    """
    if isinstance(path_or_xml, FilterScript):
        return path_or_xml
    if isinstance(path_or_xml, bytes) or (isinstance(path_or_xml, str) and path_or_xml.lstrip().startswith("<")):
        data, source, base_dir = path_or_xml, "<string>", None
    else:
        path = os.fspath(path_or_xml)
        if not os.path.isfile(path):
            problem = ScriptProblem(path, None, None, None, "filter script file not found")
            raise MlxScriptError(str(problem), [problem])
        with open(path, "rb") as f:
            data = f.read()
        source, base_dir = path, os.path.dirname(os.path.abspath(path))
    return _validate(parse_xml(data, source), source, base_dir)


def run_filter_script(ms, path_or_xml):
    """Run a MeshLab filter script (built-in filters and ours) on a MeshSet.

    The whole script is validated first (:func:`read_filter_script`); then each filter runs
    through :func:`meshlab_holefill.apply_filter`, so it is recorded like any other call.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    path_or_xml : str, os.PathLike, bytes or FilterScript

    Returns
    -------
    list of dict
        One result dictionary per filter ({} for built-ins that return nothing).

    Raises
    ------
    MlxScriptError
        The script is invalid; the MeshSet is untouched.
    MlxRunError
        A filter failed while running; the filters before it were applied (``.results``).
    """
    script = read_filter_script(path_or_xml)
    results = []
    for step in script.steps:
        where = f"{script.source}:{step.line}: filter #{step.index} '{step.mlx_name}' ({step.filter})"
        done = f"; {len(results)} earlier filter(s) of the script were applied" if results else ""
        problem = _runtime_problem(ms, step)
        if problem:
            raise MlxRunError(f"{where}: {problem}{done}", step, results)
        try:
            results.append(registry.apply_filter(ms, step.filter, **step.kwargs))
        except Exception as exc:
            raise MlxRunError(f"{where} failed: {exc}{done}", step, results) from exc
    return results


def _runtime_problem(ms, step):
    """What would crash pymeshlab instead of raising (DESIGN.md: missing current mesh id)."""
    if ms.mesh_number() > 0 and not current_mesh_exists(ms):
        return "the MeshSet's current mesh does not exist"
    for p in step.params:
        if p.mlx_type == "RichMesh" and not ms.mesh_id_exists(p.value):
            return f"parameter '{p.mlx_name}': no mesh with id {p.value} in the MeshSet"
    return None
