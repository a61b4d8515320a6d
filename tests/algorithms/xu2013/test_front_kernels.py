"""The compiled obstacle distance gives bit for bit the numpy function's minimum; the scans over
the alive nodes filter by Python's squared distance and break ties by id whatever their order."""
import numpy as np

from meshlab_holefill.algorithms.xu2013 import _front_kernels as K
from meshlab_holefill.algorithms.xu2013._front_kernels import min_point_triangle_distance
from meshlab_holefill.algorithms.xu2013._front_predicates import point_triangle_distance
from meshlab_holefill.algorithms.xu2013.advancing_front import TWO


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


def _python_beyond(X, Y, r2):
    return not (sum((float(X[i]) - float(Y[i])) ** 2 for i in range(3)) <= r2)


def test_scan_distance_filter_is_pythons_squared_distance():
    rng = np.random.default_rng(1)
    Y = rng.normal(size=3)
    for trial in range(2000):
        X = Y + rng.normal(size=3) * 10.0 ** rng.uniform(-3, 1)
        # r2 at the point's own squared distance (and a few ulps around it): the boundary cases
        d = sum((float(X[i]) - float(Y[i])) ** 2 for i in range(3))
        for r2 in (d, np.nextafter(d, 0.0), np.nextafter(d, np.inf), d * (1 + 1e-12), 0.5 * d, 2.0 * d):
            expected = _python_beyond(X, Y, r2)
            assert K._beyond_xyz(X[0], X[1], X[2], Y, r2, TWO) == expected
            assert K._beyond(X, Y, r2, TWO) == expected


def test_merge_target_breaks_distance_ties_by_id_in_any_scan_order():
    # vertices 2 and 5 at the same distance from pos; 7 farther; 1 is v (skipped)
    P = np.zeros((8, 3))
    P[1] = [0.0, 0.0, 0.0]
    P[2] = [0.3, 0.0, 0.0]
    P[5] = [0.0, 0.3, 0.0]
    P[7] = [0.0, 0.0, 0.4]
    pos = np.zeros(3)
    nv = np.arange(8, dtype=np.int64)
    nf = np.zeros(8, np.int64)
    rng = np.random.default_rng(2)
    for trial in range(20):
        alive = rng.permutation(np.array([1, 2, 5, 7], np.int64))
        assert K.merge_target(pos, 0.5, 1, -1, -1, 0, P, nv, nf, alive, len(alive), 1.0, TWO) == 2
        assert K.merge_target(pos, 0.5, 1, 2, -1, 0, P, nv, nf, alive, len(alive), 1.0, TWO) == 5
        assert K.merge_target(pos, 0.35, 1, 2, 5, 0, P, nv, nf, alive, len(alive), 1.0, TWO) == -1
