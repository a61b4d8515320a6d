"""pymeshlab integration, the only package that imports pymeshlab.

Registration of the filters as ``pymeshlab.MeshSet`` methods, MeshSet <-> array I/O,
pymeshlab's by-name doors extended to our filters, and MeshLab ``.mlx`` scripts (``mlx/``).
"""
from .registration import (FILTERS, apply_filter, clear_filter_history, filter_calls, filter_history, filter_list,
                           load_filter_kernels, print_filter_parameter_list)

__all__ = ["FILTERS", "apply_filter", "clear_filter_history", "filter_calls", "filter_history", "filter_list",
           "load_filter_kernels", "print_filter_parameter_list", "register_all"]


def register_all():
    """Register every filter on ``pymeshlab.MeshSet`` and extend pymeshlab's by-name doors (idempotent)."""
    from . import doors, filter_specs

    filter_specs.register_all()
    doors.extend()
