"""MeshLab versions of .mlx scripts: the names and parameters of MeshLab 2020.09.

MeshLab 2022 renamed and merged some filters and added parameters to others, and pymeshlab
follows current MeshLab. Scripts written for MeshLab 2020.09 (the last release with
``meshlabserver``, still the MeshLab of Debian 12) use the old names, and its
``meshlabserver`` accepts only its own: every parameter of a filter, no more and no fewer.

Two data files, measured on the real ``meshlabserver`` of MeshLab 2020.09
(``scripts/meshlab_2020_09_tables.py``):

- ``data/meshlab_2020_09_filters.tsv``: each 2020.09 filter with its parameters in order,
  their MeshLab types and defaults (as written in a script; defaults that depend on the mesh
  are those of an empty document);
- ``data/meshlab_2020_09_names.tsv``: each 2020.09 filter -> the pymeshlab python name of its
  current counterpart, the parameter values its old name implies ("Repair non Manifold Edges
  by removing faces" is ``meshing_repair_non_manifold_edges`` with ``method=0``) and renamed
  parameters; or no counterpart, with the reason.

Reading a 2020.09 script (:func:`filter_2020`) and writing one
(:func:`filter_params_2020`, used by :func:`meshlab_holefill.save_filter_script` with
``target="meshlab-2020.09"``) both go through these tables.
"""
from __future__ import annotations

import functools
import json
from dataclasses import dataclass, field
from importlib import resources

import numpy as np
import pymeshlab

from .python_names import python_param_name

CURRENT = "meshlab"
MESHLAB_2020_09 = "meshlab-2020.09"
TARGETS = (CURRENT, MESHLAB_2020_09)

FILTERS_FILE = "meshlab_2020_09_filters.tsv"
NAMES_FILE = "meshlab_2020_09_names.tsv"

# Current MeshLab types that MeshLab 2020.09 writes under another name (same attributes).
_SAME_ATTRIBUTES = {"RichPosition": "RichPoint3f", "RichDirection": "RichPoint3f"}


class MlxTargetError(ValueError, pymeshlab.PyMeshLabException):
    """A recorded filter cannot be written for the requested MeshLab version."""


@dataclass(frozen=True)
class Param2020:
    """A parameter of a MeshLab 2020.09 filter.

    Attributes
    ----------
    name : str
        Its name in scripts ("MaxHoleSize").
    type : str
        Its MeshLab type ("RichInt").
    default : dict
        The value attributes MeshLab 2020.09 writes (``value``; ``r g b a``; ``x y z``;
        ``val0``..``val15``), with its default; empty where it has none (meshes, shots).
    """

    name: str
    type: str
    default: dict


@dataclass(frozen=True)
class Filter2020:
    """A MeshLab 2020.09 filter and its current counterpart.

    Attributes
    ----------
    name : str
        Display name in MeshLab 2020.09.
    params : tuple of Param2020
        Its parameters, in MeshLab's order.
    python_name : str or None
        The pymeshlab python name of the current filter; None when it has none.
    implied : dict
        Python parameter -> value that the old name stands for.
    renamed : dict
        2020.09 parameter name -> python parameter name, where the rule of
        :func:`python_param_name` does not give it.
    note : str
        Why there is no counterpart.
    """

    name: str
    params: tuple
    python_name: str | None
    implied: dict = field(default_factory=dict)
    renamed: dict = field(default_factory=dict)
    note: str = ""

    def python_param(self, name):
        """Python name of the current parameter a 2020.09 parameter sets."""
        return self.renamed.get(name, python_param_name(name))

    def param(self, name):
        """The Param2020 called ``name``, or None."""
        return next((p for p in self.params if p.name == name), None)


def _rows(file_name):
    text = resources.files(__package__).joinpath("data").joinpath(file_name).read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if line and not line.startswith("#")]
    return [line.split("\t") for line in lines[1:]]


@functools.lru_cache(maxsize=None)
def filters_2020():
    """Dict display name -> :class:`Filter2020` of every MeshLab 2020.09 filter."""
    params = {}
    for name, param, mlx_type, default in _rows(FILTERS_FILE):
        params.setdefault(name, [])
        if param:
            params[name].append(Param2020(param, mlx_type, json.loads(default)))
    table = {}
    for name, python_name, implied, renamed, note in _rows(NAMES_FILE):
        table[name] = Filter2020(name, tuple(params[name]), python_name or None,
                                 json.loads(implied) if implied else {}, json.loads(renamed) if renamed else {},
                                 note)
    return table


def filter_2020(name):
    """The MeshLab 2020.09 filter with this display name, or None."""
    return filters_2020().get(name)


# --- reading ------------------------------------------------------------------------------


def _same_value(param, attrs):
    """Does a script's <Param> give a 2020.09 parameter its default value?"""
    if not param.default:
        return False
    for key, default in param.default.items():
        given = attrs.get(key)
        if given is None:
            return False
        try:
            if float(given) != float(default):
                return False
        except ValueError:
            if given.strip().lower() != default.strip().lower():
                return False
    return True


def dropped_param_problem(f2020, param_name, attrs):
    """Why a 2020.09 parameter without a current counterpart cannot be read; None when it can.

    Such a parameter (e.g. ``Selected`` of "Simplification: Clustering Decimation") is read
    and left out when it has its 2020.09 default value: the current filter then does what
    MeshLab 2020.09 did.
    """
    param = f2020.param(param_name)
    if param is None:
        return None
    if _same_value(param, attrs):
        return ""
    shown = ", ".join(f"{k}={v!r}" for k, v in param.default.items()) or "none"
    return (f"a MeshLab 2020.09 parameter that current MeshLab (pymeshlab) no longer has; only its 2020.09 "
            f"default ({shown}) can be read")


