"""A hole-filling algorithm as a MeshSet filter: the current layer to arrays, the pipeline, the filled layer back."""
from __future__ import annotations

import time

from ..core.pipeline import fill_mesh_holes
from .meshset_io import current_mesh_arrays, replace_current_mesh
from .progress import current_callback

__all__ = ["close_holes"]


def close_holes(ms, fill, params, *, algorithm_params=(), rings=3, prepare=None, warm_up=None,
                seconds_per_edge=None):
    """Run one hole-filling algorithm on every eligible hole of the MeshSet's current mesh.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
    fill, params, algorithm_params, rings, prepare, warm_up, seconds_per_edge
        As for :func:`meshlab_holefill.core.pipeline.fill_mesh_holes`.

    Returns
    -------
    dict
        The pipeline's result; ``seconds`` includes reading and writing the layer, and so does
        ``stage_seconds`` ("read layer" first, "write layer" last); ``mesh_id``
        is the filled layer's id: the current layer's, which keeps its place too (see
        :func:`.meshset_io.replace_current_mesh`), except in a MeshSet holding rasters, where the
        filled layer gets a new id, goes last and ``layer_note`` says why (and where another layer's own
        per-vertex normals would not survive pymeshlab's copy).

    Raises
    ------
    TypeError
        ``ms`` is not a MeshSet.
    ValueError
        Empty MeshSet, point cloud, NaN/inf coordinates, non-manifold edges
        (:class:`meshlab_holefill.MeshTopologyError`).
    """
    t_start = time.perf_counter()
    arrays = current_mesh_arrays(ms)
    read = time.perf_counter() - t_start
    filled, result = fill_mesh_holes(arrays, fill, params, algorithm_params=algorithm_params, rings=rings,
                                     prepare=prepare, warm_up=warm_up, seconds_per_edge=seconds_per_edge,
                                     progress=current_callback())
    mesh_id = arrays.mesh_id
    del arrays  # the filled arrays begin with the originals: one copy of the mesh is enough from here on
    filled.release_source()
    t_write = time.perf_counter()
    if filled.changed:
        mesh_id, note = replace_current_mesh(ms, filled.source, filled.V, filled.F, filled.vertex_attrs,
                                       filled.face_attrs, filled.wedge_texcoords, select_faces=filled.select_faces)
        if note:
            result["layer_note"] = note
    result["mesh_id"] = int(mesh_id)
    result["seconds"] = time.perf_counter() - t_start
    result["stage_seconds"] = {"read layer": read, **result["stage_seconds"],
                               "write layer": time.perf_counter() - t_write}
    return result
