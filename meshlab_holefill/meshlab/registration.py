"""Filter and parameter specifications, validation, registration on pymeshlab.MeshSet, dispatch.

Every filter of the package is declared once, as a :class:`FilterSpec`; from that one
declaration come the ``MeshSet`` method, the parameter checks, the ``filters`` listing of
the command line, and the MeshLab ``.mlx`` names.
"""
from __future__ import annotations

import importlib
import weakref
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pymeshlab

from ..core import parameters as _parameters
from ..core.parameters import MLX_TYPES, FilterParameterError, ParamSpec, Percentage  # noqa: F401 (re-exported)
from ..core.kernel_cache import refresh_kernel_cache_once
from .exceptions import pymeshlab_filter_list, raises_meshset_errors
from .meshset_io import current_mesh_exists, filter_record

def shown_value(value):
    """A parameter value as a user wrote it (pymeshlab's value types have no readable repr)."""
    if isinstance(value, (pymeshlab.PureValue, pymeshlab.PercentageValue)):
        return f"{type(value).__name__}({value.value():g})"
    if isinstance(value, pymeshlab.Color):
        return f"Color({value.red()}, {value.green()}, {value.blue()}, {value.alpha()})"
    if isinstance(value, np.ndarray):
        return repr(value.tolist())
    return repr(value)


def as_core_value(value):
    """pymeshlab's length values as the core's: PercentageValue -> Percentage, PureValue -> float."""
    if isinstance(value, pymeshlab.PercentageValue):
        return Percentage(value.value())
    if isinstance(value, pymeshlab.PureValue):
        return float(value.value())
    return value


@dataclass
class FilterSpec:
    """One filter: names, parameters and the function that runs it on a MeshSet.

    ``run(ms, **resolved_params) -> dict`` receives validated parameters (lengths already
    absolute) and returns the pymeshlab-style result dictionary.
    """

    name: str
    display_name: str
    description: str
    params: list
    run: Callable
    paper: str = ""
    extra: dict = field(default_factory=dict)

    def param(self, name):
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    def defaults(self):
        return {p.name: p.default for p in self.params}


FILTERS: dict[str, FilterSpec] = {}


def _bbox_diagonal(ms):
    if ms.mesh_number() == 0 or not current_mesh_exists(ms):
        return 0.0
    return float(ms.current_mesh().bounding_box().diagonal())


def convert_param(spec: ParamSpec, value, filter_name, ms):
    """Validate and convert one parameter value (lengths to absolute); raises FilterParameterError."""
    return _parameters.convert_param(spec, as_core_value(value), filter_name, _bbox_diagonal(ms) if ms else 0.0)


def parse_text_value(text, percentages=True):
    """A parameter value written as text (command line, ``name:param=value``): bool, int, float, string.

    With ``percentages``, ``"5%"`` becomes ``pymeshlab.PercentageValue(5)``; otherwise it stays text.
    """
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    if percentages and text.endswith("%"):
        try:
            return pymeshlab.PercentageValue(float(text[:-1]))
        except ValueError:
            pass
    return text


def resolve_params(spec: FilterSpec, kwargs: dict, ms=None):
    """Validate keyword arguments against a filter spec and fill in defaults (see core.parameters).

    Raises
    ------
    FilterParameterError
        Unknown name (with the list of valid ones), wrong type, value out of range.
    """
    values = {p.name: as_core_value(p.default) for p in spec.params}
    values.update({name: as_core_value(value) for name, value in kwargs.items()})
    return _parameters.resolve_params(spec.params, values, spec.name, _bbox_diagonal(ms) if ms is not None else 0.0)


def register(spec: FilterSpec):
    """Add a filter to the registry and as a method of pymeshlab.MeshSet."""
    FILTERS[spec.name] = spec

    def method(self, **kwargs):
        return apply_filter(self, spec.name, **kwargs)

    method.__name__ = spec.name
    method.__qualname__ = f"MeshSet.{spec.name}"
    method.__doc__ = filter_help(spec.name)
    setattr(pymeshlab.MeshSet, spec.name, method)
    return spec


def filter_list():
    """Names of the filters this package adds (sorted)."""
    return sorted(FILTERS)


def load_filter_kernels(name):
    """Load the compiled kernels of our filter ``name`` in this process (its algorithm's ``WARM_UP``).

    They are compiled on first use and cached on disk; loading them takes a few tenths of a
    second per process. Does nothing for MeshLab's own filters and for algorithms without kernels.
    """
    spec = FILTERS.get(name)
    if spec is None or "module" not in spec.extra:
        return
    warm_up = getattr(importlib.import_module(spec.extra["module"]), "WARM_UP", None)
    if warm_up is not None:
        refresh_kernel_cache_once()
        warm_up()


def is_builtin_filter(name):
    return name in set(pymeshlab_filter_list())


def filter_help(name):
    """Description and parameter table of one of our filters, as text."""
    spec = FILTERS[name]
    lines = [f"{spec.display_name}", "", spec.description]
    if spec.paper:
        lines += ["", f"Reference: {spec.paper}"]
    lines += ["", "Parameters", "----------"]
    for p in spec.params:
        default = p.default
        if isinstance(default, pymeshlab.PercentageValue):
            default = f"PercentageValue({default.value():g})"
        rng = ""
        if p.kind == "enum":
            rng = f" one of {list(p.choices)}"
        elif p.minimum is not None or p.maximum is not None:
            rng = f" in [{p.minimum if p.minimum is not None else '-inf'}, {p.maximum if p.maximum is not None else 'inf'}]"
        lines.append(f"{p.name} : {p.kind}, default {default!r}{rng}")
        lines.append(f"    {p.help}")
    return "\n".join(lines)


