"""Writing MeshLab .mlx filter scripts: the filters applied to a MeshSet through this package.

Every filter applied through this package's API (``apply_filter``, the ``MeshSet`` methods of
our filters, ``run_filter_script``) is recorded per MeshSet
(:func:`meshlab_holefill.meshlab.registration.filter_calls`); :func:`filter_script_xml` turns that record
into MeshLab FilterScript XML and :func:`save_filter_script` writes it to a file. Built-in
filters called directly as ``ms.<name>()`` bypass the API and are not recorded, and neither
are MeshSet operations that are not filters (``load_new_mesh``, ``set_current_mesh``,
``add_mesh``): a filter script cannot express them.

The written script has MeshLab's types for our parameters (RichInt, RichFloat, RichBool,
RichEnum with its values, RichAbsPerc absolute with min/max, RichString) and every parameter
with the value actually used; built-in filters are written from pymeshlab's own record of the
call (:func:`meshlab_holefill.meshlab.mlx.parse.last_recorded_filter`: all their parameters, MeshLab names
and types), real values written at full precision (the arguments given, and the defaults
pymeshlab computed for the mesh just before the call); only a ``PercentageValue`` given to a
built-in keeps pymeshlab's 6-digit absolute value. Replaying the script on the same input
(:func:`meshlab_holefill.meshlab.mlx.script.run_filter_script`) gives the same mesh.

``target="meshlab-2020.09"`` writes MeshLab 2020.09's names, parameter sets and types instead
(:mod:`.versions`), for its ``meshlabserver``; it refuses our filters, which MeshLab cannot run.
"""
from __future__ import annotations

import numbers
import os
from xml.sax.saxutils import escape, quoteattr

import numpy as np
import pymeshlab

from . import names as mlx_names
from . import versions as mlx_versions
from .. import registration as registry
from ..._version import __version__
from .parse import last_recorded_filter
from .values import POINT_TYPES


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


def _recorded_element(call):
    """The ``<filter>`` element of pymeshlab's record of a built-in call, or None."""
    if call.meshlab_record is None:
        return None
    try:
        return last_recorded_filter(call.meshlab_record, call.name)
    except Exception:  # an unreadable record: write the call from its keyword arguments instead
        return None


def _builtin_record_params(call, record):
    """The parameters of pymeshlab's record of a built-in call, with the full-precision values used."""
    params = []
    used = dict(call.defaults or {})
    used.update(call.kwargs)
    for child in record.children:
        attrs = dict(child.attrs)
        python_name = mlx_names.python_param_name(attrs.get("name", ""))
        if python_name in used:
            _exact_builtin_value(attrs, used[python_name])
        params.append(attrs)
    return params


def _filter_xml_2020(call):
    """A recorded call as MeshLab 2020.09 writes it (see :func:`mlx_versions.filter_params_2020`)."""
    if call.name in registry.FILTERS:
        raise mlx_versions.MlxTargetError(
            f"filter '{call.name}' ('{registry.FILTERS[call.name].display_name}') is a meshlab_holefill filter, "
            "written in Python: MeshLab 2020.09 cannot run it. Save with target='meshlab' and run the script "
            "with meshlab_holefill.run_filter_script or `meshlab-holefill run`")
    record = _recorded_element(call)
    if record is None:
        raise mlx_versions.MlxTargetError(f"filter '{call.name}': pymeshlab's record of the call is not available, "
                                          "and MeshLab 2020.09 needs every parameter")
    display, params = mlx_versions.filter_params_2020(call, _builtin_record_params(call, record))
    if not params:
        return [f" <filter name={quoteattr(display)}/>"]
    return [f" <filter name={quoteattr(display)}>"] + [_param_xml(a) for a in params] + [" </filter>"]


def _filter_xml(call, target=mlx_versions.CURRENT):
    if target == mlx_versions.MESHLAB_2020_09:
        return _filter_xml_2020(call)
    lines = []
    if call.name in registry.FILTERS:
        display, params = registry.FILTERS[call.name].display_name, _our_filter_params(call)
    elif (record := _recorded_element(call)) is not None:
        display, params = record.name, _builtin_record_params(call, record)
    else:
        display, params = mlx_names.display_name(call.name), _builtin_params_from_kwargs(call)
        lines.append(" <!-- parameters not listed keep their defaults (pymeshlab's record of this call was "
                     "not available) -->")
    if not params:
        return lines + [f" <filter name={quoteattr(display)}/>"]
    return lines + [f" <filter name={quoteattr(display)}>"] + [_param_xml(a) for a in params] + [" </filter>"]


def _default_comment(target):
    if target == mlx_versions.MESHLAB_2020_09:
        return (f"Recorded by meshlab_holefill {__version__} for MeshLab 2020.09: run with "
                "meshlabserver -i in.ply -o out.ply -s this.mlx, or meshlab_holefill.run_filter_script(ms, path).")
    return (f"Recorded by meshlab_holefill {__version__}. Run with meshlab_holefill.run_filter_script(ms, path) "
            "or `meshlab-holefill run`; the 'Close Holes: ...' filters of meshlab_holefill are unknown to "
            "MeshLab itself.")


def filter_script_xml(ms, comment=None, target=mlx_versions.CURRENT):
    """The filters applied to ``ms`` through this package, as MeshLab FilterScript XML text.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    comment : str, optional
        Text of an XML comment written before the script.
    target : {'meshlab', 'meshlab-2020.09'}
        Current MeshLab's names (pymeshlab's), or MeshLab 2020.09's names, parameter sets and
        types, which its ``meshlabserver`` accepts (every parameter written, none it lacks).

    Raises
    ------
    MlxTargetError
        With target 'meshlab-2020.09': a filter of this package (Python, which MeshLab cannot
        run), a filter MeshLab 2020.09 does not have, or a parameter it does not have set to
        a non-default value; the message names the filter.
    """
    mlx_versions.check_target(target)
    if comment is None:
        comment = _default_comment(target)
    lines = ["<!DOCTYPE FilterScript>", f"<!-- {escape(comment).replace('--', '- -')} -->", "<FilterScript>"]
    for call in registry.filter_calls(ms):
        lines.extend(_filter_xml(call, target))
    lines.append("</FilterScript>")
    return "\n".join(lines) + "\n"


def save_filter_script(ms, path, comment=None, target=mlx_versions.CURRENT):
    """Write the filters applied to ``ms`` through this package as a MeshLab .mlx script.

    Replaying it with :func:`run_filter_script` on the same input gives the same mesh.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    path : str or os.PathLike
    comment : str, optional
    target : {'meshlab', 'meshlab-2020.09'}
        Whose names to write: current MeshLab's (default), or MeshLab 2020.09's, for its
        ``meshlabserver`` (built-in filters only); see :func:`filter_script_xml`.

    Returns
    -------
    str
        The path written.
    """
    text = filter_script_xml(ms, comment, target)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return os.fspath(path)
