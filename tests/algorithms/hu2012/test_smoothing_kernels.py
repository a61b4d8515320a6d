"""The compiled guard of the tangential smoothing against its numpy reference (the same bits)."""
import numpy as np

from meshlab_holefill.algorithms.hu2012.tangential_smoothing import _refuse_worse, _refuse_worse_numpy

from conftest import grid


def test_compiled_guard_undoes_the_moves_the_numpy_code_undoes():
    rng = np.random.default_rng(5)
    for trial in range(40):
        V, F = grid(int(rng.integers(3, 9)), int(rng.integers(3, 9)))
        V = V + rng.normal(scale=0.05, size=V.shape)
        moved = rng.random(len(V)) < 0.6
        V_new = V + moved[:, None] * rng.normal(scale=10.0 ** rng.uniform(-3, 0), size=V.shape)
        got = _refuse_worse(V, V_new, F, moved)
        want = _refuse_worse_numpy(V, V_new, F, moved)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
        assert np.all((got == V) | (got == V_new))  # each vertex keeps its move or goes back


def test_a_move_that_flips_a_face_is_undone():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2]])
    V_new = V.copy()
    V_new[2] = [0, -1, 0]  # the face turns over
    np.testing.assert_array_equal(_refuse_worse(V, V_new, F, np.array([False, False, True])), V)