# --- writing ------------------------------------------------------------------------------


def _record_values(record_params):
    """Python parameter name -> attributes of pymeshlab's record of a call."""
    return {python_param_name(a.get("name", "")): a for a in record_params}


def _implied_match(f2020, values):
    for key, wanted in f2020.implied.items():
        attrs = values.get(key)
        if attrs is None:
            return False
        text = attrs.get("value", "")
        if isinstance(wanted, bool):
            if text.lower() != ("true" if wanted else "false"):
                return False
        elif text != str(wanted):
            return False
    return True


def counterpart_2020(python_name, record_params):
    """The MeshLab 2020.09 filter a recorded call of ``python_name`` is written as.

    Among the 2020.09 filters whose counterpart is ``python_name``, the one whose implied
    parameter values the call has (the most of them: "Select Folded Faces" before
    "Select 'problematic' faces").

    Raises
    ------
    MlxTargetError
        MeshLab 2020.09 has no such filter.
    """
    values = _record_values(record_params)
    candidates = [f for f in filters_2020().values() if f.python_name == python_name and _implied_match(f, values)]
    if not candidates:
        raise MlxTargetError(f"filter '{python_name}' has no counterpart in MeshLab 2020.09 "
                             "(it was added or changed in MeshLab 2022 or later)")
    return max(candidates, key=lambda f: (len(f.implied), f.name))


def _equal(a, b):
    value = getattr(a, "value", None)
    a = value() if callable(value) else a
    value = getattr(b, "value", None)
    b = value() if callable(value) else b
    try:
        return bool(np.all(np.asarray(a) == np.asarray(b)))
    except (TypeError, ValueError):
        return False


def _check_current_only(call, f2020, values):
    """Refuse a call that set a parameter MeshLab 2020.09 does not have to a non-default value."""
    known = {f2020.python_param(p.name) for p in f2020.params} | set(f2020.implied)
    for key in values:
        if key in known or key not in call.kwargs:
            continue
        defaults = call.defaults or {}
        if key not in defaults or not _equal(call.kwargs[key], defaults[key]):
            raise MlxTargetError(
                f"filter '{call.name}' ('{f2020.name}' in MeshLab 2020.09): parameter '{key}' = {call.kwargs[key]!r} "
                "does not exist in MeshLab 2020.09; only its default can be written for that version")


_VALUE_KEYS = {"value", "x", "y", "z", "r", "g", "b", "a"} | {f"val{i}" for i in range(16)}


def _widen_range(attrs):
    """Make a RichDynamicFloat's or RichAbsPerc's min/max contain its value."""
    if not {"value", "min", "max"} <= set(attrs):
        return
    try:
        value, low, high = (float(attrs[k]) for k in ("value", "min", "max"))
    except ValueError:
        return
    if value < low:
        attrs["min"] = attrs["value"]
    if value > high:
        attrs["max"] = attrs["value"]


def _param_attrs_2020(call, f2020, param, values):
    """The <Param> attributes of one 2020.09 parameter: the recorded value, else the 2020.09 default.

    The attributes are those MeshLab 2020.09 writes for the parameter (``value``, and
    ``min``/``max`` of a RichDynamicFloat or RichAbsPerc, the values of a RichEnum, ...), each
    from the recorded call where it has it.
    """
    where = f"filter '{call.name}' ('{f2020.name}' in MeshLab 2020.09): parameter '{param.name}'"
    recorded = values.get(f2020.python_param(param.name))
    if recorded is not None:
        kind = _SAME_ATTRIBUTES.get(recorded.get("type"), recorded.get("type"))
        if kind != param.type and not {kind, param.type} <= {"RichFloat", "RichDynamicFloat", "RichAbsPerc"}:
            raise MlxTargetError(f"{where} is a {param.type} there, recorded as {recorded.get('type')}")
    keys = list(param.default) or [k for k in ("value",) if recorded is not None and k in recorded]
    if not keys:
        raise MlxTargetError(f"{where}: no value to write")
    attrs = {"type": param.type, "name": param.name}
    for key in keys:
        if recorded is not None and key in recorded:
            attrs[key] = recorded[key]
        elif recorded is not None and key in _VALUE_KEYS:
            raise MlxTargetError(f"{where}: the recorded call has no '{key}'")
        else:
            attrs[key] = param.default[key]
    _widen_range(attrs)
    return attrs


def filter_params_2020(call, record_params):
    """Display name and <Param> attributes of a recorded built-in call, for MeshLab 2020.09.

    Every parameter of the 2020.09 filter is written (its ``meshlabserver`` requires all of
    them), in its order, with its types: the recorded value where current MeshLab has the
    parameter, else the 2020.09 default. A recorded parameter that 2020.09 does not have is
    left out when it kept its default and refused otherwise.

    Parameters
    ----------
    call : registry.FilterCall
    record_params : list of dict
        Attributes of the ``<Param>`` elements of pymeshlab's record of the call, with the
        values actually used.

    Returns
    -------
    (str, list of dict)

    Raises
    ------
    MlxTargetError
        The filter or one of its parameter values does not exist in MeshLab 2020.09.
    """
    f2020 = counterpart_2020(call.name, record_params)
    values = _record_values(record_params)
    _check_current_only(call, f2020, values)
    return f2020.name, [_param_attrs_2020(call, f2020, p, values) for p in f2020.params]


def check_target(target):
    """Refuse an unknown target name."""
    if target not in TARGETS:
        raise ValueError(f"unknown MeshLab target {target!r}; choose one of {', '.join(map(repr, TARGETS))}")
