"""SuperLU in its symmetric mode (geometry.sparse_lu)."""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.laplacian import uniform_laplacian
from meshlab_holefill.geometry.sparse_lu import symmetric_lu

from conftest import grid


@settings(max_examples=20, deadline=None)
@given(st.integers(4, 12), st.integers(0, 2**31 - 1))
def test_weighted_normal_equations_are_solved_as_by_the_default_factorisation(size, seed):
    # A^T W A of a grid Laplacian's rows, the border fixed, W positive: symmetric positive definite
    rng = np.random.default_rng(seed)
    V, F = grid(size, size)
    L = uniform_laplacian(F, len(V)).tocsr()
    free = np.flatnonzero(np.abs(V[:, :2] - 0.5).max(axis=1) < 0.49)
    A = L[:, free]
    M = (A.T @ sp.diags(rng.uniform(0.25, 16.0, len(V))) @ A).tocsc()
    b = rng.normal(size=(len(free), 3))
    x = symmetric_lu(M).solve(b)
    assert np.abs(M @ x - b).max() < 1e-9 * np.abs(b).max()
    assert np.allclose(x, spla.splu(M).solve(b), rtol=0, atol=1e-10 * np.abs(x).max())


def test_a_zero_on_the_diagonal_is_pivoted_around():
    swap = sp.csc_matrix(np.array([[0.0, 1.0], [1.0, 0.0]]))
    assert np.allclose(symmetric_lu(swap).solve(np.array([1.0, 2.0])), [2.0, 1.0])
