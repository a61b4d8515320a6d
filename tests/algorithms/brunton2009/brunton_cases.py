"""Shapes and hole contexts shared by the curve-unfolding tests (plain functions)."""

import numpy as np
import pymeshlab

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009.linear_motion import project_to_best_plane
from meshlab_holefill.core.holes import boundary_loops, hole_context

from conftest import cut_disks, grid, mesh_arrays


def mean_edge(P):
    return float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())


def sphere_cap_domain():
    """A sphere hole's context and its refined planar domain (points, faces in patch numbering)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    _, F, _ = cut_disks(V, F, [(0, 0, 1)], 0.6)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=2)
    points, Fp = tri.refine_planar(tri.scale_to_loop(project_to_best_plane(ctx.points)[0], ctx.points)[0],
                                  float(ctx.edge_scale.mean()))
    return ctx, points, Fp


def flat_disk_hole(n=9, radius=0.3):
    """HoleContext of a disk cut from the middle of a flat n x n grid (a 20-vertex staircase for n = 9)."""
    V, F = grid(n, n)
    V, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], radius)
    return hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)
