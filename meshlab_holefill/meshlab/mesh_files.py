"""Plain (V, F) arrays to and from pymeshlab: mesh files, meshes, MeshSets, and MeshLab's distance filter.

The evaluation layer works on arrays only; every pymeshlab call it needs (reading a mesh file
or a ``pymeshlab.Mesh``, building a MeshSet in a worker, MeshLab's point-to-surface distance)
goes through this module. Vertex arrays are float64 and face arrays int64 on the way out;
faces are handed to pymeshlab as int32, as it expects.
"""
from __future__ import annotations

import os

import numpy as np
import pymeshlab

__all__ = ["is_mesh", "load_mesh", "mesh_arrays", "meshset_from_arrays", "point_to_surface_distances"]


def load_mesh(path):
    """Read a mesh file (any format pymeshlab reads) into arrays.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.fspath(path))
    return mesh_arrays(ms)


def is_mesh(obj):
    """Is ``obj`` a ``pymeshlab.Mesh`` or a ``pymeshlab.MeshSet`` (something :func:`mesh_arrays` reads)?"""
    return isinstance(obj, (pymeshlab.Mesh, pymeshlab.MeshSet))


def mesh_arrays(mesh):
    """Vertices and faces of a ``pymeshlab.Mesh``, or of a MeshSet's current mesh.

    Parameters
    ----------
    mesh : pymeshlab.Mesh or pymeshlab.MeshSet

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    """
    if isinstance(mesh, pymeshlab.MeshSet):
        mesh = mesh.current_mesh()
    if not isinstance(mesh, pymeshlab.Mesh):
        raise TypeError(f"expected a pymeshlab.Mesh or MeshSet, got {type(mesh).__name__}")
    return np.asarray(mesh.vertex_matrix(), np.float64), np.asarray(mesh.face_matrix(), np.int64)


def meshset_from_arrays(V, F, label="mesh"):
    """A new MeshSet holding one mesh built from arrays (the current mesh).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    label : str  the layer's name

    Returns
    -------
    pymeshlab.MeshSet
    """
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, np.float64), face_matrix=np.asarray(F).astype(np.int32)),
                label)
    return ms


def point_to_surface_distances(X, V, F):
    """Unsigned distance from each point to the nearest point of a triangle surface.

    Exact: MeshLab's per-vertex distance filter (a uniform grid over the faces), with the
    points as a vertex-only mesh.

    Parameters
    ----------
    X : (q, 3) float64  query points
    V : (n, 3) float64
    F : (m, 3) int

    Returns
    -------
    (q,) float64
    """
    X, V = np.asarray(X, np.float64), np.asarray(V, np.float64)
    if len(X) == 0:
        return np.empty(0)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=X))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=np.asarray(F, np.int32)))
    both = np.concatenate([X, V])
    reach = 10.0 * max(float(np.linalg.norm(both.max(axis=0) - both.min(axis=0))), 1.0)
    ms.compute_scalar_by_distance_from_another_mesh_per_vertex(measuremesh=0, refmesh=1, signeddist=False,
                                                              maxdist=pymeshlab.PureValue(reach))
    return np.asarray(ms.mesh(0).vertex_scalar_array(), np.float64)
