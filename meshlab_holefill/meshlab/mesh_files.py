"""Plain (V, F) arrays to and from pymeshlab: mesh files, meshes, MeshSets, and MeshLab's distance filter.

The evaluation layer works on arrays only; every pymeshlab call it needs (reading a mesh file
or a ``pymeshlab.Mesh``, building a MeshSet in a worker, MeshLab's point-to-surface distance)
goes through this module. Vertex arrays are float64 and face arrays int64 on the way out;
faces are handed to pymeshlab as int32, as it expects.
"""
from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np
import pymeshlab

__all__ = ["boolean_mesh", "cad_tessellation", "canonical_face_order", "generated_mesh", "is_mesh", "load_mesh",
           "mesh_arrays", "meshset_from_arrays", "point_to_surface_distances", "remeshed"]


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


def generated_mesh(generator, **params):
    """A mesh from one of MeshLab's generators (``create_cube``, ``create_cone``, ``create_sphere``, ...).

    Parameters
    ----------
    generator : str  the name of a pymeshlab filter starting with ``create_``
    **params : the generator's parameters (``create_cone(r0=1, r1=1, h=2)`` is a cylinder with sharp rims)

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    """
    if not generator.startswith("create_") or not hasattr(pymeshlab.MeshSet, generator):
        raise ValueError(f"'{generator}' is not one of MeshLab's create_* generators")
    ms = pymeshlab.MeshSet()
    getattr(ms, generator)(**params)
    return mesh_arrays(ms)


# The remeshing of :func:`remeshed`, run by a Python that imports pymeshlab and numpy only.
# MeshLab's isotropic remeshing reads memory it has not set: its result changes with glibc's
# MALLOC_PERTURB_ pattern, and in a long-running process with whatever ran before it (numba
# compiling kernels changed the benchmark's union mesh by one vertex). In a new process that
# does nothing else first, the memory it finds is the same each time.
_REMESH_SCRIPT = """
import io, sys
import numpy as np
import pymeshlab
args = np.load(io.BytesIO(sys.stdin.buffer.read()))
edge = float(args["edge_length"])
ms = pymeshlab.MeshSet()
ms.add_mesh(pymeshlab.Mesh(vertex_matrix=args["V"], face_matrix=args["F"]))
ms.meshing_surface_subdivision_midpoint(iterations=8, threshold=pymeshlab.PureValue(2.0 * edge))
ms.meshing_isotropic_explicit_remeshing(iterations=int(args["iterations"]), targetlen=pymeshlab.PureValue(edge),
                                        featuredeg=float(args["feature_angle"]),
                                        maxsurfdist=pymeshlab.PureValue(0.05 * edge))
out = io.BytesIO()
np.savez(out, V=ms.current_mesh().vertex_matrix(), F=ms.current_mesh().face_matrix())
sys.stdout.buffer.write(out.getvalue())
"""


def remeshed(V, F, edge_length, feature_angle=30.0, iterations=10):
    """MeshLab's isotropic explicit remeshing: triangles of about ``edge_length``, creases kept.

    Edges whose dihedral angle exceeds ``feature_angle`` stay where they are (MeshLab's
    ``featuredeg``); vertices are reprojected within 5 % of ``edge_length`` of the input.
    Long input edges are first split at their midpoints, so the remeshing starts from a fine
    sampling. The remeshing runs in a new Python process (about 0.3 s more): in this one
    its result depends on what the process did before (MeshLab's remeshing reads memory it
    has not set), and the test meshes built with it must be the same in every run.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    edge_length : float  target edge length (absolute)
    feature_angle : float  degrees
    iterations : int

    Returns
    -------
    V : (n', 3) float64
    F : (m', 3) int64

    Raises
    ------
    ValueError
        When ``edge_length`` is not positive.
    RuntimeError
        When the remeshing process fails (its error output is in the message).
    """
    if not edge_length > 0:
        raise ValueError(f"edge_length must be positive, got {edge_length}")
    given = io.BytesIO()
    np.savez(given, V=np.asarray(V, np.float64), F=np.asarray(F).astype(np.int32), edge_length=float(edge_length),
             feature_angle=float(feature_angle), iterations=int(iterations))
    # glibc's settings that fill new memory with a pattern are not passed on: they change the result.
    env = {key: value for key, value in os.environ.items() if not key.startswith(("MALLOC_", "GLIBC_TUNABLES"))}
    run = subprocess.run([sys.executable, "-c", _REMESH_SCRIPT], input=given.getvalue(), capture_output=True, env=env)
    if run.returncode != 0:
        raise RuntimeError(f"MeshLab's isotropic remeshing failed: {run.stderr.decode(errors='replace').strip()}")
    result = np.load(io.BytesIO(run.stdout))
    return np.asarray(result["V"], np.float64), np.asarray(result["F"], np.int64)


def cad_tessellation(V, F, faces):
    """The mesh tessellated as a CAD export is: MeshLab's quadric edge collapse with planar simplification.

    Flat faces end up covered by few large triangles and the creases and curved walls by small
    ones, as in an STL written by a CAD program (the triangles' shapes kept above quality 0.05).

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    faces : int  faces kept (fewer than m)

    Returns
    -------
    V : (n', 3) float64
    F : (faces, 3) int64
    """
    if not 0 < int(faces) < len(F):
        raise ValueError(f"faces must be between 1 and the mesh's {len(F) - 1}, got {faces}")
    ms = meshset_from_arrays(V, F)
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=int(faces), planarquadric=True, preservenormal=True,
                                                qualitythr=0.05)
    return mesh_arrays(ms)


def boolean_mesh(operation, first, second):
    """MeshLab's mesh booleans (libigl): the union, intersection or difference of two closed meshes.

    Parameters
    ----------
    operation : "union", "intersection" or "difference" (first minus second)
    first, second : ((n, 3) float, (m, 3) int) closed, consistently oriented meshes

    Returns
    -------
    V : (n', 3) float64
    F : (m', 3) int64
    """
    if operation not in ("union", "intersection", "difference"):
        raise ValueError(f"operation must be union, intersection or difference, got {operation!r}")
    ms = pymeshlab.MeshSet()
    for V, F in (first, second):
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, np.float64), face_matrix=np.asarray(F).astype(np.int32)))
    getattr(ms, f"generate_boolean_{operation}")(first_mesh=0, second_mesh=1)
    V, F = mesh_arrays(ms)
    return V, canonical_face_order(F)


def canonical_face_order(F):
    """The faces in a fixed order: each rotated to start at its smallest vertex (orientation kept), then sorted.

    MeshLab's booleans return the same vertices but their faces in an order that changes from
    run to run; the remeshing that follows depends on that order, so without this a creased
    test mesh (``evaluation.creased``) came out different in each run.

    Parameters
    ----------
    F : (m, 3) int

    Returns
    -------
    (m, 3) int64
    """
    F = np.asarray(F, np.int64).reshape(-1, 3)
    first = np.argmin(F, axis=1)
    F = np.take_along_axis(F, (first[:, None] + np.arange(3)) % 3, axis=1)
    return F[np.lexsort(F.T[::-1])]
