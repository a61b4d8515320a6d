"""MeshLab names and types: filter and parameter names, parameter kinds, typed Param values.

MeshLab ``.mlx`` filter scripts name a filter by its *display name* ("Close Holes") and a
parameter by its MeshLab name ("MaxHoleSize"); pymeshlab uses python names
(``meshing_close_holes``, ``maxholesize``). This module holds the translations:

- ``data/meshlab_filter_names.tsv``: display name of every built-in filter of pymeshlab
  (the shared facts table, from pymeshlab's documentation, plus ``create_dodecahedron_sym``
  -> "Dodecahedron (symmetric)", which that table missed; the display name was read back from
  pymeshlab's own ``save_filter_script``). :func:`check_filter_table` compares it with
  ``pymeshlab.filter_list()``; a disagreement is reported with a warning at import.
- pymeshlab's ``keys.txt`` (shipped inside the pymeshlab package) maps the python names used
  before pymeshlab 2022.2 to the current ones; the old python name of a filter was its
  display name put through :func:`python_param_name`, so old display names and old python
  names are both accepted (:func:`resolve_filter`).
- :func:`builtin_param_kinds` reads the parameter names and python types of a built-in
  filter from ``pymeshlab.print_filter_parameter_list`` (the only mesh-independent source).
- :func:`parse_value` reads a ``<Param>`` element of each MeshLab type;
  :func:`builtin_param_value` and :func:`our_param_value` check it against the parameter it
  sets and turn it into the keyword argument for ``apply_filter``.
"""
from __future__ import annotations

import ctypes
import difflib
import functools
import os
import re
import sys
import tempfile
import warnings
from dataclasses import dataclass
from importlib import resources

import numpy as np
import pymeshlab

from . import registry
from .registry import FilterParameterError

TABLE_FILE = "meshlab_filter_names.tsv"

# pymeshlab's computePythonName appends '_' to these (its list, including its missing comma
# that leaves out "def" and "from", so that the names agree with pymeshlab's).
_PYMESHLAB_KEYWORDS = {
    "False", "await", "else", "import", "pass", "None", "break", "except", "in", "raise", "True", "class",
    "finally", "is", "return", "and", "continue", "for", "lambda", "try", "as", "def\tfrom", "nonlocal",
    "while", "assert", "del", "global", "not", "with", "async", "elif", "if", "or", "yield",
}
_REMOVED_CHARACTERS = re.compile(r"""[()\[\].,'":+]+""")


def python_param_name(mlx_name):
    """MeshLab's rule from a MeshLab name to the pymeshlab python name.

    Lower case; ``' '``, ``'/'`` and ``'-'`` become ``'_'``; the characters ``()[].,'":+``
    are removed; a python keyword gets a trailing ``'_'`` ("lambda" -> "lambda_"). This is
    pymeshlab's ``computePythonName`` (which also produced the pre-2022 filter names from
    display names); pymeshlab's regular expression does not remove ``[]``, this one does,
    so that the result is always an identifier (no MeshLab name contains them).
    """
    name = mlx_name.lower().replace(" ", "_").replace("/", "_").replace("-", "_")
    name = _REMOVED_CHARACTERS.sub("", name)
    if name in _PYMESHLAB_KEYWORDS:
        name += "_"
    return name


@functools.lru_cache(maxsize=None)
def builtin_display_names():
    """Dict python name -> MeshLab display name of pymeshlab's built-in filters (the shipped table)."""
    text = resources.files(__package__).joinpath("data").joinpath(TABLE_FILE).read_text(encoding="utf-8")
    table = {}
    for line in text.splitlines()[1:]:
        if not line.strip() or line.startswith("#"):
            continue
        python_name, display = line.split("\t")
        table[python_name] = display
    return table


@functools.lru_cache(maxsize=None)
def _builtin_names():
    return frozenset(pymeshlab.filter_list())


