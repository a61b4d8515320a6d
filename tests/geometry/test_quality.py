"""Triangle measures of geometry.quality: 2r/R quality, angles, vertex normals."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.quality import corner_angles, face_areas, triangle_quality, vertex_normals
from conftest import grid


EQUILATERAL = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])


def test_quality_of_equilateral_is_one_and_of_degenerate_is_zero():
    V = np.concatenate([EQUILATERAL, [[2, 0, 0]]])
    q = triangle_quality(V, np.array([[0, 1, 2], [0, 1, 3]]))
    assert q[0] == pytest.approx(1.0)
    assert q[1] == 0.0


def test_quality_of_right_isoceles_triangle():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    # r = (2 - sqrt 2)/2, R = sqrt(2)/2  =>  2r/R = 2(2 - sqrt 2)/sqrt 2
    assert triangle_quality(V, np.array([[0, 1, 2]]))[0] == pytest.approx(2 * (2 - np.sqrt(2)) / np.sqrt(2))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-5, 5), min_size=9, max_size=9), st.floats(0.1, 10))
def test_quality_is_scale_invariant_and_in_unit_interval(coords, s):
    V = np.array(coords).reshape(3, 3)
    F = np.array([[0, 1, 2]])
    q = triangle_quality(V, F)[0]
    assert 0.0 <= q <= 1.0
    if face_areas(V, F)[0] > 1e-6:
        assert triangle_quality(V * s, F)[0] == pytest.approx(q, rel=1e-6, abs=1e-9)
    assert corner_angles(V, F).sum() == pytest.approx(np.pi) or face_areas(V, F)[0] < 1e-9


def test_vertex_normals_of_a_grid_point_up():
    V, F = grid(4, 4)
    assert np.allclose(vertex_normals(V, F), [0, 0, 1])


def test_vertex_normals_weigh_faces_by_area():
    """Sum of face cross products: a face of area 2 counts twice as much as one of area 1.

    Both faces have a right angle at vertex 0 and at vertex 1 the angles differ, so neither the
    unweighted mean of unit normals, (0, 1, 1)/sqrt 2, nor angle weighting gives the answer.
    """
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 1], [5, 5, 5]], float)
    F = np.array([[0, 1, 2],   # area 2, normal +z
                  [0, 3, 1]])  # area 1, normal +y, shares edge (0, 1) with consistent orientation
    N = vertex_normals(V, F)
    both = np.array([0, 2, 4]) / np.sqrt(20)  # (0, 2, 0) + (0, 0, 4), normalised
    assert np.allclose(N[0], both) and np.allclose(N[1], both)
    assert np.allclose(N[2], [0, 0, 1]) and np.allclose(N[3], [0, 1, 0])
    assert np.array_equal(N[4], [0, 0, 0])  # a vertex without faces gets a zero normal


def test_corner_sums_adds_like_add_at_in_corner_order():
    from meshlab_holefill.geometry.quality import corner_sums

    rng = np.random.default_rng(0)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        F = rng.integers(0, n, (int(rng.integers(0, 60)), 3))
        C = rng.normal(size=(len(F), 3)) * 10.0 ** rng.integers(-6, 6, (len(F), 1))
        expected = np.zeros((n, 3))
        for k in range(3):
            np.add.at(expected, F[:, k], C)
        np.testing.assert_array_equal(corner_sums(F, C, n), expected)


def test_unique_edges_equals_the_row_wise_unique_of_the_sorted_edges():
    from meshlab_holefill.geometry.quality import unique_edges

    rng = np.random.default_rng(1)
    for _ in range(200):
        F = rng.integers(0, int(rng.integers(1, 60)), (int(rng.integers(0, 50)), 3))
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).astype(np.int64), axis=1)
        got = unique_edges(F)
        assert got.dtype == np.int64 and got.shape == (len(np.unique(E, axis=0)), 2)
        np.testing.assert_array_equal(got, np.unique(E, axis=0))


def test_compiled_quality_matches_the_numpy_reference_bit_for_bit():
    from meshlab_holefill.geometry.quality import triangle_quality_numpy

    rng = np.random.default_rng(2)
    V = rng.normal(size=(300, 3)) * 10.0 ** rng.integers(-6, 6, (300, 1))
    V[:30] = V[30:60]  # repeated points: degenerate faces
    V[60:70] = np.linspace(0.0, 1.0, 10)[:, None] * [1.0, 2.0, 3.0]  # collinear points
    for F in (rng.integers(0, 300, (5000, 3)), rng.integers(-300, 300, (500, 3)).astype(np.int32),
              np.zeros((0, 3), np.int64), np.array([[60, 61, 62], [0, 30, 1]])):
        got, want = triangle_quality(V, F), triangle_quality_numpy(V, F)
        assert got.shape == want.shape and got.dtype == np.float64
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


def test_quality_rejects_an_index_out_of_range():
    with pytest.raises(IndexError, match="out of bounds"):
        triangle_quality(EQUILATERAL, np.array([[0, 1, 3]]))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(3, 60), m=st.integers(1, 120), exponent=st.integers(-8, 8),
       extra=st.integers(0, 3), poison=st.booleans())
def test_compiled_normals_match_the_numpy_reference_bit_for_bit(seed, n, m, exponent, extra, poison):
    from meshlab_holefill.geometry.quality import face_normals, face_normals_numpy, vertex_normals_numpy

    rng = np.random.default_rng(seed)
    V = rng.normal(size=(n, 3)) * 10.0 ** exponent + rng.normal(size=3) * 10.0 ** (exponent + 2)
    F = rng.integers(0, n, (m, 3))
    F[0, 1] = F[0, 0]  # a degenerate face: a zero normal
    if poison:
        V[rng.integers(0, n)] = np.nan
    for normalize in (True, False):
        got, want = face_normals(V, F, normalize), face_normals_numpy(V, F, normalize)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
    wrapped = F - n * (rng.random(F.shape) < 0.3)  # negative indices count from the end, as numpy's
    np.testing.assert_array_equal(face_normals(V, wrapped).view(np.int64), face_normals_numpy(V, wrapped).view(np.int64))
    got, want = vertex_normals(V, F, n + extra), vertex_normals_numpy(V, F, n + extra)
    assert got.shape == want.shape == (n + extra, 3)
    np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


def test_normals_reject_an_index_out_of_range_and_of_no_face_are_zero():
    from meshlab_holefill.geometry.quality import face_normals

    with pytest.raises(IndexError, match="out of bounds"):
        face_normals(EQUILATERAL, np.array([[0, 1, 3]]))
    with pytest.raises(ValueError, match="negative"):
        vertex_normals(EQUILATERAL, np.array([[0, 1, -1]]))
    assert not vertex_normals(EQUILATERAL, np.zeros((0, 3), np.int64)).any()
    np.testing.assert_array_equal(vertex_normals(EQUILATERAL, [[0, 1, 2]]), np.tile([0.0, 0.0, 1.0], (3, 1)))
