"""geometry.development: the curvature a hole's loop encloses, by Gauss-Bonnet."""
import numpy as np
import pymeshlab
import pytest
from hypothesis import assume, given, settings, strategies as st

from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.geometry.development import boundary_gap_angles, enclosed_curvature
from meshlab_holefill.geometry.quality import corner_angles


@pytest.fixture(scope="module")
def sphere():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=4)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def angle_defects(V, F):
    """2 pi minus the corner angles at every vertex of a closed mesh."""
    return 2 * np.pi - np.bincount(F.ravel(), weights=corner_angles(V, F).ravel(), minlength=len(V))


def loop_curvature(V, F, loop=None):
    loop = boundary_loops(F)[0] if loop is None else loop
    ctx = hole_context(V, F, loop, rings=1)
    return enclosed_curvature(boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)), loop


@settings(max_examples=25, deadline=None)
@given(theta=st.floats(0.1, np.pi - 0.1), phi=st.floats(0, 2 * np.pi), radius=st.floats(0.2, 1.2))
def test_a_cap_s_curvature_is_the_angle_defect_of_the_vertices_it_removes(sphere, theta, phi, radius):
    V, F = sphere
    centre = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    removed = np.linalg.norm(V[F].mean(axis=1) - centre, axis=1) < radius
    kept = F[~removed]
    loops = boundary_loops(kept)
    assume(removed.sum() > 1 and len(loops) == 1)
    on_loop = np.zeros(len(V), bool)
    on_loop[loops[0].vertices] = True
    inside = np.setdiff1d(np.unique(F[removed]), np.flatnonzero(on_loop))
    assume(len(np.unique(loops[0].vertices)) == len(loops[0].vertices))
    K, _ = loop_curvature(V, kept)
    # Discrete Gauss-Bonnet: exactly the angle defects of the vertices inside the hole and on its loop.
    assert K == pytest.approx(angle_defects(V, F)[np.union1d(inside, loops[0].vertices)].sum(), abs=1e-9)
    assert K > 0


def test_a_developable_surface_encloses_no_curvature_across_its_crease():
    # A grid folded by 90 degrees along x = 0.5 (a crease), a disc cut across the fold.
    n = 21
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    u, v = u.ravel(), v.ravel()
    V = np.stack([np.minimum(u, 0.5), v, np.maximum(u - 0.5, 0.0)], axis=1)
    i = np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]
    i = i.ravel()
    F = np.concatenate([np.stack([i, i + 1, i + n + 1], 1), np.stack([i, i + n + 1, i + n], 1)])
    C = np.stack([u, v], 1)[F].mean(axis=1)
    kept = F[np.linalg.norm(C - 0.5, axis=1) > 0.22]
    (loop,) = [lp for lp in boundary_loops(kept) if len(lp) < 60]  # not the grid's border
    K, _ = loop_curvature(V, kept, loop)
    assert len(loop) > 20
    assert abs(K) < 1e-9