def check_filter_table():
    """Compare the shipped display-name table with ``pymeshlab.filter_list()``.

    Returns
    -------
    dict
        ``missing``: pymeshlab filters without a display name in the table;
        ``unknown``: table rows naming a filter this pymeshlab does not have;
        ``duplicate_display_names``: display names given to more than one filter.
        All three empty when the table agrees.
    """
    table = builtin_display_names()
    builtins = _builtin_names()
    seen, duplicates = set(), set()
    for display in table.values():
        (duplicates if display in seen else seen).add(display)
    return {"missing": sorted(builtins - set(table)), "unknown": sorted(set(table) - builtins),
            "duplicate_display_names": sorted(duplicates)}


def _warn_if_table_disagrees():
    problems = check_filter_table()
    if any(problems.values()):
        warnings.warn(f"meshlab_holefill: the MeshLab filter-name table disagrees with this pymeshlab "
                      f"({pymeshlab.__name__}): {problems}; .mlx scripts naming these filters may not run",
                      RuntimeWarning, stacklevel=3)


@functools.lru_cache(maxsize=None)
def old_python_names():
    """Dict pre-2022 python name -> current python name, from pymeshlab's ``keys.txt``.

    A target pymeshlab no longer has (``keys.txt`` of pymeshlab 2025.7 still maps to
    ``meshing_re_orient_faces_coherentely``, since renamed ``..._coherently``) is replaced by
    its closest current name when that is unambiguous, else dropped.
    """
    path = os.path.join(os.path.dirname(pymeshlab.__file__), "keys.txt")
    if not os.path.exists(path):
        return {}
    builtins = _builtin_names()
    mapping = {}
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.split()
            if len(parts) != 2:
                continue
            old, new = parts
            if new not in builtins:
                close = difflib.get_close_matches(new, builtins, n=2, cutoff=0.9)
                if len(close) != 1:
                    continue
                new = close[0]
            mapping[old] = new
    return mapping


@dataclass(frozen=True)
class FilterName:
    """How a filter name of a script was understood.

    Attributes
    ----------
    python_name : str
    ours : bool
        True for a filter of this package, False for a pymeshlab built-in.
    how : str
        'display name', 'python name', 'old display name' or 'old python name'.
    """

    python_name: str
    ours: bool
    how: str


@functools.lru_cache(maxsize=None)
def _display_index():
    """Display name -> python name for built-ins, and the same keyed by the rule applied to it."""
    exact = {display: name for name, display in builtin_display_names().items()}
    by_rule = {}
    for display, name in exact.items():
        by_rule.setdefault(python_param_name(display), set()).add(name)
    return exact, by_rule


def resolve_filter(name):
    """Understand a filter name written in an .mlx script.

    Tried in order: a display name of ours, a python name of ours, a current built-in display
    name, a current built-in python name, an old (pre-2022) python name, a current display
    name compared by MeshLab's rule (ignoring case and punctuation), an old display name
    (by the rule that made the old python names). Current names win over old ones
    ("Ambient Occlusion" is today the GPU filter; before 2022 it was
    ``compute_scalar_ambient_occlusion``).

    Returns
    -------
    FilterName or None
    """
    for spec in registry.FILTERS.values():
        if name == spec.display_name:
            return FilterName(spec.name, True, "display name")
    if name in registry.FILTERS:
        return FilterName(name, True, "python name")
    exact, by_rule = _display_index()
    builtins = _builtin_names()
    if name in exact and exact[name] in builtins:
        return FilterName(exact[name], False, "display name")
    if name in builtins:
        return FilterName(name, False, "python name")
    old = old_python_names()
    if name in old:
        return FilterName(old[name], False, "old python name")
    ruled = python_param_name(name)
    candidates = by_rule.get(ruled, set()) & builtins
    if len(candidates) == 1:
        return FilterName(next(iter(candidates)), False, "display name")
    if ruled in old:
        return FilterName(old[ruled], False, "old display name")
    return None


