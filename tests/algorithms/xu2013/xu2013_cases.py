"""Shared cases of the Xu et al. 2013 tests: holes cut from spheres and grids, and a folding Poisson solve."""
import numpy as np
import pymeshlab

from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.geometry.quality import face_areas

from conftest import cut_disks, mesh_arrays

UP = (0.0, 0.0, 1.0)


def sphere_hole(center=(0.0, 0.0, 1.0), radius=0.45, subdiv=4):
    """Unit sphere (pymeshlab) with the faces near ``center`` removed: (V, F, removed faces)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    V, F = mesh_arrays(ms)
    return cut_disks(V, F, np.asarray([center], float), radius)


def context_of(V, F, inside=None, rings=xu.RINGS):
    """HoleContext of the mesh's only hole, or of the loop whose vertices all satisfy ``inside``."""
    loops = boundary_loops(F)
    if inside is not None:
        loops = [lp for lp in loops if inside(V[lp.vertices]).all()]
    assert len(loops) == 1
    return hole_context(V, F, loops[0], rings=rings)


def surface_area(V, F):
    return float(face_areas(V, F).sum())


def fold_case():
    """Planar patch (8 boundary vertices, 3 inner) and a solve target moving inner vertex 10 past edge (3, 8).

    Returns X (initial patch), F (its Delaunay faces), T (the target: triangle (3, 8, 10) turned
    over, a quad whose other diagonal (10, 4) is sound) and a stand-in HoleContext for the swaps.
    """
    from types import SimpleNamespace

    from scipy.spatial import Delaunay

    k = 8
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    X = np.concatenate([np.stack([np.cos(t), np.sin(t), 0.0 * t], axis=1),
                        [[-0.35, -0.2, 0.0], [0.35, -0.2, 0.0], [0.0, 0.4, 0.0]]])
    F = Delaunay(X[:, :2]).simplices.astype(np.int64)
    A = X[F]
    cw = np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0])[:, 2] < 0
    F[cw] = F[cw][:, [0, 2, 1]]
    T = X.copy()
    T[10] = X[10] + 1.2 * (0.5 * (X[3] + X[8]) - X[10])
    return X, F, T, SimpleNamespace(size=k, forbidden_edges=np.zeros((0, 2), np.int64))
