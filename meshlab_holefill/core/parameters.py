"""Filter parameters: their specification (ParamSpec), validation and conversion, without pymeshlab.

A filter declares its parameters once, as a list of :class:`ParamSpec`; the MeshSet
methods, the array API, the command line and the ``.mlx`` reader all validate through
:func:`resolve_params`. Lengths relative to the mesh are given as :class:`Percentage`
(percent of the bounding-box diagonal); the pymeshlab layer turns
``pymeshlab.PercentageValue`` / ``pymeshlab.PureValue`` into these before validating.
"""
from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FilterParameterError

__all__ = ["FilterParameterError", "MLX_TYPES", "ParamSpec", "Percentage", "convert_param", "resolve_params"]

# MeshLab's RichParameter type for each kind of parameter (used when writing .mlx files).
MLX_TYPES = {"int": "RichInt", "float": "RichFloat", "bool": "RichBool", "enum": "RichEnum",
             "length": "RichAbsPerc", "string": "RichString"}


@dataclass(frozen=True)
class Percentage:
    """A length given as a percentage of the mesh's bounding-box diagonal (MeshLab's RichAbsPerc)."""

    value: float

    def __repr__(self):
        return f"PercentageValue({self.value:g})"


@dataclass(frozen=True)
class ParamSpec:
    """One filter parameter.

    Attributes
    ----------
    name : str
        Python keyword name.
    kind : {'int', 'float', 'bool', 'enum', 'length', 'string'}
        'length' accepts a float (absolute) or a :class:`Percentage` of the bounding-box
        diagonal, like MeshLab's RichAbsPerc parameters.
    default : Any
        For 'length', a default relative to the mesh is written ``Percentage(p)``.
    help : str
    minimum, maximum : float, optional
        Inclusive bounds for numbers (for 'length', on the absolute value).
    choices : tuple of str, optional
        Allowed values of an 'enum' (also accepted as their index, as in .mlx files).
    mlx_name : str, optional
        Parameter name in MeshLab .mlx files; defaults to ``name``.
    display : str, optional
        Short description shown in MeshLab's dialog (``description`` in .mlx).
    """

    name: str
    kind: str
    default: Any
    help: str
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple = ()
    mlx_name: str | None = None
    display: str | None = None

    @property
    def mlx(self):
        return self.mlx_name or self.name

    @property
    def mlx_type(self):
        return MLX_TYPES[self.kind]


def _is_bool(value):
    return isinstance(value, (bool, np.bool_))


def _finite(value, where):
    if not np.isfinite(value):
        raise FilterParameterError(f"{where}: must be finite, got {value!r}")
    return value


def convert_param(spec: ParamSpec, value, filter_name, bbox_diagonal=0.0):
    """Validate and convert one parameter value (lengths to absolute); raises FilterParameterError.

    Parameters
    ----------
    spec : ParamSpec
    value : object
        As given by the caller.
    filter_name : str
        Named in the error message.
    bbox_diagonal : float
        The mesh's bounding-box diagonal, the unit of a :class:`Percentage`.
    """
    where = f"filter '{filter_name}', parameter '{spec.name}'"
    kind = spec.kind
    if kind == "bool":
        if _is_bool(value):
            return bool(value)
        raise FilterParameterError(f"{where}: expected a bool, got {value!r}")
    if kind == "int":
        if _is_bool(value) or not isinstance(value, numbers.Integral):
            raise FilterParameterError(f"{where}: expected an int, got {value!r}")
        value = int(value)
    elif kind == "float":
        if _is_bool(value) or not isinstance(value, numbers.Real):
            raise FilterParameterError(f"{where}: expected a number, got {value!r}")
        value = _finite(float(value), where)
    elif kind == "length":
        if isinstance(value, Percentage):
            value = value.value / 100.0 * bbox_diagonal
        elif isinstance(value, numbers.Real) and not _is_bool(value):
            value = float(value)
        else:
            raise FilterParameterError(
                f"{where}: expected a number, pymeshlab.PureValue or pymeshlab.PercentageValue, got {value!r}")
        value = _finite(value, where)
    elif kind == "enum":
        if isinstance(value, numbers.Integral) and not isinstance(value, bool) and 0 <= value < len(spec.choices):
            return spec.choices[int(value)]
        if value not in spec.choices:
            raise FilterParameterError(f"{where}: expected one of {list(spec.choices)}, got {value!r}")
        return value
    elif kind == "string":
        if not isinstance(value, str):
            raise FilterParameterError(f"{where}: expected a string, got {value!r}")
        return value
    if spec.minimum is not None and value < spec.minimum:
        raise FilterParameterError(f"{where}: {value!r} is below the minimum {spec.minimum}")
    if spec.maximum is not None and value > spec.maximum:
        raise FilterParameterError(f"{where}: {value!r} is above the maximum {spec.maximum}")
    return value


def resolve_params(params, kwargs, filter_name, bbox_diagonal=0.0):
    """Validate keyword arguments against a filter's parameters and fill in defaults.

    Parameters
    ----------
    params : sequence of ParamSpec
    kwargs : dict
        As given by the caller.
    filter_name : str
    bbox_diagonal : float
        Unit of :class:`Percentage` lengths.

    Returns
    -------
    dict
        Every parameter by name, converted (lengths absolute).

    Raises
    ------
    FilterParameterError
        Unknown name (with the list of valid ones), wrong type, value out of range.
    """
    known = {p.name: p for p in params}
    unknown = sorted(set(kwargs) - set(known))
    if unknown:
        raise FilterParameterError(
            f"filter '{filter_name}' has no parameter {', '.join(map(repr, unknown))}; "
            f"valid parameters: {', '.join(known)}")
    return {name: convert_param(p, kwargs.get(name, p.default), filter_name, bbox_diagonal)
            for name, p in known.items()}