def display_name(python_name):
    """MeshLab display name of a filter (ours or built-in); the python name if unknown."""
    if python_name in registry.FILTERS:
        return registry.FILTERS[python_name].display_name
    return builtin_display_names().get(python_name, python_name)


def suggest_filters(name, n=3):
    """Closest known display names (ours and built-ins) to an unknown filter name."""
    names = [spec.display_name for spec in registry.FILTERS.values()] + list(builtin_display_names().values())
    return difflib.get_close_matches(name, names, n=n, cutoff=0.6)


# --- parameters of built-in filters ---------------------------------------------------------

# pymeshlab's python type string -> our kind name
_PYTHON_TYPE_KINDS = {
    "bool": "bool", "int": "int", "float": "float", "float (bounded)": "dynamic_float",
    "PercentageValue": "percentage", "str": "str", "Color": "color",
    "numpy.ndarray[numpy.float64[3]]": "point3", "numpy.ndarray[numpy.float64[4, 4]]": "matrix44",
    "Shotf [still unsupported]": "shot",
}
_PARAM_LINE = re.compile(r"^\t(\w+) : (.+?) = (.*)$")


def _flush_c_stdio():
    try:
        libc = ctypes.CDLL(None)
    except (OSError, TypeError):  # Windows: no process-wide C library handle
        try:
            libc = ctypes.cdll.msvcrt
        except OSError:
            return
    libc.fflush(None)


def _capture_stdout(function, *args):
    """Text a C++ function writes to the process's standard output (file descriptor 1).

    pymeshlab prints its parameter listing from C++, out of reach of ``sys.stdout``; the
    file descriptor is redirected to a temporary file for the call.
    """
    sys.stdout.flush()
    _flush_c_stdio()
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+b") as sink:
        os.dup2(sink.fileno(), 1)
        try:
            function(*args)
        finally:
            _flush_c_stdio()
            os.dup2(saved, 1)
            os.close(saved)
        sink.seek(0)
        return sink.read().decode("utf-8", "replace")


@functools.lru_cache(maxsize=None)
def builtin_param_kinds(python_name):
    """Parameters of a pymeshlab built-in filter and their kinds.

    Returns
    -------
    dict or None
        python parameter name -> kind, one of 'bool', 'int' (RichInt, and RichMesh: a mesh
        id), 'float', 'dynamic_float' (RichDynamicFloat), 'percentage' (RichAbsPerc, given
        as pymeshlab.PureValue or PercentageValue), 'str' (RichString, RichEnum: pymeshlab
        lists enums as str and accepts their index, file names), 'color', 'point3',
        'matrix44', 'shot'. None when pymeshlab's listing could not be read (then the
        script's parameter names are passed on unchecked).
    """
    text = _capture_stdout(pymeshlab.print_filter_parameter_list, python_name)
    marker = f"{python_name} filter - list of parameter names:"
    if marker not in text:
        return None
    kinds = {}
    for line in text.split(marker, 1)[1].splitlines():
        match = _PARAM_LINE.match(line)
        if match:
            kinds[match.group(1)] = _PYTHON_TYPE_KINDS.get(match.group(2).strip(), "unknown")
    if not kinds and "None." not in text:
        return None
    return kinds


# --- parameter values: MeshLab types -> python values ---------------------------------------

FLOAT_TYPES = {"RichFloat", "RichDynamicFloat", "RichAbsPerc", "RichPercentage"}
NUMBER_TYPES = FLOAT_TYPES | {"RichInt"}
FILE_TYPES = {"RichOpenFile", "RichSaveFile", "RichFileOpen", "RichFileSave"}
POINT_TYPES = {"RichPosition", "RichDirection", "RichPoint3f"}
INT_TYPES = {"RichInt", "RichEnum", "RichMesh"}
KNOWN_TYPES = (NUMBER_TYPES | FILE_TYPES | POINT_TYPES | INT_TYPES
               | {"RichBool", "RichString", "RichColor", "RichMatrix44f", "RichShotf"})

