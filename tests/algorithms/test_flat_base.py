"""A model scanned without its base: the lowest part cut off by a plane, one large, nearly planar loop.

The surface meets the missing base at a steep angle, and a border cut through triangles
zigzags in small notches; every filter must close it without the patch crossing itself or
the mesh.
"""
import numpy as np
import pytest

from meshlab_holefill.core.holes import boundary_loops

from conftest import assert_filled_cleanly, mesh_arrays, meshset_from_arrays, sample

FILTERS = ["meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
           "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution"]


@pytest.fixture(scope="module")
def bunny_without_base():
    """bunny.obj without the faces that reach into the lowest tenth of its height."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny.obj"))
    V, F = mesh_arrays(ms)
    height = V[:, 1]
    F = F[V[F, 1].min(axis=1) > height.min() + 0.1 * np.ptp(height)]
    loop = max(boundary_loops(F), key=len)
    P = V[loop.vertices]
    assert len(loop) > 200 and np.ptp(P[:, 1]) < 0.02 * np.ptp(P[:, [0, 2]], axis=0).max()  # nearly planar
    return V, F, len(loop)


@pytest.mark.parametrize("name", FILTERS)
def test_a_cut_off_base_is_closed_cleanly(bunny_without_base, name):
    V, F, edges = bunny_without_base
    ms = meshset_from_arrays(V, F)
    res = getattr(ms, name)(maxholesize=edges + 1, workers=1)
    assert res["failed_holes"] == 0 and res["closed_holes"] == len(boundary_loops(F))
    V1, F1 = mesh_arrays(ms)
    assert_filled_cleanly(V, F, V1, F1, faces_kept=name != "meshing_close_holes_lssvm_poisson")
