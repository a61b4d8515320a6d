"""One mesh file through pymeshlab: load it, run a filter or a .mlx script, save it; job checks.

The batch machinery (``meshlab_holefill.batching``) never imports pymeshlab itself: it asks this
module to check a job before any work starts, to turn parameter values into plain data that
crosses to dask workers and back, and to process one file inside a worker.
"""
from __future__ import annotations

import os
import time

import numpy as np

from ..core.parallel import limit_workers

# Plain-data tags for pymeshlab's length values, so parameters pickle, hash and print as JSON.
_PERCENTAGE, _ABSOLUTE = "percentage", "absolute"


def encode_params(params):
    """Filter parameters as plain JSON data.

    Parameters
    ----------
    params : dict
        Keyword arguments of a filter; values may be ``pymeshlab.PercentageValue`` or
        ``pymeshlab.PureValue``.

    Returns
    -------
    dict
        The same keys; length values become ``{"percentage": p}`` / ``{"absolute": x}``,
        numpy scalars become Python numbers.
    """
    import pymeshlab

    out = {}
    for name, value in params.items():
        if isinstance(value, pymeshlab.PercentageValue):
            value = {_PERCENTAGE: float(value.value())}
        elif isinstance(value, pymeshlab.PureValue):
            value = {_ABSOLUTE: float(value.value())}
        elif isinstance(value, np.generic):
            value = value.item()
        elif isinstance(value, np.ndarray):
            value = value.tolist()
        out[name] = value
    return out


def decode_params(encoded):
    """Inverse of :func:`encode_params`: keyword arguments for ``apply_filter``."""
    import pymeshlab

    out = {}
    for name, value in encoded.items():
        if isinstance(value, dict) and set(value) == {_PERCENTAGE}:
            value = pymeshlab.PercentageValue(value[_PERCENTAGE])
        elif isinstance(value, dict) and set(value) == {_ABSOLUTE}:
            value = pymeshlab.PureValue(value[_ABSOLUTE])
        out[name] = value
    return out


def _tetrahedron():
    """A closed MeshSet with nothing to fill: a filter's parameters are checked on it at no cost."""
    import pymeshlab

    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F), "check")
    return ms


def check_filter(name, params):
    """Refuse an unknown filter or parameter before a batch starts.

    Our filters are run once on a closed tetrahedron (their parameters are validated exactly as
    in a real run, and there is no hole to fill); built-in filters have their parameter names
    checked against pymeshlab's list.

    Raises
    ------
    meshlab_holefill.FilterParameterError
        Unknown filter, unknown parameter, wrong type or out-of-range value.
    """
    import pymeshlab

    from ..errors import FilterParameterError
    from .registration import FILTERS, apply_filter, filter_list

    params = decode_params(params)
    if name in FILTERS:
        apply_filter(_tetrahedron(), name, **params)
        return
    if name not in pymeshlab.filter_list():
        raise FilterParameterError(
            f"unknown filter '{name}': not one of ours ({', '.join(filter_list())}) nor a pymeshlab filter")
    try:
        known = _tetrahedron().filter_parameter_values(name)
    except Exception:  # a filter whose defaults need more than a bare mesh: the run will tell
        return
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise FilterParameterError(
            f"filter '{name}' has no parameter {', '.join(map(repr, unknown))}; valid parameters: {', '.join(known)}")


def check_script(path):
    """Validate a MeshLab .mlx script (raises ``meshlab_holefill.MlxScriptError``); returns its step count."""
    from .mlx.script import read_filter_script

    return len(read_filter_script(path).steps)


def fill_file(input_path, output_path, filter=None, params=None, mlx=None, on_stage=None):
    """Load a mesh file, run one filter or a filter script on it and save the current layer.

    Parameters
    ----------
    input_path, output_path : str
        Any format pymeshlab reads; the output format follows the output's extension.
    filter : str, optional
        A filter name (ours or a pymeshlab built-in), run through ``apply_filter`` as ``fill`` does.
    params : dict, optional
        Its parameters as produced by :func:`encode_params`.
    mlx : str, optional
        A .mlx script run through ``run_filter_script`` (as ``meshlab-holefill run`` does) instead of ``filter``.
    on_stage : callable, optional
        Called with ``"load"``, ``"fill"`` and ``"save"`` as each stage starts.

    Returns
    -------
    dict
        ``result`` (the filter's result dictionary, or ``{"steps": [...]}`` with one per script
        filter), ``seconds`` (``load``, ``fill``, ``save``), ``vertices`` and ``faces`` of the
        saved mesh.
    """
    import pymeshlab

    from .mlx.script import run_filter_script
    from .registration import apply_filter

    stage = on_stage or (lambda name: None)
    seconds = {}
    t = time.perf_counter()
    stage("load")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.fspath(input_path))
    seconds["load"], t = time.perf_counter() - t, time.perf_counter()
    stage("fill")
    with limit_workers(1):  # the batch runs one file per core already
        if mlx is not None:
            result = {"steps": run_filter_script(ms, os.fspath(mlx))}
        else:
            result = apply_filter(ms, filter, **decode_params(params or {}))
    seconds["fill"], t = time.perf_counter() - t, time.perf_counter()
    stage("save")
    ms.save_current_mesh(os.fspath(output_path))
    seconds["save"] = time.perf_counter() - t
    m = ms.current_mesh()
    return {"result": result, "seconds": seconds, "vertices": m.vertex_number(), "faces": m.face_number()}
