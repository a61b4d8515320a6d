"""MeshLab parameter values: typed ``<Param>`` elements of .mlx scripts -> python values.

A ``<Param type="..." .../>`` element of a MeshLab filter script holds its value in
attributes that depend on its MeshLab type (``value``; ``r g b a`` for RichColor; ``x y z``
for RichPosition; ``val0``..``val15`` for RichMatrix44f). :func:`parse_value` reads each
type; :func:`builtin_param_value` and :func:`our_param_value` check the type against the
parameter it sets (a built-in's kind from :func:`mlx_names.builtin_param_kinds`, or our
``ParamSpec.kind``) and turn the value into the keyword argument for ``apply_filter``.
Every problem raises :class:`ParamValueError`, whose message says what is wrong.
"""
from __future__ import annotations

import os

import numpy as np
import pymeshlab

from .. import registration as registry
from .names import python_param_name
from ..registration import FilterParameterError

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
