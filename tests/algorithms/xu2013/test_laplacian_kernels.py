"""The compiled normalised cotangent Laplacian: the very CSR arrays scipy's sparse algebra builds."""
import numpy as np
import pytest
import scipy.sparse as sp

from meshlab_holefill.algorithms.xu2013._laplacian_kernels import edge_weight_rows
from meshlab_holefill.algorithms.xu2013.poisson_patch import _normalized_from_sparse, normalized_cotangent_laplacian
from tests.conftest import grid, sphere_with_holes


def _assert_identical(A, B):
    assert A.indptr.dtype == B.indptr.dtype and A.indices.dtype == B.indices.dtype
    assert np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
    assert A.data.tobytes() == B.data.tobytes()


def _jittered_grid(seed):
    V, F = grid(9, 7)
    rng = np.random.default_rng(seed)
    return V + rng.normal(scale=0.02, size=V.shape) * [1.0, 1.0, 3.0], np.asarray(F, np.int64)


@pytest.mark.parametrize("seed", range(4))
def test_same_matrix_as_the_sparse_construction_on_open_meshes(seed):
    V, F = _jittered_grid(seed)
    _assert_identical(normalized_cotangent_laplacian(V, F), _normalized_from_sparse(V, F, len(V), None))


def test_same_matrix_on_a_closed_mesh_with_extra_rows_and_given_cotangents():
    V, F, _ = sphere_with_holes(subdiv=2, radius=0.0)
    F = np.asarray(F, np.int64)
    C = np.random.default_rng(1).normal(size=F.shape)  # obtuse (negative) weights raised to the floor
    n = len(V) + 5  # rows of vertices without neighbours stay empty
    L = normalized_cotangent_laplacian(V, F, n, C)
    _assert_identical(L, _normalized_from_sparse(V, F, n, C))
    assert L.shape == (n, n) and L[len(V):].nnz == 0


def test_edges_whose_weights_cancel_are_left_out():
    V, F = _jittered_grid(0)
    h = len(F) // 2  # the grid's faces (a, b, c) of a cell, then its faces (a, c, d)
    C = np.full(F.shape, 0.5)
    C[0, 1], C[h, 2] = 0.25, -0.25  # the corners opposite the cell's diagonal (a, c)
    a, c = sorted((F[0, 0], F[0, 2]))
    assert {F[h, 0], F[h, 1]} == {a, c}
    L = normalized_cotangent_laplacian(V, F, cotangents=C)
    _assert_identical(L, _normalized_from_sparse(V, F, len(V), C))
    assert c not in L.indices[L.indptr[a]:L.indptr[a + 1]]


def test_meshes_the_kernel_refuses_take_the_sparse_construction():
    V, F = _jittered_grid(2)
    fin = np.concatenate([F, [[F[0, 0], F[0, 2], len(V)]]])  # a third face on the first cell's diagonal
    V3 = np.concatenate([V, [[0.3, 0.3, 1.0]]])
    degenerate = np.concatenate([F, [[0, 0, 1]]])
    for X, G in ((V3, fin), (V, degenerate)):
        assert not edge_weight_rows(G, 0.5 * np.ones(G.shape), len(X))[0]
        _assert_identical(normalized_cotangent_laplacian(X, G), _normalized_from_sparse(X, G, len(X), None))


def test_rows_are_convex_combinations_minus_the_vertex():
    V, F = _jittered_grid(3)
    L = normalized_cotangent_laplacian(V, F)
    assert np.allclose(L.diagonal(), -1.0) and np.allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0)
    off = L - sp.diags(L.diagonal())
    assert off.data.min() > 0
