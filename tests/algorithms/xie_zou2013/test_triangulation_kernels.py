"""The compiled kernels of the planar triangulation give bit for bit the numpy expressions they replace."""
import numpy as np

from meshlab_holefill.algorithms.xie_zou2013 import _triangulation_kernels as K


def _points_in_polygon_numpy(Q, X):
    a, b = Q, np.roll(Q, -1, axis=0)
    px, py = X[:, 0:1], X[:, 1:2]
    crosses = (a[None, :, 1] > py) != (b[None, :, 1] > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = a[None, :, 0] + (py - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (b[None, :, 1] - a[None, :, 1])
    return (np.count_nonzero(crosses & (px < xint), axis=1) % 2) == 1


def _distance_to_polygon_numpy(Q, X):
    a, b = Q[None, :, :], np.roll(Q, -1, axis=0)[None, :, :]
    d = b - a
    t = np.einsum("qkd,qkd->qk", X[:, None, :] - a, d) / np.maximum(np.einsum("qkd,qkd->qk", d, d), 1e-300)
    t = np.clip(t, 0, 1)
    closest = a + t[..., None] * d
    return np.linalg.norm(X[:, None, :] - closest, axis=2).min(axis=1)


def _polygons(rng, count=60):
    """Star-shaped polygons of 3 to 60 vertices at scales 1e-3 to 1e2, every third on a grid (horizontal
    edges, repeated coordinates), with points around them, on their vertices and on their vertices' lines."""
    for trial in range(count):
        k, q = int(rng.integers(3, 60)), int(rng.integers(1, 200))
        angle = np.sort(rng.random(k)) * 2.0 * np.pi
        Q = np.stack([np.cos(angle), np.sin(angle)], axis=1) * (1.0 + 0.5 * rng.random((k, 1)))
        Q *= 10.0 ** rng.integers(-3, 3)
        if trial % 3 == 0:
            Q = np.round(Q * 4.0) / 4.0
        X = (rng.random((q, 2)) * 3.0 - 1.5) * np.abs(Q).max()
        X[:min(q, k)] = Q[:min(q, k)]
        X[k:2 * k, 1] = Q[:len(X[k:2 * k]), 1]
        yield Q, X


def test_points_in_polygon_equals_numpy():
    for Q, X in _polygons(np.random.default_rng(1)):
        assert np.array_equal(K.points_in_polygon(Q, X), _points_in_polygon_numpy(Q, X))


def test_distance_to_polygon_equals_numpy():
    for Q, X in _polygons(np.random.default_rng(2)):
        assert K.distance_to_polygon(Q, X).tobytes() == _distance_to_polygon_numpy(Q, X).tobytes()