# MeshLab types a built-in parameter accepts, by the kind pymeshlab lists (builtin_param_kinds).
BUILTIN_ACCEPTS = {
    "bool": {"RichBool"}, "int": INT_TYPES, "float": NUMBER_TYPES, "dynamic_float": NUMBER_TYPES,
    "percentage": NUMBER_TYPES, "str": {"RichString", "RichEnum"} | FILE_TYPES, "color": {"RichColor"},
    "point3": POINT_TYPES, "matrix44": {"RichMatrix44f"}, "shot": set(), "unknown": KNOWN_TYPES,
}
# ... and an untyped MeshLab 2016 <xmlparam> is read as this type.
BUILTIN_XMLPARAM_TYPE = {"bool": "RichBool", "int": "RichInt", "float": "RichFloat",
                         "dynamic_float": "RichFloat", "percentage": "RichFloat", "str": "RichString"}
# MeshLab types a parameter of ours accepts, by ParamSpec.kind.
OURS_ACCEPTS = {"int": {"RichInt"}, "float": NUMBER_TYPES, "bool": {"RichBool"},
                "enum": {"RichEnum", "RichInt", "RichString"}, "length": NUMBER_TYPES, "string": {"RichString"}}


class ParamValueError(Exception):
    """A Param element whose value cannot be used (the message says why)."""


def _attr_float(attrs, key):
    if key not in attrs:
        raise ParamValueError(f"has no '{key}' attribute")
    try:
        value = float(attrs[key])
    except ValueError:
        raise ParamValueError(f"{key}={attrs[key]!r} is not a number") from None
    if not np.isfinite(value):
        raise ParamValueError(f"{key}={attrs[key]!r} is not finite")
    return value


def _attr_int(attrs, key):
    if key not in attrs:
        raise ParamValueError(f"has no '{key}' attribute")
    try:
        return int(attrs[key].strip())
    except ValueError:
        raise ParamValueError(f"{key}={attrs[key]!r} is not an integer") from None


def parse_value(mlx_type, attrs, base_dir):
    """Python value of a Param element of a given MeshLab type (raises ParamValueError)."""
    if mlx_type == "RichBool":
        text = attrs.get("value")
        if text is None or text.strip().lower() not in ("true", "false"):
            raise ParamValueError(f"value={text!r} is not 'true' or 'false'")
        return text.strip().lower() == "true"
    if mlx_type in ("RichInt", "RichMesh"):
        value = _attr_int(attrs, "value")
        if mlx_type == "RichMesh" and value < 0:
            raise ParamValueError(f"mesh id {value} is negative")
        return value
    if mlx_type == "RichEnum":
        value = _attr_int(attrs, "value")
        if "enum_cardinality" in attrs:
            cardinality = _attr_int(attrs, "enum_cardinality")
            if not 0 <= value < cardinality:
                raise ParamValueError(f"enum index {value} is not in [0, {cardinality})")
        elif value < 0:
            raise ParamValueError(f"enum index {value} is negative")
        return value
    if mlx_type in FLOAT_TYPES:
        return _attr_float(attrs, "value")
    if mlx_type == "RichString":
        return attrs.get("value", "")
    if mlx_type in FILE_TYPES:
        return _file_value(mlx_type, attrs.get("value", ""), base_dir)
    if mlx_type == "RichColor":
        rgba = [_attr_int(attrs, k) if k in attrs or k != "a" else 255 for k in "rgba"]
        if not all(0 <= c <= 255 for c in rgba):
            raise ParamValueError(f"colour components {rgba} are not all in [0, 255]")
        return tuple(rgba)
    if mlx_type in POINT_TYPES:
        return np.array([_attr_float(attrs, k) for k in "xyz"])
    if mlx_type == "RichMatrix44f":
        return np.array([_attr_float(attrs, f"val{i}") for i in range(16)]).reshape(4, 4)
    if mlx_type == "RichShotf":
        raise ParamValueError("RichShotf (camera) parameters are not supported by pymeshlab")
    raise ParamValueError(f"unknown MeshLab parameter type {mlx_type!r}")


