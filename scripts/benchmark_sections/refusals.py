"""How fast each filter refuses a loop that outlines its whole mesh."""
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
