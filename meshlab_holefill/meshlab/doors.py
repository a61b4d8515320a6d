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

import weakref

import pymeshlab

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


def _names_our_filter(path):
    """Does the script at ``path`` name one of our filters (python or MeshLab display name)?"""
    try:
        with open(path, "rb") as fh:
            text = fh.read().decode("utf-8", "replace")
    except OSError:
        return False
    names = {spec.name for spec in registry.FILTERS.values()} | {spec.display_name for spec in registry.FILTERS.values()}
    return any(f'"{name}"' in text for name in names)


def load_filter_script(self, file_path):
    """``MeshSet.load_filter_script``; a script naming our filters is read and checked here too.

    pymeshlab loads such a script without complaint; it is also parsed and validated by
    :func:`.mlx.read_filter_script` (an invalid one raises :class:`.mlx.MlxScriptError` now,
    naming every problem), and :func:`apply_filter_script` then runs that.
    """
    result = _LOAD_SCRIPT(self, file_path)
    _LOADED.pop(self, None)
    if _names_our_filter(file_path):
        _LOADED[self] = mlx.read_filter_script(file_path)
    return result


def apply_filter_script(self):
    """``MeshSet.apply_filter_script``: a loaded script naming our filters runs through :func:`.mlx.run_filter_script`.

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
