"""The compiled minimum-angle triangulation against its Python reference (the faces must be the same)."""
import importlib

import numpy as np
import pytest

from meshlab_holefill.algorithms.hu2012 import _min_angle_kernels as K
from meshlab_holefill.core.holes import hole_context, vertex_face_incidence
from meshlab_holefill.errors import HoleFillError

M = importlib.import_module("meshlab_holefill.algorithms.hu2012.min_angle_triangulation")


def _same_as_python(P, N, forbidden=()):
    """The kernel's answer is the greedy Python code's faces, or UNSURE; FAILED exactly where it raises
    (and then the filter's triangulation is the Python search's)."""
    faces, status = M._compiled_faces(P, N, forbidden)
    try:
        expected = M.greedy_ear_faces(P, N, forbidden)
    except HoleFillError:
        assert status in (K.FAILED, K.UNSURE)
        try:
            searched = M.min_angle_triangulation_python(P, N, forbidden)
        except HoleFillError:
            searched = None
        if searched is None:
            with pytest.raises(HoleFillError):
                M.min_angle_triangulation(P, N, forbidden)
        else:
            np.testing.assert_array_equal(M.min_angle_triangulation(P, N, forbidden), searched)
        return status
    if status == K.OK:
        np.testing.assert_array_equal(faces, expected)
    else:
        assert status == K.UNSURE
    np.testing.assert_array_equal(M.min_angle_triangulation(P, N, forbidden), expected)
    np.testing.assert_array_equal(M.min_angle_triangulation_python(P, N, forbidden), expected)
    return status


def _jagged_loop(rng, k):
    """A star-shaped, bumpy, jagged loop in 3D (counter-clockwise from +z) with noisy normals."""
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    r = 1.0 + 0.4 * rng.uniform(-1, 1, k) * rng.integers(0, 2, k)
    P = np.stack([r * np.cos(t), r * np.sin(t), 0.3 * np.sin(3 * t) + 0.05 * rng.normal(size=k)], axis=1)
    N = np.array([0.0, 0.0, 1.0]) + 0.4 * rng.normal(size=(k, 3))
    return P * 10.0 ** rng.integers(-3, 4), N / np.linalg.norm(N, axis=1, keepdims=True)


def test_compiled_triangulation_matches_python_on_random_loops():
    rng = np.random.default_rng(0)
    statuses = []
    for _ in range(300):
        k = int(rng.integers(3, 60))
        P, N = _jagged_loop(rng, k)
        forbidden = rng.integers(0, k, (int(rng.integers(0, 3)), 2))
        statuses.append(_same_as_python(P, N, forbidden))
    assert statuses.count(K.OK) >= 250  # the Python fallback is for the rare undecided comparison


def test_compiled_triangulation_matches_python_on_regular_and_collinear_loops():
    # Exact ties of angles (regular polygons, squares with collinear border vertices) are broken by
    # index, as the stable sort of the Python code does.
    up = np.tile([0.0, 0.0, 1.0], (24, 1))
    t = np.arange(24) * 2 * np.pi / 24
    assert _same_as_python(np.stack([np.cos(t), np.sin(t), 0 * t], axis=1), up) == K.OK
    side = np.arange(6, dtype=float)
    square = np.concatenate([np.stack([side, 0 * side], 1), np.stack([6 + 0 * side, side], 1),
                             np.stack([6 - side, 6 + 0 * side], 1), np.stack([0 * side, 6 - side], 1)])
    square = np.concatenate([square, np.zeros((24, 1))], axis=1)
    assert _same_as_python(square, up) in (K.OK, K.UNSURE)


def test_compiled_triangulation_matches_python_on_the_face_scan_holes(face_scan):
    V, F, loops = face_scan
    incidence = vertex_face_incidence(F, len(V))
    for i, loop in enumerate(loops):
        if len(loop.vertices) > 300:
            continue  # the outline
        ctx = hole_context(V, F, loop, incidence, rings=2, index=i)
        _same_as_python(ctx.points, ctx.loop_normals, ctx.forbidden_edges)


def test_an_undecided_normal_test_falls_back_to_python():
    # Neighbour normals exactly at the 45 degree threshold: the kernel leaves the decision to Python.
    c = np.cos(np.radians(45.0))
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    N = np.array([[0, 0, 1], [0, c, c], [0, 0, 1], [0, c, c]], float)
    N[1] /= np.linalg.norm(N[1])
    N[3] = N[1]
    faces, status = M._compiled_faces(P, N, ())
    assert status == K.UNSURE
    np.testing.assert_array_equal(M.min_angle_triangulation(P, N), M.min_angle_triangulation_python(P, N))


def test_errors_are_raised_as_by_the_python_code():
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    up = np.tile([0.0, 0.0, 1.0], (3, 1))
    with pytest.raises(HoleFillError, match="duplicate an existing edge"):
        M.min_angle_triangulation(P, up, np.array([[0, 1]]))
    with pytest.raises(HoleFillError, match="at least 3 boundary vertices"):
        M.min_angle_triangulation(P[:2], up[:2])
