"""The Poisson system with the hole boundary's Laplacian rows (Sec. 2.3 boundary condition, least squares)."""
import numpy as np
import pymeshlab

from meshlab_holefill.algorithms.xu2013.poisson_reconstruction import solve_poisson
from meshlab_holefill.algorithms.xu2013.poisson_patch import normalized_cotangent_laplacian


def _sphere_with_patch():
    """A sphere mesh reordered so that a cap's vertices come first: its border ring, then its inside."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(radius=1.0, subdiv=3)
    V = np.asarray(ms.current_mesh().vertex_matrix(), np.float64)
    F = np.asarray(ms.current_mesh().face_matrix(), np.int64)
    cap = (V[F].mean(axis=1) @ np.array([0.0, 0.0, 1.0])) > 0.8
    inner = np.setdiff1d(np.unique(F[cap]), np.unique(F[~cap]))
    border = np.setdiff1d(np.unique(F[cap]), inner)
    order = np.concatenate([border, inner, np.setdiff1d(np.arange(len(V)), np.unique(F[cap]))])
    new = np.empty(len(V), np.int64)
    new[order] = np.arange(len(V))
    V2, F2 = V[order], new[F]
    n = len(border) + len(inner)
    free = np.arange(n) >= len(border)
    return V2, F2, F2[cap], n, free, np.arange(len(border))


def test_boundary_rows_reproduce_the_surface_from_its_own_laplacians():
    allV, allF, F, n, free, rows = _sphere_with_patch()
    L = normalized_cotangent_laplacian(allV, allF)
    delta = L @ allV
    X = allV[:n].copy()
    got = solve_poisson(X, F, free, delta[:n][free], (rows, allV, allF, delta[rows]))
    assert np.abs(got - allV[:n][free]).max() < 1e-9


def test_boundary_rows_solve_the_least_squares_problem():
    # Inconsistent right-hand sides: the answer is the dense least-squares solution of the
    # inner and boundary rows, the other vertices fixed.
    allV, allF, F, n, free, rows = _sphere_with_patch()
    rng = np.random.default_rng(0)
    rhs, rhs_rows = rng.normal(size=(free.sum(), 3)) * 1e-2, rng.normal(size=(len(rows), 3)) * 1e-2
    got = solve_poisson(allV[:n].copy(), F, free, rhs, (rows, allV, allF, rhs_rows))
    L = normalized_cotangent_laplacian(allV, allF).toarray()
    free_idx = np.flatnonzero(free)
    known = np.setdiff1d(np.arange(len(allV)), free_idx)
    R = np.concatenate([free_idx, rows])
    B = np.concatenate([rhs, rhs_rows]) - L[np.ix_(R, known)] @ allV[known]
    want = np.linalg.lstsq(L[np.ix_(R, free_idx)], B, rcond=None)[0]
    assert np.abs(got - want).max() < 1e-9


def test_without_boundary_rows_the_square_dirichlet_system_is_solved():
    allV, allF, F, n, free, rows = _sphere_with_patch()
    X = allV[:n]
    rhs = np.zeros((free.sum(), 3))
    got = solve_poisson(X, F, free, rhs)
    L = normalized_cotangent_laplacian(X, F).toarray()
    assert np.abs(L[free][:, free] @ got + L[free][:, ~free] @ X[~free]).max() < 1e-9


def _inconsistent_rows():
    """The sphere cap's rows with random right-hand sides, which no positions satisfy all at once."""
    allV, allF, F, n, free, rows = _sphere_with_patch()
    rng = np.random.default_rng(1)
    rhs, rhs_rows = rng.normal(size=(free.sum(), 3)) * 1e-2, rng.normal(size=(len(rows), 3)) * 1e-2
    return allV, allF, F, n, free, rows, rhs, rhs_rows


def test_weighted_boundary_rows_solve_the_weighted_least_squares_problem():
    allV, allF, F, n, free, rows, rhs, rhs_rows = _inconsistent_rows()
    got = solve_poisson(allV[:n].copy(), F, free, rhs, (rows, allV, allF, rhs_rows), boundary_weight=3.0)
    L = normalized_cotangent_laplacian(allV, allF).toarray()
    free_idx = np.flatnonzero(free)
    known = np.setdiff1d(np.arange(len(allV)), free_idx)
    R = np.concatenate([free_idx, rows])
    B = np.concatenate([rhs, rhs_rows]) - L[np.ix_(R, known)] @ allV[known]
    w = np.concatenate([np.ones(len(free_idx)), np.full(len(rows), 3.0)])[:, None]
    want = np.linalg.lstsq(w * L[np.ix_(R, free_idx)], w * B, rcond=None)[0]
    assert np.abs(got - want).max() < 1e-9


def test_a_heavier_boundary_weight_brings_the_boundary_laplacians_closer_to_their_prediction():
    allV, allF, F, n, free, rows, rhs, rhs_rows = _inconsistent_rows()
    L = normalized_cotangent_laplacian(allV, allF)
    residuals = []
    for weight in (0.5, 1.0, 2.0, 8.0):
        X = allV.copy()
        X[np.flatnonzero(free)] = solve_poisson(allV[:n].copy(), F, free, rhs, (rows, allV, allF, rhs_rows),
                                                boundary_weight=weight)
        residuals.append(np.linalg.norm(L[rows] @ X - rhs_rows))
    assert all(a > b for a, b in zip(residuals, residuals[1:])), residuals

