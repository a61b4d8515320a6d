"""Laplacians and tangential umbrella smoothing of geometry.laplacian."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.geometry.laplacian import (adjacency_matrix, adjacency_matrix_numpy, cotangent_laplacian,
                                                 tangential_umbrella_smoothing, tangential_umbrella_smoothing_numpy,
                                                 uniform_laplacian)
from conftest import grid


def test_laplacians_annihilate_constants_and_cotangent_has_linear_precision():
    V, F = grid(8, 8)
    interior = np.flatnonzero((V[:, 0] > 0.01) & (V[:, 0] < 0.99) & (V[:, 1] > 0.01) & (V[:, 1] < 0.99))
    rng = np.random.default_rng(1)
    V[:, :2] += rng.uniform(-0.02, 0.02, size=(len(V), 2))
    for L in (uniform_laplacian(F, len(V)), cotangent_laplacian(V, F)):
        assert np.allclose(L @ np.ones(len(V)), 0)
        assert abs(L - L.T).max() < 1e-12
    Lc = cotangent_laplacian(V, F)
    linear = 2 * V[:, 0] - 3 * V[:, 1]
    assert np.abs((Lc @ linear)[interior]).max() < 1e-10


def test_tangential_umbrella_smoothing_evens_a_plane_within_it():
    """On a tilted plane the vertices stay in the plane and return to the regular grid."""
    V, F = grid(9, 9, z=lambda x, y: 0.3 * x + 0.2 * y)
    boundary = (V[:, 0] < 1e-9) | (V[:, 0] > 1 - 1e-9) | (V[:, 1] < 1e-9) | (V[:, 1] > 1 - 1e-9)
    rng = np.random.default_rng(4)
    shaken = V.copy()
    shaken[~boundary, :2] += rng.uniform(-0.04, 0.04, size=(int((~boundary).sum()), 2))
    shaken[:, 2] = 0.3 * shaken[:, 0] + 0.2 * shaken[:, 1]
    out = tangential_umbrella_smoothing(shaken, F, boundary, 200)
    assert np.array_equal(out[boundary], shaken[boundary])
    assert np.abs(out[:, 2] - 0.3 * out[:, 0] - 0.2 * out[:, 1]).max() < 1e-12
    # the umbrella's fixed point on this grid is the grid itself (each vertex the mean of its neighbours)
    L = uniform_laplacian(F, len(V))
    assert np.abs((L @ out)[~boundary]).max() < 1e-6
    assert np.abs(out - V).max() < 0.05 * np.abs(shaken - V).max()
    assert np.array_equal(tangential_umbrella_smoothing(shaken, F, boundary, 0), shaken)


def test_tangential_umbrella_smoothing_keeps_a_sphere_round_to_first_order():
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    fixed = V[:, 2] < 0
    out = tangential_umbrella_smoothing(V, F, fixed, 10, step=0.5)
    radius = np.linalg.norm(out, axis=1)
    moved = np.linalg.norm(out - V, axis=1)
    assert moved[~fixed].max() > 1e-3  # the sphere's triangulation is not the umbrella's fixed point
    assert np.abs(radius - 1).max() < 0.05 * moved.max()  # radial drift is second order


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), rows=st.integers(3, 12), iterations=st.integers(1, 6),
       step=st.sampled_from([0.25, 0.5, 1.0]), shake=st.floats(0.0, 0.2))
def test_compiled_tangential_rounds_have_the_bits_of_the_numpy_rounds(seed, rows, iterations, step, shake):
    rng = np.random.default_rng(seed)
    V, F = grid(rows, rows + 1, z=lambda x, y: 0.4 * np.sin(3 * x) * y)
    V[:, :2] += shake * rng.uniform(-1.0, 1.0, size=(len(V), 2)) / rows
    fixed = rng.random(len(V)) < 0.3
    F = F.copy()
    repeated = rng.random(len(F)) < 0.05
    F[repeated, 2] = F[repeated, 0]  # degenerate faces: their edge to themselves counts twice
    out = tangential_umbrella_smoothing(V, F, fixed, iterations, step=step)
    np.testing.assert_array_equal(out, tangential_umbrella_smoothing_numpy(V, F, fixed, iterations, step=step))
    assert not np.array_equal(out[~fixed], V[~fixed]) or not (~fixed).any()


@pytest.mark.parametrize("index", [-1, 16])
def test_tangential_smoothing_with_a_face_out_of_range_raises_as_the_numpy_code_does(index):
    V, F = grid(4, 4)
    F = F.copy()
    F[0, 0] = index
    with pytest.raises(ValueError) as ref:
        tangential_umbrella_smoothing_numpy(V, F, np.zeros(len(V), bool), 2)
    with pytest.raises(ref.type, match="index"):
        tangential_umbrella_smoothing(V, F, np.zeros(len(V), bool), 2)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), m=st.integers(1, 40), n=st.integers(3, 30), spare=st.integers(0, 3))
def test_compiled_adjacency_has_the_arrays_of_scipys_conversion(seed, m, n, spare):
    rng = np.random.default_rng(seed)
    F = rng.integers(0, n, size=(m, 3))  # repeated corners too: self-loops count twice, as scipy sums them
    A, ref = adjacency_matrix(F, n + spare), adjacency_matrix_numpy(F, n + spare)
    for name in ("data", "indices", "indptr"):
        got, want = getattr(A, name), getattr(ref, name)
        assert got.dtype == want.dtype
        np.testing.assert_array_equal(got, want)
    assert A.has_canonical_format and A.shape == ref.shape


def test_tangential_smoothing_with_a_fixed_mask_of_another_length_raises_as_the_numpy_code_does():
    V, F = grid(4, 4)
    with pytest.raises(IndexError):
        tangential_umbrella_smoothing_numpy(V, F, np.zeros(len(V) + 3, bool), 2)
    with pytest.raises(IndexError):
        tangential_umbrella_smoothing(V, F, np.zeros(len(V) + 3, bool), 2)

