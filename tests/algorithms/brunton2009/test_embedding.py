"""Curve unfolding Sec. 3.3: the embedding energy, its solve and the umbrella operator."""

import numpy as np
import pytest
import scipy.optimize
import scipy.sparse.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009.embedding import embed_patch, embedding_energy, energy_rows
from meshlab_holefill.algorithms.brunton2009.umbrella import umbrella_operator

from conftest import grid
from brunton_cases import sphere_cap_domain


@pytest.mark.parametrize("energy, order", [("area", 1), ("area_interior", 1), ("fairing", 2)])
def test_embedding_solves_its_energy(energy, order):
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    interior = embed_patch(ctx, s, Fp, energy=energy)
    n_ctx = len(ctx.vertices)
    joint = np.concatenate([ctx.faces, np.where(Fp < ctx.size, Fp, Fp - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    R = energy_rows(joint, n_ctx + s, free, order, anchors=energy == "area")
    X = np.concatenate([ctx.vertices, interior])
    energy_value, gradient = embedding_energy(X, R, free)
    assert np.abs(gradient).max() < 1e-10
    if energy == "area":  # least-squares mesh: loop rows too, so U(p) cannot vanish everywhere
        assert s < R.shape[0] <= s + ctx.size and energy_value > 0
    # The paper's quasi-Newton solve (L-BFGS) reaches the same minimiser.
    start = X.copy()
    start[free] = ctx.points.mean(axis=0)

    def f(x):
        Y = start.copy()
        Y[free] = x.reshape(-1, 3)
        e, g = embedding_energy(Y, R, free)
        return e, g.ravel()

    res = scipy.optimize.minimize(f, start[free].ravel(), jac=True, method="L-BFGS-B",
                                  options={"maxiter": 20000, "gtol": 1e-12, "ftol": 1e-15})
    assert res.fun >= energy_value - 1e-12
    assert np.abs(res.x.reshape(-1, 3) - interior).max() < 1e-3


@pytest.mark.parametrize("energy", ["area", "fairing"])
def test_symmetric_mode_lu_moves_the_patch_by_rounding_only(energy, monkeypatch):
    # SuperLU's symmetric mode (minimum degree on A + A^T, diagonal pivots preferred) against its
    # default (COLAMD, partial pivoting), for the energy solve and the tangential relaxation.
    from meshlab_holefill.algorithms.brunton2009 import embedding, tangential_relaxation as relaxation
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    fast = embed_patch(ctx, s, Fp, energy=energy, tangential=True)
    for module in (embedding, relaxation):
        monkeypatch.setattr(module, "symmetric_lu", lambda A: scipy.sparse.linalg.splu(A.tocsc()))
    reference = embed_patch(ctx, s, Fp, energy=energy, tangential=True)
    assert np.abs(fast - reference).max() < 1e-12 * np.abs(reference).max()


def test_least_squares_mesh_rows_follow_the_surrounding_slope():
    # E_AREA over P_Int alone is a membrane spanning the loop; the least-squares mesh's loop
    # rows make the patch leave the loop along the sphere, much closer to it.
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    off = {e: np.abs(np.linalg.norm(embed_patch(ctx, s, Fp, energy=e), axis=1) - 1).mean()
           for e in ("area", "area_interior", "fairing")}
    assert off["area"] < 0.5 * off["area_interior"]
    n_ctx = len(ctx.vertices)
    joint = np.concatenate([ctx.faces, np.where(Fp < ctx.size, Fp, Fp - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    R = energy_rows(joint, n_ctx + s, free, 1, anchors=True)
    W = energy_rows(joint, n_ctx + s, np.ones(n_ctx + s, bool), 1)
    # the anchor rows are exactly the fixed vertices whose umbrella reaches a free vertex: the loop
    touching = np.flatnonzero(np.asarray(abs(W[:n_ctx, n_ctx:]).sum(axis=1)).ravel() > 0)
    assert 0 < len(touching) and touching.max() < ctx.size
    assert R.shape[0] == s + len(touching)


def test_energy_parameters_default_to_the_least_squares_mesh():
    names = {p.name: p for p in cu.PARAMS}
    assert names["energy"].default == "area" and names["area_rows"].default == "mesh"


@settings(max_examples=30, deadline=None)
@given(n=st.integers(4, 6), order=st.sampled_from([1, 2]), anchors=st.booleans(), seed=st.integers(0, 10_000))
def test_minimise_embedding_energy_matches_a_dense_least_squares_solve(n, order, anchors, seed):
    from meshlab_holefill.algorithms.brunton2009.embedding import minimise_embedding_energy

    V, F = grid(n, n)
    rng = np.random.default_rng(seed)
    X = rng.normal(size=V.shape)  # arbitrary fixed positions: the solve does not rely on a flat border
    free = np.ones(n * n, bool)
    ij = np.arange(n * n).reshape(n, n)
    free[np.r_[ij[0], ij[-1], ij[:, 0], ij[:, -1]]] = False
    R = energy_rows(F, n * n, free, order, anchors=anchors)
    assert R.shape[0] > free.sum() if anchors else R.shape[0] == free.sum()
    start = X.copy()
    start[free] = np.nan  # free rows of the input are ignored
    Y = minimise_embedding_energy(start, R, free)
    D = R.toarray()
    expected = np.linalg.lstsq(D[:, free], -D[:, ~free] @ X[~free], rcond=None)[0]
    assert np.array_equal(Y[~free], X[~free])
    assert np.allclose(Y[free], expected, atol=1e-10)
    assert np.abs(embedding_energy(Y, R, free)[1]).max() < 1e-9  # the gradient vanishes


def test_minimise_embedding_energy_without_free_rows_or_with_a_free_island():
    from meshlab_holefill.algorithms.brunton2009.embedding import minimise_embedding_energy

    V, F = grid(4, 4)
    R = energy_rows(F, 16, np.zeros(16, bool), 1)
    assert np.array_equal(minimise_embedding_energy(V, R, np.zeros(16, bool)), V)
    # A free triangle joined to nothing fixed makes R_f singular: the least-squares fallback is
    # still a minimiser (the island collapses to a point, the rest solved as usual).
    F2 = np.concatenate([F, [[16, 17, 18]]])
    free = np.zeros(19, bool)
    free[[5, 6, 9, 10, 16, 17, 18]] = True
    X = np.random.default_rng(0).normal(size=(19, 3))
    R = energy_rows(F2, 19, free, 1)
    Y = minimise_embedding_energy(X, R, free)
    D = R.toarray()
    best = np.linalg.lstsq(D[:, free], -D[:, ~free] @ X[~free], rcond=None)[0]
    assert np.allclose(Y[[5, 6, 9, 10]], best[:4], atol=1e-9)
    assert np.allclose(Y[16:], Y[16], atol=1e-9)
    assert embedding_energy(Y, R, free)[0] == pytest.approx(0.0, abs=1e-15)


def _scipy_umbrella(F, n):
    """U built by scipy's sparse algebra, diags(1 / degree) @ (A - diags(degree)): the oracle."""
    import scipy.sparse as sp
    from meshlab_holefill.geometry.laplacian import uniform_laplacian

    L = uniform_laplacian(np.asarray(F, np.int64), n)
    degree = -L.diagonal()
    return (sp.diags(np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)) @ L).tocsr()


def test_umbrella_operator_is_scipys_matrix_entry_for_entry():
    """Same stored entries, in the same order within each row, so later products and LU factors are identical."""
    from conftest import grid

    rng = np.random.default_rng(0)
    _, F = grid(7)
    cases = [(F, int(F.max()) + 4)]  # isolated vertices at the end
    cases += [(F[rng.choice(len(F), size=len(F) // 2, replace=False)], int(F.max()) + 1) for _ in range(5)]
    cases += [(rng.integers(0, 25, (15, 3)), 25) for _ in range(20)]  # some faces degenerate
    for F, n in cases:
        got, expected = umbrella_operator(F, n), _scipy_umbrella(F, n)
        for attr in ("indptr", "indices", "data"):
            np.testing.assert_array_equal(getattr(got, attr), getattr(expected, attr))
        W = got.toarray()
        used = np.abs(W).sum(axis=1) > 0
        np.testing.assert_allclose(W[used].sum(axis=1), 0.0, atol=1e-12)  # U of a constant is zero
