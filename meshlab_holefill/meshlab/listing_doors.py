"""pymeshlab's filter listings, extended to this package's filters.

``pymeshlab.filter_list()``, ``pymeshlab.print_filter_list()`` and
``MeshSet.filter_parameter_values(name)`` know only MeshLab's plugins. The wrappers here add
our filters after pymeshlab's own and pass every built-in name to pymeshlab unchanged
(:func:`extend`, called by :func:`.doors.extend`).
"""
from __future__ import annotations

import sys

import pymeshlab

from . import registration as registry


def _original(owner, name):
    current = getattr(owner, name)
    return getattr(current, "pymeshlab_original", current)


_FILTER_LIST = _original(pymeshlab, "filter_list")
_PRINT_FILTER_LIST = _original(pymeshlab, "print_filter_list")
_PARAMETER_VALUES = _original(pymeshlab.MeshSet, "filter_parameter_values")


def filter_list():
    """``pymeshlab.filter_list()``: pymeshlab's filters in its order, then ours (sorted)."""
    return list(_FILTER_LIST()) + registry.filter_list()


def print_filter_list():
    """``pymeshlab.print_filter_list()``: pymeshlab's listing, then ours in the same form."""
    from .mlx.names import _flush_c_stdio

    sys.stdout.flush()
    _PRINT_FILTER_LIST()
    _flush_c_stdio()
    print("meshlab_holefill filters - list of filter names:")
    for name in registry.filter_list():
        print(f"\t{name}")


def filter_parameter_values(self, filter_name):
    """``MeshSet.filter_parameter_values(name)``; for our filters, their defaults on the current mesh.

    Returns
    -------
    dict
        Python parameter name -> default value, as pymeshlab gives them for built-ins: a
        length given as a percentage comes as the absolute value on the current mesh.
    """
    if filter_name not in registry.FILTERS:
        return _PARAMETER_VALUES(self, filter_name)
    return registry.resolve_params(registry.FILTERS[filter_name], {}, self)


def extend():
    """Put the wrappers in place (each keeps pymeshlab's function as ``pymeshlab_original``)."""
    for owner, name, wrapper, original in (
            (pymeshlab, "filter_list", filter_list, _FILTER_LIST),
            (pymeshlab, "print_filter_list", print_filter_list, _PRINT_FILTER_LIST),
            (pymeshlab.MeshSet, "filter_parameter_values", filter_parameter_values, _PARAMETER_VALUES)):
        wrapper.pymeshlab_original = original
        setattr(owner, name, wrapper)
