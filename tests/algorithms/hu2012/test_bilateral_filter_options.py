"""Hu et al. Sec. III.D: the bilateral filter's quality guard, radius neighbourhood and fixed surrounding points."""
import numpy as np

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import grid


def _noisy_grid(noise, seed=1):
    V, F = grid(9, 9)
    V = V.astype(float)
    V[:, 2] = np.random.default_rng(seed).normal(scale=noise, size=len(V))
    movable = np.ones(len(V), bool)
    movable[boundary_loops(F)[0].vertices] = False
    return V, F, movable


def test_bilateral_guard_keeps_every_face_above_its_floor():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F, movable = _noisy_grid(0.1)
    h = 0.125  # grid spacing: sigma_c = 0.1 and sigma_s = 0.5 of it, as the filter's defaults
    q0 = triangle_quality(V, F)
    floor = np.minimum(q0, 0.3)
    plain = bilateral_filter(V, F, movable, 0.1 * h, 0.5 * h, 1)
    assert np.any(triangle_quality(plain, F) < floor - 1e-12)  # the unguarded step makes slivers here
    guarded = bilateral_filter(V, F, movable, 0.1 * h, 0.5 * h, 3, min_quality=0.3)
    # (three iterations: each one's floor is the quality before it, so the first one's bound holds throughout)
    assert np.all(triangle_quality(guarded, F) >= floor - 1e-12)
    assert np.abs(guarded - V).max() > 0.01  # the guard undoes offending moves only
    n0 = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n1 = np.cross(guarded[F[:, 1]] - guarded[F[:, 0]], guarded[F[:, 2]] - guarded[F[:, 0]])
    assert np.all(np.einsum("ij,ij->i", n0, n1) > 0)


def test_bilateral_default_is_unchanged_by_the_new_keywords():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F, movable = _noisy_grid(0.05)
    a = bilateral_filter(V, F, movable, 0.06, 0.1, 3)
    b = bilateral_filter(V, F, movable, 0.06, 0.1, 3, neighbourhood="ring", fixed_points=V[:4], min_quality=None)
    assert np.array_equal(a, b)


def test_radius_neighbourhood_reaches_the_fixed_surrounding_points():
    # A flat patch with fixed points lifted beside it: only Eq. 4's spatial neighbourhood sees them.
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F = grid(5, 5)
    V = V.astype(float)
    movable = np.zeros(len(V), bool)
    movable[12] = True  # the centre (0.5, 0.5)
    lifted = np.array([[0.5, 0.5 + 0.3, 0.05], [0.5, 0.5 - 0.3, 0.05]])
    ring = bilateral_filter(V, F, movable, 0.2, 1.0, 1, fixed_points=lifted)
    assert np.array_equal(ring, V)  # 1-ring neighbours are all at z = 0
    spatial = bilateral_filter(V, F, movable, 0.2, 1.0, 1, neighbourhood="radius", fixed_points=lifted)
    assert spatial[12, 2] > 0.005 and np.array_equal(np.delete(spatial, 12, 0), np.delete(V, 12, 0))
    # rho = 2 sigma_c below the grid spacing: no neighbour at all, nothing moves (the literal sigma_c = 0.1 reading).
    tiny = bilateral_filter(V, F, movable, 0.1, 1.0, 1, neighbourhood="radius", fixed_points=lifted)
    assert np.array_equal(tiny, V)
