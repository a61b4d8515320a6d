"""MeshLab .mlx filter scripts that mix MeshLab's built-in filters with this package's.

pymeshlab's ``load_filter_script`` / ``apply_filter_script`` run in C++: they cannot reach a
Python filter, and a filter name they do not know fails only when it is reached, after the
filters before it have changed the meshes. This module reads the same XML, checks all of it
first, and runs each step through :func:`meshlab_holefill.apply_filter`, the door that knows
both kinds of filter.

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
    Every filter applied through this package's API (``apply_filter``, the ``MeshSet``
    methods of our filters, ``run_filter_script``) is recorded per MeshSet
    (:func:`meshlab_holefill.registry.filter_calls`). Built-in filters called directly as
    ``ms.<name>()`` bypass the API and are not recorded, and neither are MeshSet operations
    that are not filters (``load_new_mesh``, ``set_current_mesh``, ``add_mesh``): a filter
    script cannot express them. The written script has MeshLab's
    types for our parameters (RichInt, RichFloat, RichBool, RichEnum with its values,
    RichAbsPerc absolute with min/max, RichString) and every parameter with the value
    actually used; built-in filters are written from pymeshlab's own record of the call (all
    their parameters, MeshLab names and types), real values written at full precision (the
    arguments given, and the defaults pymeshlab computed for the mesh just before the call);
    only a ``PercentageValue`` given to a built-in keeps pymeshlab's 6-digit absolute value.
    Replaying the script on the same input gives the same mesh.
"""
from __future__ import annotations

import numbers
import os
import tempfile
from dataclasses import dataclass, field
from typing import Any
from xml.parsers import expat
from xml.sax.saxutils import escape, quoteattr

import numpy as np
import pymeshlab

from . import mlx_names, registry
from .mlx_names import POINT_TYPES, ParamValueError, builtin_param_value, our_param_value


class MlxScriptError(ValueError):
    """A filter script cannot be run; nothing was applied.

    Attributes
    ----------
    problems : list of ScriptProblem
        Every problem found, each with its line, filter and parameter.
    """

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = list(problems)


class MlxRunError(MlxScriptError):
    """A step of a validated script failed while running; the steps before it were applied.

    Attributes
    ----------
    step : ScriptStep
    results : list of dict
        Results of the steps that ran.
    """

    def __init__(self, message, step, results):
        super().__init__(message)
        self.step = step
        self.results = results


@dataclass
class ScriptProblem:
    source: str
    line: int | None
    filter: str | None
    parameter: str | None
    message: str

    def __str__(self):
        where = f"{self.source}:{self.line}" if self.line else self.source
        parts = [where]
        if self.filter is not None:
            parts.append(f"filter '{self.filter}'")
        if self.parameter is not None:
            parts.append(f"parameter '{self.parameter}'")
        return ": ".join(parts + [self.message])


@dataclass
class _Element:
    """An XML element of the script with its line number."""

    tag: str
    line: int
    attrs: dict
    children: list = field(default_factory=list)

    @property
    def name(self):
        return self.attrs.get("name")


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


def _parse_xml(data, source):
    """Parse FilterScript XML into _Element trees (root's children: filters, theirs: params)."""
    parser = expat.ParserCreate()
    stack = []
    root = []

    def start(tag, attrs):
        element = _Element(tag, parser.CurrentLineNumber, dict(attrs))
        if stack:
            stack[-1].children.append(element)
        else:
            root.append(element)
        stack.append(element)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        problem = ScriptProblem(source, exc.lineno, None, None,
                                f"malformed XML: {expat.ErrorString(exc.code)} (column {exc.offset + 1})")
        raise MlxScriptError(str(problem), [problem]) from None
    top = root[0]
    if top.tag != "FilterScript":
        problem = ScriptProblem(source, top.line, None, None,
                                f"not a MeshLab filter script: the root element is <{top.tag}>, not <FilterScript>")
        raise MlxScriptError(str(problem), [problem])
    return top


def pymeshlab_last_filter(ms, python_name):
    """pymeshlab's own record of the last filter it applied to ``ms``, if it is ``python_name``.

    pymeshlab keeps every built-in filter applied to a MeshSet, with all its parameters in
    MeshLab form; this reads the last one back through ``ms.save_filter_script``.

    Returns
    -------
    _Element or None
        The ``<filter>`` element, or None when the last record is another filter.
    """
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "record.mlx")
        ms.save_filter_script(path)
        with open(path, "rb") as f:
            data = f.read()
    filters = [e for e in _parse_xml(data, path).children if e.tag == "filter"]
    if not filters:
        return None
    understood = mlx_names.resolve_filter(filters[-1].name or "")
    if understood is None or understood.python_name != python_name:
        return None
    return filters[-1]


