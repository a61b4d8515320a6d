"""The compiled candidate scores of the quality pass against the numpy code they replace."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import _quality_pass_numpy as QP
from meshlab_holefill.algorithms.xie_zou2013._quality_pass_kernels import star_candidate_scores


def numpy_scores(P, mask, X, ref, nv, floor_min, floor, energy_objective):
    """The numpy score of _Patch.optimise_position (without the loop-edge test)."""
    Q = np.repeat(P[None], len(X), axis=0)
    Q[:, mask] = X[:, None, :]
    q, c = QP._quality(Q)
    ln = np.linalg.norm(c, axis=2)
    ok = np.all(ln > 0, axis=1)
    N = c / np.maximum(ln, 1e-300)[..., None]
    ok &= np.all(np.einsum("cij,ij->ci", N, ref) > QP.TURN_COS, axis=1)
    ok &= np.all(N @ nv > QP.TURN_COS, axis=1)
    qmin = q.min(axis=1)
    ok &= qmin >= floor_min - QP.GAIN
    energy = (1.0 / np.maximum(q, 1e-12)).mean(axis=1)
    val = energy if energy_objective else -np.minimum(qmin, floor) + 1e-3 * energy
    return np.where(ok, val, np.inf), qmin, N


def star(rng, s):
    """A vertex at the origin with s neighbours on a jittered ring, its fan of triangles."""
    ang = (np.arange(s) + rng.uniform(-0.3, 0.3, s)) * (2 * np.pi / s)
    ring = np.stack([np.cos(ang), np.sin(ang), 0.1 * rng.standard_normal(s)], axis=1)
    V = np.vstack([[0.0, 0.0, 0.0], ring])
    T = np.array([[0, 1 + i, 1 + (i + 1) % s] for i in range(s)])
    T = np.array([np.roll(t, rng.integers(3)) for t in T])  # the centre at any corner
    return V, T


@pytest.mark.parametrize("s", [3, 5, 8, 9, 13, 20])
@pytest.mark.parametrize("energy", [False, True])
def test_star_candidate_scores_bit_equal_to_numpy(s, energy):
    rng = np.random.default_rng(s)
    finite = 0
    for _ in range(20):
        V, T = star(rng, s)
        P = V[T]
        mask = T == 0
        q0, cr = QP._quality(P)
        ref = cr / np.maximum(np.linalg.norm(cr, axis=1), 1e-300)[:, None]
        nv = cr.sum(axis=0)
        nv /= np.linalg.norm(nv)
        X = np.vstack([[0.0, 0.0, 0.0], rng.normal(scale=0.2, size=(8, 3)), V[1]])  # V[1]: degenerate
        floor_min = float(q0.min()) * rng.uniform(0.5, 1.0)
        want = numpy_scores(P, mask, X, ref, nv, floor_min, 0.4, energy)
        got = star_candidate_scores(P, np.argmax(mask, axis=1), X, ref, nv, floor_min, 0.4, QP.GAIN, QP.TURN_COS,
                                    energy)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
        finite += np.isfinite(got[0]).sum()
        assert np.isinf(got[0][-1])  # the candidate on a neighbour degenerates two triangles: rejected
    assert finite > 40  # most candidates pass the guards: the objective is compared, not only inf
