"""MeshLab names: filter and parameter names, and the parameter kinds of built-in filters.

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

The values of typed ``<Param>`` elements are read in :mod:`mlx_values`.
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

import pymeshlab

from .. import registration as registry
from .python_names import python_param_name
from .versions import filter_2020

TABLE_FILE = "meshlab_filter_names.tsv"

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
    from ..exceptions import pymeshlab_filter_list

    return frozenset(pymeshlab_filter_list())


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
        'display name', 'python name', 'MeshLab 2020.09 name', 'old display name' or
        'old python name'.
    meshlab_2020 : versions.Filter2020 or None
        The MeshLab 2020.09 filter of this name, when it is one and stands for this filter.
    """

    python_name: str
    ours: bool
    how: str
    meshlab_2020: object = None


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
    (by the rule that made the old python names); a MeshLab 2020.09 display name
    (:mod:`.versions`) is tried right after the current names. Current names win over old ones
    ("Ambient Occlusion" is today the GPU filter; before 2022 it was
    ``compute_scalar_ambient_occlusion``).

    A built-in filter named by its MeshLab 2020.09 name gets that filter's table entry
    (``meshlab_2020``): its implied and renamed parameters, and the parameters current
    MeshLab dropped.

    Returns
    -------
    FilterName or None
    """
    understood = _resolve_filter(name)
    if understood is None or understood.ours:
        return understood
    f2020 = filter_2020(name)
    if f2020 is not None and f2020.python_name == understood.python_name:
        return FilterName(understood.python_name, False, understood.how, f2020)
    return understood


def _resolve_filter(name):
    """The filter a name stands for, without the MeshLab 2020.09 details."""
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
    f2020 = filter_2020(name)
    if f2020 is not None and f2020.python_name in builtins:
        return FilterName(f2020.python_name, False, "MeshLab 2020.09 name")
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


_warn_if_table_disagrees()