def _validate(root, source, base_dir):
    steps, problems, index = [], [], 0
    for element in root.children:
        if element.tag not in ("filter", "xmlfilter"):
            problems.append(ScriptProblem(source, element.line, None, None,
                                          f"unexpected element <{element.tag}> (expected <filter>)"))
            continue
        name = element.name
        index += 1
        if not name:
            problems.append(ScriptProblem(source, element.line, None, None, "<filter> without a name attribute"))
            continue
        understood = mlx_names.resolve_filter(name)
        if understood is None:
            hint = mlx_names.suggest_filters(name)
            problems.append(ScriptProblem(
                source, element.line, name, None,
                "unknown filter: neither one of meshlab_holefill's "
                f"({', '.join(s.display_name for s in registry.FILTERS.values())}) nor a pymeshlab built-in"
                + (f"; did you mean {' or '.join(map(repr, hint))}?" if hint else "")))
            continue
        spec = registry.FILTERS.get(understood.python_name) if understood.ours else None
        kinds = None if understood.ours else mlx_names.builtin_param_kinds(understood.python_name)
        params, seen = [], {}
        for child in element.children:
            param_name = child.name
            if child.tag not in ("Param", "xmlparam"):
                problems.append(ScriptProblem(source, child.line, name, None,
                                              f"unexpected element <{child.tag}> (expected <Param>)"))
                continue
            if not param_name:
                problems.append(ScriptProblem(source, child.line, name, None, "<Param> without a name attribute"))
                continue
            mlx_type = child.attrs.get("type") if child.tag == "Param" else None
            if child.tag == "Param" and not mlx_type:
                problems.append(ScriptProblem(source, child.line, name, param_name, "<Param> without a type attribute"))
                continue
            try:
                if understood.ours:
                    python_name, value = our_param_value(spec, child, param_name, mlx_type, base_dir)
                else:
                    python_name, value = builtin_param_value(kinds, child, param_name, mlx_type, base_dir)
            except ParamValueError as exc:
                problems.append(ScriptProblem(source, child.line, name, param_name, str(exc)))
                continue
            if python_name in seen:
                problems.append(ScriptProblem(source, child.line, name, param_name,
                                              f"given twice (first on line {seen[python_name]})"))
                continue
            seen[python_name] = child.line
            params.append(ScriptParam(param_name, mlx_type, child.line, python_name, value))
        steps.append(ScriptStep(index, element.line, name, understood.python_name, understood.ours,
                                understood.how, params))
    if problems:
        lines = "\n  ".join(map(str, problems))
        raise MlxScriptError(f"{len(problems)} problem(s) in filter script {source}; nothing was run:\n  {lines}",
                             problems)
    return FilterScript(steps, source)


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
    return _validate(_parse_xml(data, source), source, base_dir)


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
    if ms.mesh_number() > 0 and not ms.mesh_id_exists(ms.current_mesh_id()):
        return "the MeshSet's current mesh does not exist"
    for p in step.params:
        if p.mlx_type == "RichMesh" and not ms.mesh_id_exists(p.value):
            return f"parameter '{p.mlx_name}': no mesh with id {p.value} in the MeshSet"
    return None


# --- writing ------------------------------------------------------------------------------


def _number(value):
    """Shortest text that reads back as the same double."""
    return repr(float(value))


def _param_xml(attrs):
    first = [k for k in ("type", "name", "value") if k in attrs]
    last = [k for k in ("description", "tooltip") if k in attrs]
    keys = first + sorted(k for k in attrs if k not in first and k not in last) + last
    return "  <Param " + " ".join(f"{k}={quoteattr(str(attrs[k]))}" for k in keys) + "/>"


def _our_filter_params(call):
    """MeshLab Param attributes for every parameter of one of our filters."""
    spec = registry.FILTERS[call.name]
    out = []
    for p in spec.params:
        value = call.resolved[p.name]
        attrs = {"type": p.mlx_type, "name": p.mlx}
        if p.kind == "bool":
            attrs["value"] = "true" if value else "false"
        elif p.kind == "int":
            attrs["value"] = str(int(value))
        elif p.kind == "float":
            attrs["value"] = _number(value)
        elif p.kind == "length":
            attrs.update(value=_number(value), min="0", max=_number(max(call.bbox_diagonal, float(value))))
        elif p.kind == "enum":
            attrs.update(value=str(p.choices.index(value)), enum_cardinality=str(len(p.choices)),
                         **{f"enum_val{i}": c for i, c in enumerate(p.choices)})
        else:
            attrs["value"] = str(value)
        attrs["description"] = p.display or p.name
        attrs["tooltip"] = p.help
        out.append(attrs)
    return out


