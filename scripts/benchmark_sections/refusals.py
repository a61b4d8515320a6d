"""How fast each filter refuses a loop that outlines its whole mesh, and a scan's debris of many islands."""
from __future__ import annotations

import time

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.report.labels import short_label
from meshlab_holefill.meshlab.mesh_files import mesh_arrays


def spherical_cap(subdivisions=7, height=0.3):
    """A cap of the unit icosphere (``subdivisions`` levels), ``height`` high: an open scan-like sheet.

    Its area is 1.1 times the area its rim spans, so its one loop outlines the whole mesh.
    """
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdivisions)
    V, F = mesh_arrays(ms)
    keep = V[F].mean(axis=1)[:, 2] > 1 - height
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F[keep].astype(np.int32)))
    ms.meshing_remove_unreferenced_vertices()
    return mesh_arrays(ms)


def refusal_times(filters=("meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
                           "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution")):
    """Whole-run seconds of each filter on a mesh whose only loop it refuses: a spherical cap.

    The cap's rim outlines its whole component (an island outline), which the filters skip by
    default; the run's time is how long the refusal takes, mesh transfer included (each filter first
    runs once on a small cap, untimed, so imports and compiled kernels are loaded).
    """
    V, F = spherical_cap()
    small = spherical_cap(subdivisions=3)
    edges = None
    rows = []
    for name in filters:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=small[0], face_matrix=small[1].astype(np.int32)))
        getattr(ms, name)()
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
        t = time.perf_counter()
        res = getattr(ms, name)()
        seconds = time.perf_counter() - t
        hole = res["holes"][0]
        edges = hole.get("boundary_edges", edges)
        rows.append([f"`{short_label(name)}`", hole["status"], f"{seconds:.2f}", hole.get("reason", "").split(":")[0]])
    header = ["filter", "status", "whole run (s)", "reason"]
    return f"{len(F):,} faces, one loop of {edges} edges", header, rows


def with_debris(V, F, islands=20_000, seed=0):
    """The mesh and ``islands`` small squares of two triangles scattered around it (a range scan's debris)."""
    rng = np.random.default_rng(seed)
    size = 0.01 * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    corners = rng.uniform(V.min(axis=0) - 1.0, V.max(axis=0) + 1.0, (islands, 3))
    square = np.array([[0.0, 0, 0], [size, 0, 0], [size, size, 0], [0, size, 0]])
    debris_V = (corners[:, None, :] + square[None]).reshape(-1, 3)  # (4 islands, 3)
    debris_F = (len(V) + 4 * np.arange(islands)[:, None, None] + np.array([[0, 1, 2], [0, 2, 3]])).reshape(-1, 3)
    return np.concatenate([V, debris_V]), np.concatenate([F, debris_F])


def debris_times(islands=20_000, filters=("meshing_close_holes_min_angle_bilateral",
                                          "meshing_close_holes_curve_unfolding", "meshing_close_holes_lssvm_poisson",
                                          "meshing_close_holes_differential_evolution")):
    """Whole-run seconds of each filter on the spherical cap with ``islands`` debris squares, none of them a hole.

    Every loop outlines its component (the cap's rim, each square's border), so the filters
    refuse them all; the run is the loops' search, measures and classes and the mesh's
    transfer. MeshLab's Close Holes (all loops, ``maxholesize`` above the largest) runs on the
    same mesh for reference: it caps every loop it can.
    """
    V, F = with_debris(*spherical_cap(), islands=islands)
    rows = []
    for name in filters + ("meshing_close_holes",):
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
        params = {"maxholesize": 1000} if name == "meshing_close_holes" else {}
        t = time.perf_counter()
        res = getattr(ms, name)(**params)
        seconds = time.perf_counter() - t
        if name == "meshing_close_holes":
            rows.append([f"`{short_label(name)} (all holes)`", "–", "–", f"{seconds:.2f}"])
            continue
        skipped = sum(h.get("size_class") == "outline" for h in res["holes"])
        rows.append([f"`{short_label(name)}`", f"{skipped:,}/{len(res['holes']):,}",
                     f"{res['stage_seconds']['hole selection']:.2f}", f"{seconds:.2f}"])
    header = ["filter", "loops refused as outlines", "hole selection (s)", "whole run (s)"]
    return f"{len(F):,} faces, {islands:,} islands", header, rows