@raises_meshset_errors
def print_filter_parameter_list(name):
    """Print the parameters of a filter (ours, or pymeshlab's for a built-in name)."""
    if name in FILTERS:
        print(filter_help(name))
    elif is_builtin_filter(name):
        pymeshlab.print_filter_parameter_list(name)
    else:
        raise FilterParameterError(f"unknown filter '{name}'")


@raises_meshset_errors
def apply_filter(ms, name, **kwargs):
    """Run a filter by name: one of ours, or any pymeshlab built-in filter.

    Parameters are validated before anything runs. Every call through this door is
    recorded on the MeshSet for :func:`meshlab_holefill.save_filter_script`.

    Returns
    -------
    dict
        The filter's result dictionary (built-in filters that return nothing give {}).
    """
    global _DEPTH
    if not isinstance(ms, pymeshlab.MeshSet):
        raise TypeError(f"apply_filter: expected a pymeshlab.MeshSet, got {type(ms).__name__}")
    if ms.mesh_number() > 0 and not current_mesh_exists(ms):
        # pymeshlab's own filters crash the process on a dangling current mesh id (DESIGN.md)
        raise ValueError(f"filter '{name}': the MeshSet's current mesh does not exist; call set_current_mesh "
                         "with an existing id")
    if name in FILTERS:
        spec = FILTERS[name]
        params = resolve_params(spec, kwargs, ms)
        call = FilterCall(name, dict(kwargs), resolved=dict(params), bbox_diagonal=_bbox_diagonal(ms))
        _DEPTH += 1
        try:
            result = spec.run(ms, **params)
        finally:
            _DEPTH -= 1
    elif is_builtin_filter(name):
        defaults = _parameter_values(ms, name) if _DEPTH == 0 else None
        _check_builtin_values(name, kwargs, defaults)
        result = getattr(pymeshlab.MeshSet, name)(ms, **kwargs)
        result = {} if result is None else result
        call = FilterCall(name, dict(kwargs), defaults=defaults)
        if _DEPTH == 0:
            call.meshlab_record = filter_record(ms)  # pymeshlab's record just after the call
    else:
        raise FilterParameterError(f"unknown filter '{name}': not one of ours ({', '.join(filter_list())}) "
                                   "nor a pymeshlab filter")
    if _DEPTH == 0:  # a filter of ours calling apply_filter inside is not a step of the user's script
        _HISTORY.setdefault(ms, []).append(call)
    return result


@dataclass
class FilterCall:
    """One filter applied through :func:`apply_filter`, as recorded for writing .mlx scripts.

    Attributes
    ----------
    name : str
        Python filter name.
    kwargs : dict
        The keyword arguments as given.
    resolved : dict or None
        Our filters: every parameter after validation (defaults filled in, lengths absolute).
    bbox_diagonal : float
        Our filters: bounding-box diagonal of the current mesh before the call (MeshLab writes
        it as the ``max`` of RichAbsPerc parameters).
    meshlab_record : bytes or None
        Built-in filters: pymeshlab's own record of the MeshSet's filters just after the call
        (.mlx text; its last filter holds every parameter with its MeshLab name, type and
        value), see :func:`meshlab_holefill.meshlab.mlx.parse.last_recorded_filter`.
    defaults : dict or None
        Built-in filters: ``ms.filter_parameter_values(name)`` just before the call, the
        mesh-dependent defaults at full precision (pymeshlab's record has 6 digits).
    """

    name: str
    kwargs: dict
    resolved: dict | None = None
    bbox_diagonal: float = 0.0
    meshlab_record: Any = None
    defaults: dict | None = None


def _check_builtin_values(name, kwargs, defaults):
    """Refuse what pymeshlab would answer with an unreadable C++ cast error (a string for a number)."""
    if not defaults:
        return
    for key, value in kwargs.items():
        if key not in defaults:
            raise FilterParameterError(f"filter '{name}': unknown parameter '{key}' (known: {', '.join(defaults)})")
        default = defaults[key]
        numeric = isinstance(value, (bool, int, float, np.number, pymeshlab.PercentageValue, pymeshlab.PureValue))
        if isinstance(default, (bool, int, float)) and not numeric:
            kind = "a bool" if isinstance(default, bool) else "a number"
            raise FilterParameterError(f"filter '{name}', parameter '{key}': expected {kind}, got {shown_value(value)}")


def _parameter_values(ms, name):
    try:
        return ms.filter_parameter_values(name)
    except Exception:  # e.g. a missing component: the filter itself will say so
        return None


# The filters applied to each MeshSet through apply_filter, for writing .mlx scripts. Keyed
# by the MeshSet itself (weakly): a log dies with its MeshSet, and a new MeshSet that gets a
# dead one's id() starts with an empty log.
_HISTORY: "weakref.WeakKeyDictionary[pymeshlab.MeshSet, list[FilterCall]]" = weakref.WeakKeyDictionary()
_DEPTH = 0  # > 0 while one of our filters runs


def filter_calls(ms):
    """List of :class:`FilterCall` applied to ``ms`` through this package, oldest first."""
    return list(_HISTORY.get(ms, []))


def filter_history(ms):
    """List of (filter name, keyword arguments) applied to ``ms`` through this package."""
    return [(call.name, dict(call.kwargs)) for call in _HISTORY.get(ms, [])]


def clear_filter_history(ms):
    """Forget the filters recorded for ``ms``."""
    _HISTORY.pop(ms, None)