def _exact_builtin_value(attrs, given):
    """Overwrite pymeshlab's 6-digit text of a real value with the full-precision value used.

    ``given`` is the keyword argument, or the default pymeshlab computed for the mesh just
    before the call; a ``PercentageValue`` argument keeps pymeshlab's (absolute) text.
    """
    kind = attrs.get("type")
    real = isinstance(given, numbers.Real) and not isinstance(given, (bool, np.bool_))
    if kind in ("RichFloat", "RichDynamicFloat") and real:
        attrs["value"] = _number(given)
    elif kind == "RichAbsPerc" and isinstance(given, pymeshlab.PureValue):
        attrs["value"] = _number(given.value())
    elif kind == "RichAbsPerc" and real:
        attrs["value"] = _number(given)
    elif kind in POINT_TYPES and np.shape(given) == (3,):
        attrs.update({k: _number(v) for k, v in zip("xyz", np.asarray(given, float))})
    elif kind == "RichMatrix44f" and np.shape(given) == (4, 4):
        attrs.update({f"val{i}": _number(v) for i, v in enumerate(np.asarray(given, float).ravel())})


def _builtin_params_from_kwargs(call):
    """Fallback when pymeshlab's record is missing: the explicitly given parameters only."""
    kinds = mlx_names.builtin_param_kinds(call.name) or {}
    out = []
    for name, value in call.kwargs.items():
        kind = kinds.get(name)
        attrs = {"name": name}
        if isinstance(value, (bool, np.bool_)):
            attrs.update(type="RichBool", value="true" if value else "false")
        elif kind == "percentage" and isinstance(value, pymeshlab.PercentageValue):
            continue  # its absolute value depended on the mesh; the default is closest
        elif kind == "percentage":
            v = value.value() if isinstance(value, pymeshlab.PureValue) else value
            attrs.update(type="RichAbsPerc", value=_number(v), min="0", max=_number(abs(float(v))))
        elif kind == "str" and isinstance(value, numbers.Integral):
            attrs.update(type="RichEnum", value=str(int(value)), enum_cardinality=str(int(value) + 1))
        elif isinstance(value, numbers.Integral):
            attrs.update(type="RichInt", value=str(int(value)))
        elif isinstance(value, numbers.Real):
            attrs.update(type="RichDynamicFloat" if kind == "dynamic_float" else "RichFloat", value=_number(value))
            if kind == "dynamic_float":
                attrs.update(min=_number(value), max=_number(value))
        elif isinstance(value, str):
            attrs.update(type="RichString", value=value)
        elif isinstance(value, pymeshlab.Color):
            attrs.update(type="RichColor", r=value.red(), g=value.green(), b=value.blue(), a=value.alpha())
        elif np.shape(value) == (3,):
            attrs.update(type="RichPosition", **{k: _number(v) for k, v in zip("xyz", np.asarray(value, float))})
        elif np.shape(value) == (4, 4):
            attrs.update(type="RichMatrix44f",
                         **{f"val{i}": _number(v) for i, v in enumerate(np.asarray(value, float).ravel())})
        else:
            continue
        out.append(attrs)
    return out


def _filter_xml(call):
    lines = []
    if call.name in registry.FILTERS:
        display, params = registry.FILTERS[call.name].display_name, _our_filter_params(call)
    elif call.meshlab_record is not None:
        display, params = call.meshlab_record.name, []
        used = dict(call.defaults or {})
        used.update(call.kwargs)
        for child in call.meshlab_record.children:
            attrs = dict(child.attrs)
            python_name = mlx_names.python_param_name(attrs.get("name", ""))
            if python_name in used:
                _exact_builtin_value(attrs, used[python_name])
            params.append(attrs)
    else:
        display, params = mlx_names.display_name(call.name), _builtin_params_from_kwargs(call)
        lines.append(" <!-- parameters not listed keep their defaults (pymeshlab's record of this call was "
                     "not available) -->")
    if not params:
        return lines + [f" <filter name={quoteattr(display)}/>"]
    return lines + [f" <filter name={quoteattr(display)}>"] + [_param_xml(a) for a in params] + [" </filter>"]


def filter_script_xml(ms, comment=None):
    """The filters applied to ``ms`` through this package, as MeshLab FilterScript XML text.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    comment : str, optional
        Text of an XML comment written before the script.
    """
    from . import __version__

    if comment is None:
        comment = (f"Recorded by meshlab_holefill {__version__}. Run with meshlab_holefill.run_filter_script(ms, path) "
                   "or `meshlab-holefill run`; the 'Close Holes: ...' filters of meshlab_holefill are unknown to "
                   "MeshLab itself.")
    lines = ["<!DOCTYPE FilterScript>", f"<!-- {escape(comment).replace('--', '- -')} -->", "<FilterScript>"]
    for call in registry.filter_calls(ms):
        lines.extend(_filter_xml(call))
    lines.append("</FilterScript>")
    return "\n".join(lines) + "\n"


def save_filter_script(ms, path, comment=None):
    """Write the filters applied to ``ms`` through this package as a MeshLab .mlx script.

    Replaying it with :func:`run_filter_script` on the same input gives the same mesh.

    Returns
    -------
    str
        The path written.
    """
    text = filter_script_xml(ms, comment)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return os.fspath(path)
