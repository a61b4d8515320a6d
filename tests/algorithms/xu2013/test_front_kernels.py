"""The compiled obstacle distance gives bit for bit the numpy function's minimum."""
import numpy as np

from meshlab_holefill.algorithms.xu2013._front_kernels import min_point_triangle_distance
from meshlab_holefill.algorithms.xu2013._front_predicates import point_triangle_distance


def test_min_point_triangle_distance_equals_numpy():
    rng = np.random.default_rng(0)
    V = rng.normal(size=(40, 3))
    F = rng.integers(0, 40, (60, 3))
    F[0] = [3, 3, 5]  # degenerate
    for trial in range(50):
        x = rng.normal(size=3)
        cand = np.unique(rng.integers(0, 60, 12))
        for radius in (0.05, 10.0):
            ref = min(float(point_triangle_distance(x, V[F[cand]]).min()), radius)
            got = min_point_triangle_distance(x, V, F, cand, radius)
            assert got == ref
    # a point on a triangle's plane inside it
    Vt = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert min_point_triangle_distance(np.array([0.2, 0.2, 0.5]), Vt, np.array([[0, 1, 2]]), np.array([0]), 9.0) == 0.5
