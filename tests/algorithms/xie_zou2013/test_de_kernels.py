"""The compiled DE kernels give bit for bit the numpy expressions they replace."""
import numpy as np

from meshlab_holefill.algorithms.xie_zou2013 import _de_kernels as K
from meshlab_holefill.algorithms.xie_zou2013.de_rand_1_bin import reflect_into_bounds


def _problem(rng, B=3, N=7, n=5):
    lower = rng.normal(size=(B, n))
    upper = lower + rng.random((B, n)) * 2.0
    upper[:, -1] = lower[:, -1]  # a fixed (padding) component
    X = lower[:, None, :] + (rng.random((B, N, n)) * 3.0 - 1.0) * (upper - lower + 0.5)[:, None, :]
    return X, lower, upper


def test_reflect_moved_equals_numpy():
    rng = np.random.default_rng(1)
    X, lower, upper = _problem(rng)
    X[0, 0, 0] = -0.0
    out, moved = K.reflect_moved(X, lower, upper)
    ref = reflect_into_bounds(X, lower, upper)
    assert out.tobytes() == ref.tobytes()
    assert np.array_equal(moved, np.any(ref != X, axis=2))


def test_trial_vectors_and_select_equal_numpy():
    rng = np.random.default_rng(2)
    X, _, _ = _problem(rng)
    B, N, n = X.shape
    r1, r2, r3 = (rng.integers(0, N, (B, N)) for _ in range(3))
    u = rng.random((B, N, n))
    rn = rng.integers(0, n, (B, N))
    F, CR = 0.8, 0.3
    rows = np.arange(B)[:, None]
    V = X[rows, r1] + F * (X[rows, r2] - X[rows, r3])
    take = (u <= CR) | (np.arange(n)[None, None, :] == rn[..., None])
    U_ref = np.where(take, V, X)
    U = K.trial_vectors(X, r1, r2, r3, u, rn, F, CR)
    assert U.tobytes() == U_ref.tobytes()
    fX, fU = rng.random((B, N)), rng.random((B, N))
    fU[0, 0] = fX[0, 0]  # ties select the trial
    active = rng.random((B, N)) < 0.8
    better = (fU <= fX) & active
    X_ref, f_ref = np.where(better[..., None], U, X), np.where(better, fU, fX)
    K.select(X, fX, U, fU, active)
    assert X.tobytes() == X_ref.tobytes() and fX.tobytes() == f_ref.tobytes()


def test_turning_terms_equal_numpy():
    rng = np.random.default_rng(3)
    p, N, m = 4, 6, 5
    Y = rng.normal(size=(p, N, m))
    seg_x = rng.normal(size=(p, m + 3))
    seg_y_add = np.zeros((p, m + 3))
    seg_y_add[:, 0], seg_y_add[:, m + 2] = rng.normal(size=p), rng.normal(size=p)
    # the numpy expression turning_angles used before the kernel
    dy = np.diff(Y, axis=2, prepend=0.0, append=0.0)
    sy = np.concatenate([np.zeros((p, N, 1)), dy, np.zeros((p, N, 1))], axis=2) + seg_y_add[:, None, :]
    sx = seg_x[:, None, :]
    cross_ref = sx[..., :-1] * sy[..., 1:] - sy[..., :-1] * sx[..., 1:]
    dot_ref = sx[..., :-1] * sx[..., 1:] + sy[..., :-1] * sy[..., 1:]
    cross, dot = K.turning_terms(Y, seg_x, seg_y_add)
    assert cross.tobytes() == cross_ref.tobytes() and dot.tobytes() == dot_ref.tobytes()
