"""The compiled steps and guard of the tangential smoothing against their numpy references (the same bits)."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.hu2012.tangential_smoothing import (STEP_FRACTIONS, _refuse_worse_numpy, _tangential_steps,
                                                                     _tangential_steps_numpy, _guarded_moves,
                                                                     _guarded_moves_numpy)

from conftest import grid


def test_compiled_guard_undoes_the_moves_the_numpy_code_undoes():
    rng = np.random.default_rng(5)
    for trial in range(40):
        V, F = grid(int(rng.integers(3, 9)), int(rng.integers(3, 9)))
        V = V + rng.normal(scale=0.05, size=V.shape)
        moved = rng.random(len(V)) < 0.6
        d = rng.normal(scale=10.0 ** rng.uniform(-3, 0), size=V.shape)
        V_new = V + 1.0 * d * moved[:, None]
        got = _guarded_moves(V, d, F, moved, (1.0,))
        want = _refuse_worse_numpy(V, V_new, F, moved)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
        assert np.all((got == V) | (got == V_new))  # each vertex keeps its move or goes back


def test_a_move_that_flips_a_face_is_taken_back():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    F = np.array([[0, 1, 2]])
    d = np.array([[0, 0, 0], [0, 0, 0], [0, -2, 0]], float)  # the face turns over, at every step
    np.testing.assert_array_equal(_guarded_moves(V, d, F, np.array([False, False, True]), STEP_FRACTIONS), V)


@pytest.mark.parametrize("seed", range(6))
def test_compiled_steps_are_the_numpy_steps_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    for trial in range(20):
        V, F = grid(int(rng.integers(2, 9)), int(rng.integers(2, 9)))
        scale = 10.0 ** rng.uniform(-6, 6)
        V = (V + rng.normal(scale=10.0 ** rng.uniform(-4, -0.5), size=V.shape)) * scale + rng.normal(size=3) * scale
        V = np.concatenate([V, rng.normal(size=(2, 3))])  # two vertices on no face
        if trial % 4 == 0:
            F = np.concatenate([F, [[0, 0, 1]]])  # a degenerate face: a zero normal, a zero apex offset
        movable = rng.random(len(V)) < 0.7
        d, ok = _tangential_steps(V, F, movable)
        d_ref, ok_ref = _tangential_steps_numpy(V, np.asarray(F, np.int64), movable)
        np.testing.assert_array_equal(ok, ok_ref)
        np.testing.assert_array_equal(d.view(np.int64), d_ref.view(np.int64))
        assert not ok[-2:].any() and not d[~ok].any()  # isolated and fixed vertices stay


def test_a_step_is_tangential_and_moves_a_vertex_towards_the_equilateral_apexes():
    # A fan of six triangles around vertex 0 on the plane z = 0, vertex 0 off centre: its step stays in
    # the plane and points back to the centre, where the six apexes average.
    ring = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.arange(6) * np.pi / 3])
    V = np.concatenate([[[0.2, -0.1, 0.0]], ring])
    F = np.array([[0, 1 + i, 1 + (i + 1) % 6] for i in range(6)])
    d, ok = _tangential_steps(V, F, np.array([True] + [False] * 6))
    assert ok[0] and not ok[1:].any()
    assert d[0, 2] == 0.0
    assert np.dot(d[0, :2], -V[0, :2]) > 0.9 * np.linalg.norm(d[0, :2]) * np.linalg.norm(V[0, :2])


@pytest.mark.parametrize("seed", range(6))
def test_compiled_collapse_search_chooses_the_numpy_collapse(seed):
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import _best_collapse, _best_collapse_numpy

    rng = np.random.default_rng(seed)
    chosen = 0
    for trial in range(25):
        V, F = grid(int(rng.integers(3, 8)), int(rng.integers(3, 8)))
        V = V + rng.normal(scale=10.0 ** rng.uniform(-2.5, -0.5), size=V.shape)  # poor and flipped triangles
        F = np.asarray(F, np.int64)
        movable = rng.random(len(V)) < 0.7
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]]]), axis=1)
        fixed = E[rng.random(len(E)) < 0.2] if trial % 3 else None
        max_quality = float(rng.uniform(0.3, 0.95))
        got = _best_collapse(V, F, movable, fixed, max_quality)
        assert got == _best_collapse_numpy(V, F, movable, fixed, max_quality)
        chosen += got is not None
    assert chosen > 0  # the search found collapses, not only refusals


@pytest.mark.parametrize("seed", range(4))
def test_compiled_guarded_moves_are_the_step_by_step_guard_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    for trial in range(25):
        V, F = grid(int(rng.integers(3, 9)), int(rng.integers(3, 9)))
        V = V + rng.normal(scale=0.05, size=V.shape)
        d = rng.normal(scale=10.0 ** rng.uniform(-3, 0), size=V.shape)
        pending = rng.random(len(V)) < 0.7
        if trial % 5 == 0:
            F = np.concatenate([F, F[:1, [0, 0, 1]]])  # a face of zero area: its normal is zero, it counts as flipped
        got = _guarded_moves(V, d, F, pending, STEP_FRACTIONS)
        want = _guarded_moves_numpy(V, d, F, pending, STEP_FRACTIONS)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
        shorter = [V + s * d for s in STEP_FRACTIONS]
        assert all(np.any([np.all(got[v] == x[v]) for x in [V] + shorter]) for v in range(len(V)))
