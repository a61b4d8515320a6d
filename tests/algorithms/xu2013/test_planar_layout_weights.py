"""Xu et al. 2013, Sec. 3.4: the first Poisson solve of a patch built in the plane takes that plane's weights."""
import numpy as np

from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.algorithms.xu2013.advancing_front import advancing_front_triangulation
from meshlab_holefill.algorithms.xu2013.poisson_patch import harmonic_lift, normalized_cotangent_laplacian, planar_boundaries
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.geometry.laplacian import cotangent_weights

from conftest import grid


def cylinder_with_hole(radius=1.0, height=1.6, hole_angle=1.2):
    """A unit-radius open tube, (u, z) grid wrapped around the z axis, a disk cut from its side.

    The hole spans ``hole_angle`` radians of the tube (about 70 degrees), so the membrane
    spanning its loop lies well inside the tube.
    """
    V, F = grid(48, 25)
    u, z = V[:, 0] * (2.0 * np.pi * 47 / 48), V[:, 1] * height
    V = np.stack([radius * np.cos(u), radius * np.sin(u), z], axis=1)
    centre_u, centre_z = np.pi, height / 2
    C = np.stack([np.mean(u[F], axis=1), np.mean(z[F], axis=1)], axis=1)
    keep = np.hypot(radius * (C[:, 0] - centre_u), C[:, 1] - centre_z) > radius * hole_angle / 2
    return V, F[keep]


def developed_patch(ctx):
    """The advancing front on the loop's development, lifted: (X, F, layout)."""
    name, D = planar_boundaries(ctx)[0]
    assert name == "developed"
    new, F, _ = advancing_front_triangulation(D, ctx.forbidden_edges, 0.75, reference_normal=(0.0, 0.0, 1.0))
    layout = np.concatenate([D, new])
    return harmonic_lift(layout, F, ctx.points), F, layout


def hole_of(V, F):
    loops = [lp for lp in boundary_loops(F) if np.abs(V[lp.vertices, 2] - 0.8).max() < 0.7]
    assert len(loops) == 1
    return hole_context(V, F, loops[0], rings=xu.RINGS)


def test_the_development_of_a_tube_hole_gives_its_patch_the_tube_s_weights_and_shape():
    V, F = cylinder_with_hole()
    ctx = hole_of(V, F)
    X, G, layout = developed_patch(ctx)
    fixed = np.arange(len(X)) < ctx.size
    off_tube = {}
    for name, weights_from in (("lift", None), ("layout", layout)):
        Y, _, info = xu.poisson_reposition(X, G, fixed, None, boundary_ctx=ctx, layout=weights_from)
        assert info["poisson_solves"] == 1 and not info["poisson_rejected"]
        off_tube[name] = np.abs(np.linalg.norm(Y[ctx.size:, :2], axis=1) - 1.0).mean()
    membrane = np.abs(np.linalg.norm(X[ctx.size:, :2], axis=1) - 1.0).mean()
    # The lift is a membrane inside the tube, the solve bulges it out onto the tube, and with the
    # layout's weights (the tube's own: a tube develops onto the plane without distortion) it
    # lands closer (0.0083 -> 0.0071 mean distance from the tube, unit radius).
    assert membrane > 0.04
    assert off_tube["lift"] < 0.25 * membrane
    assert off_tube["layout"] < 0.9 * off_tube["lift"]


def test_solve_with_a_layout_uses_the_layout_s_cotangents_for_the_patch_faces_only():
    V, F = cylinder_with_hole()
    ctx = hole_of(V, F)
    X, G, layout = developed_patch(ctx)
    free = np.arange(len(X)) >= ctx.size
    rows, allX, allF = xu.boundary_rows(X, G, ctx)
    rhs, rhs_rows = np.zeros((free.sum(), 3)), np.zeros((len(rows), 3))
    # Own cotangents passed explicitly: the same system, bit for bit.
    plain = xu.solve_poisson(X, G, free, rhs, (rows, allX, allF, rhs_rows))
    same = xu.solve_poisson(X, G, free, rhs, (rows, allX, allF, rhs_rows), cotangents=cotangent_weights(X, G))
    assert np.array_equal(plain, same)
    # The layout's: the least-squares solution of the system whose patch rows have the layout's weights.
    got = xu.solve_poisson(X, G, free, rhs, (rows, allX, allF, rhs_rows), cotangents=cotangent_weights(layout, G))
    C = np.concatenate([cotangent_weights(layout, G), cotangent_weights(allX, allF[len(G):])])
    L = normalized_cotangent_laplacian(allX, allF, cotangents=C).toarray()
    free_idx = np.flatnonzero(free)
    known = np.setdiff1d(np.arange(len(allX)), free_idx)
    R = np.concatenate([free_idx, rows])
    want = np.linalg.lstsq(L[np.ix_(R, free_idx)], -L[np.ix_(R, known)] @ allX[known], rcond=None)[0]
    assert np.allclose(got, want, atol=1e-9)