def _file_value(mlx_type, path, base_dir):
    if not path:
        raise ParamValueError("empty file name")
    candidates = [path]
    if not os.path.isabs(path) and base_dir is not None:
        candidates.append(os.path.join(base_dir, path))
    if mlx_type in ("RichOpenFile", "RichFileOpen"):
        for candidate in candidates:
            if os.path.isfile(candidate):
                return candidate
        raise ParamValueError(f"file not found: {path!r}")
    for candidate in candidates:
        if os.path.isdir(os.path.dirname(os.path.abspath(candidate))):
            return candidate
    raise ParamValueError(f"the directory of {path!r} does not exist")


def builtin_param_value(kinds, element, param_name, mlx_type, base_dir):
    """(python name, value) for a parameter of a built-in filter."""
    python_name = python_param_name(param_name)
    if kinds is None:  # pymeshlab's listing unreadable: pass the name on, pymeshlab checks it
        kind = "unknown"
    elif python_name not in kinds:
        valid = ", ".join(kinds) if kinds else "none"
        raise ParamValueError(f"unknown parameter (python name '{python_name}'); this filter's parameters: {valid}")
    else:
        kind = kinds[python_name]
    if mlx_type is None:  # MeshLab 2016 <xmlparam>: untyped
        if kind not in BUILTIN_XMLPARAM_TYPE:
            raise ParamValueError(f"an untyped <xmlparam> cannot give a {kind} parameter")
        mlx_type = BUILTIN_XMLPARAM_TYPE[kind]
    if mlx_type not in BUILTIN_ACCEPTS[kind]:
        raise ParamValueError(f"type {mlx_type} does not fit this parameter ({kind}; accepts "
                              f"{', '.join(sorted(BUILTIN_ACCEPTS[kind])) or 'nothing pymeshlab can set'})")
    value = parse_value(mlx_type, element.attrs, base_dir)
    if kind == "percentage" or (kind == "unknown" and mlx_type in ("RichAbsPerc", "RichPercentage")):
        value = pymeshlab.PureValue(float(value))
    elif kind in ("float", "dynamic_float"):
        value = float(value)
    elif mlx_type == "RichColor":
        value = pymeshlab.Color(*value)
    return python_name, value


def our_param_value(spec, element, param_name, mlx_type, base_dir):
    """(python name, value) for a parameter of one of our filters."""
    ruled = python_param_name(param_name)
    matches = [p for p in spec.params if p.mlx == param_name] or \
              [p for p in spec.params if ruled in (p.name, python_param_name(p.mlx))]
    if not matches:
        raise ParamValueError(f"unknown parameter; this filter's parameters: {', '.join(p.mlx for p in spec.params)}")
    param = matches[0]
    if mlx_type is None:  # untyped <xmlparam>
        mlx_type = param.mlx_type
        if param.kind == "enum" and not element.attrs.get("value", "").strip().isdigit():
            mlx_type = "RichString"
    if mlx_type not in OURS_ACCEPTS[param.kind]:
        raise ParamValueError(f"type {mlx_type} does not fit this parameter ({param.mlx_type}; accepts "
                              f"{', '.join(sorted(OURS_ACCEPTS[param.kind]))})")
    value = parse_value(mlx_type, element.attrs, base_dir)
    if param.kind in ("float", "length"):
        value = float(value)
    try:
        value = registry.convert_param(param, value, spec.name, None)
    except FilterParameterError as exc:
        raise ParamValueError(str(exc).split(": ", 1)[-1]) from None
    return param.name, value


_warn_if_table_disagrees()
