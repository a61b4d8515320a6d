"""pymeshlab's by-name entry points, extended to this package's filters.

pymeshlab reaches a filter by name through ``MeshSet.apply_filter`` (every filter method
calls it), ``pymeshlab.print_filter_parameter_list`` and a loaded filter script
(``MeshSet.load_filter_script`` then ``apply_filter_script``). All of them run in C++ and
know only MeshLab's plugins: a script naming one of our filters loads, then fails with
"Something really bad happened" when applied. :func:`extend` wraps each of them so that our
names go to :func:`.registry.apply_filter` and :func:`.mlx.run_filter_script`, and every
other name or script goes to pymeshlab's own method, unchanged.
"""
from __future__ import annotations

import re
import weakref
from xml.sax.saxutils import unescape

import pymeshlab

from . import listing_doors
from .mlx import names as mlx_names
from .mlx import script as mlx
from . import registration as registry


def _original(owner, name):
    """pymeshlab's own function, also when the package is imported (or reloaded) again."""
    current = getattr(owner, name)
    return getattr(current, "pymeshlab_original", current)


_APPLY_FILTER = _original(pymeshlab.MeshSet, "apply_filter")
_PRINT_PARAMETERS = _original(pymeshlab, "print_filter_parameter_list")
_LOAD_SCRIPT = _original(pymeshlab.MeshSet, "load_filter_script")
_APPLY_SCRIPT = _original(pymeshlab.MeshSet, "apply_filter_script")
_CLEAR_SCRIPT = _original(pymeshlab.MeshSet, "clear_filter_script")

# MeshSet -> the loaded script, parsed, when it names one of our filters
_LOADED: "weakref.WeakKeyDictionary[pymeshlab.MeshSet, mlx.FilterScript]" = weakref.WeakKeyDictionary()


def apply_filter(self, filter_name, **kwargs):
    """``MeshSet.apply_filter`` that also runs this package's filters by name."""
    if filter_name in registry.FILTERS:
        return registry.apply_filter(self, filter_name, **kwargs)
    return _APPLY_FILTER(self, filter_name, **kwargs)


def print_filter_parameter_list(filter_name):
    """``pymeshlab.print_filter_parameter_list`` that also knows this package's filters."""
    if filter_name in registry.FILTERS:
        print(registry.filter_help(filter_name))
    else:
        _PRINT_PARAMETERS(filter_name)


_FILTER_NAME = re.compile(r"""<(?:xml)?filter\b[^>]*\bname=(?:"([^"]*)"|'([^']*)')""")


def _needs_our_reader(path):
    """Does the script at ``path`` name a filter pymeshlab cannot run by that name?

    That is one of our filters, or a built-in named otherwise than by its current display
    name (a MeshLab 2020.09 name such as "Repair non Manifold Edges by removing faces", a
    pre-2022 or a python name). Unknown names stay pymeshlab's business.
    """
    try:
        with open(path, "rb") as fh:
            text = fh.read().decode("utf-8", "replace")
    except OSError:
        return False
    for match in _FILTER_NAME.finditer(text):
        understood = mlx_names.resolve_filter(unescape(match.group(1) or match.group(2) or ""))
        if understood is not None and (understood.ours or understood.how != "display name"
                                       or understood.meshlab_2020 is not None and understood.meshlab_2020.implied):
            return True
    return False


def load_filter_script(self, file_path):
    """``MeshSet.load_filter_script``; a script naming our filters or old names is read and checked here too.

    pymeshlab loads such a script (ours, or one written for MeshLab 2020.09) without complaint
    and fails when applying it; it is also parsed and validated by
    :func:`.mlx.read_filter_script` (an invalid one raises :class:`.mlx.MlxScriptError` now,
    naming every problem), and :func:`apply_filter_script` then runs that.
    """
    result = _LOAD_SCRIPT(self, file_path)
    _LOADED.pop(self, None)
    if _needs_our_reader(file_path):
        _LOADED[self] = mlx.read_filter_script(file_path)
    return result


def apply_filter_script(self):
    """``MeshSet.apply_filter_script``: a script loaded by our reader runs through :func:`.mlx.run_filter_script`.

    Filters applied after the script was loaded are not appended to it then (pymeshlab
    appends them to its own script).
    """
    script = _LOADED.get(self)
    if script is None:
        return _APPLY_SCRIPT(self)
    mlx.run_filter_script(self, script)
    return None


def clear_filter_script(self):
    """``MeshSet.clear_filter_script``, forgetting a loaded script of ours too."""
    _LOADED.pop(self, None)
    return _CLEAR_SCRIPT(self)


def extend():
    """Put the wrappers in place of pymeshlab's functions (each keeps the original as ``pymeshlab_original``)."""
    for owner, name, wrapper, original in (
            (pymeshlab.MeshSet, "apply_filter", apply_filter, _APPLY_FILTER),
            (pymeshlab, "print_filter_parameter_list", print_filter_parameter_list, _PRINT_PARAMETERS),
            (pymeshlab.MeshSet, "load_filter_script", load_filter_script, _LOAD_SCRIPT),
            (pymeshlab.MeshSet, "apply_filter_script", apply_filter_script, _APPLY_SCRIPT),
            (pymeshlab.MeshSet, "clear_filter_script", clear_filter_script, _CLEAR_SCRIPT)):
        wrapper.pymeshlab_original = original
        setattr(owner, name, wrapper)
    listing_doors.extend()
