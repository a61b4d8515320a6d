"""Curve unfolding Sec. 3.1: the annealing that unfolds the loop, its moves and the linear motion to the plane."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill import HoleFillError
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009.linear_motion import linear_motion_is_simple, project_to_best_plane
from meshlab_holefill.algorithms.brunton2009.annealing import anneal_loop, colour_classes, planarity_energy, planarity_terms
from meshlab_holefill.algorithms.brunton2009.unfolding import unfold_loop
from meshlab_holefill.geometry.segments import min_segment_distance, segment_distances

from brunton_cases import mean_edge


def wrapped_rectangle(n_arc=20, n_side=3, wrap=200.0, height=1.0):
    """Boundary of a rectangle wrapped around the unit cylinder: its best-plane projection overlaps itself."""
    th = np.radians(np.linspace(0, wrap, n_arc))
    bottom = np.c_[np.cos(th), np.sin(th), np.zeros(n_arc)]
    top = np.c_[np.cos(th[::-1]), np.sin(th[::-1]), np.full(n_arc, height)]
    z = np.linspace(0, height, n_side + 1)[1:-1]
    up = np.c_[np.full_like(z, np.cos(th[-1])), np.full_like(z, np.sin(th[-1])), z]
    down = np.c_[np.ones_like(z), np.zeros_like(z), z[::-1]]
    return np.vstack([bottom, up, top, down])


def trefoil(n=36):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=12, max_size=12), st.sampled_from(["general", "parallel", "point"]))
def test_segment_distance_is_exact(coords, kind):
    A0, A1, B0, B1 = np.reshape(coords, (4, 3))
    if kind == "parallel":
        B1 = B0 + 0.7 * (A1 - A0)
    elif kind == "point":
        A1 = A0.copy()
    d = float(segment_distances(A0, A1, B0, B1))
    s = np.linspace(0, 1, 301)
    X, Y = A0 + np.outer(s, A1 - A0), B0 + np.outer(s, B1 - B0)
    brute = np.sqrt(((X[:, None] - Y[None]) ** 2).sum(-1)).min()
    assert d <= brute + 1e-12  # never above a sampled distance ...
    step = max(np.linalg.norm(A1 - A0), np.linalg.norm(B1 - B0)) / 300
    assert brute - d <= step + 1e-12  # ... and within the sampling resolution of the true minimum


def test_planarity_energy_is_zero_for_a_convex_planar_loop_and_counts_inflections():
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    circle = np.c_[np.cos(t), np.sin(t), np.zeros(12)]
    assert planarity_energy(circle) == pytest.approx(0, abs=1e-12)
    # One reflex vertex flips one normal n_i: two terms of pi (angle between vectors, as written).
    L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    assert planarity_energy(L) == pytest.approx(2 * np.pi)
    # A non-planar loop has positive energy; the terms are angles in [0, pi].
    bent = circle + np.c_[np.zeros(12), np.zeros(12), 0.3 * np.sin(2 * t)]
    terms = planarity_terms(bent)
    assert np.all((terms >= 0) & (terms <= np.pi)) and terms.sum() > 0.1


@pytest.mark.parametrize("m", range(4, 23))
def test_colour_classes_partition_the_loop_into_independent_moves(m):
    classes = colour_classes(m)
    flat = np.concatenate(classes)
    assert sorted(flat.tolist()) == list(range(m))
    for c in classes:
        gap = np.abs(c[:, None] - c[None, :])
        gap = np.minimum(gap, m - gap)
        assert np.all(gap[~np.eye(len(c), dtype=bool)] >= 4)


def test_batched_moves_change_the_energy_by_the_sum_of_single_moves():
    rng = np.random.default_rng(3)
    P = np.c_[np.cos(np.linspace(0, 2 * np.pi, 16, endpoint=False)), np.sin(np.linspace(0, 2 * np.pi, 16, endpoint=False)),
              np.zeros(16)] + 0.1 * rng.normal(size=(16, 3))
    J = colour_classes(16)[0]
    moves = 0.05 * rng.normal(size=(len(J), 3))
    single = 0.0
    for j, dv in zip(J, moves):
        Q = P.copy()
        Q[j] += dv
        single += planarity_energy(Q) - planarity_energy(P)
    Q = P.copy()
    Q[J] += moves
    assert planarity_energy(Q) - planarity_energy(P) == pytest.approx(single, abs=1e-10)


def test_annealing_keeps_the_loop_simple_throughout(bunny_loops):
    V, _, loops = bunny_loops
    P = V[loops[0].vertices]
    eps = 1e-5 * mean_edge(P)
    states = [P]

    def check(Q):
        assert min_segment_distance(Q) > eps
        # No vertex moves by half d_MD or more: two segments d_MD apart cannot meet on the way,
        # so the motion between two states is free of crossings, not only the states.
        assert np.linalg.norm(Q - states[-1], axis=1).max() < 0.5 * min_segment_distance(states[-1])
        for t in (0.25, 0.5, 0.75):
            assert min_segment_distance((1 - t) * states[-1] + t * Q) > eps
        states.append(Q.copy())

    A, stats = anneal_loop(P, np.random.default_rng(0), eps=eps, sa_steps=40 * len(P), stop_when_simple=False,
                           on_move=check)
    assert stats["accepted"] > 0 and len(states) > 20
    assert stats["d_md"] > eps


@pytest.mark.parametrize("step_bound", ["global", "local"])
def test_compiled_annealing_moves_equal_the_numpy_steps(bunny_loops, step_bound):
    # The kernels of _anneal_kernels against the numpy steps they replace: the same loop to the
    # last bit, the same statistics and the same generator state afterwards (restarts continue
    # from it), on wrapped, knotted and scanned loops, with uphill moves and cone directions.
    V, _, loops = bunny_loops
    for P in (wrapped_rectangle(), trefoil(), V[loops[0].vertices], V[loops[1].vertices]):
        eps = 1e-5 * mean_edge(P)
        runs = []
        for compiled in (True, False):
            rng = np.random.default_rng(5)
            A, stats = anneal_loop(P, rng, eps=eps, sa_steps=30 * len(P), step_bound=step_bound,
                                   stop_when_simple=False, compiled=compiled)
            runs.append((A, stats, rng.random()))
        (A, stats, after), (B, reference, after_reference) = runs
        assert np.array_equal(A, B)
        assert stats == reference and after == after_reference
        assert stats["accepted"] > 0


def test_warm_up_loads_the_annealing_kernels():
    from meshlab_holefill.algorithms.brunton2009 import _anneal_kernels as K
    cu.WARM_UP()
    for name in ("propose_moves", "apply_moves"):
        assert len(getattr(K, name).signatures) >= 1, name


def test_linear_motion_to_the_projection_is_checked_exactly(bunny_loops):
    V, _, loops = bunny_loops
    P = V[loops[0].vertices]
    A, _ = anneal_loop(P, np.random.default_rng(1), eps=1e-5 * mean_edge(P), sa_steps=20 * len(P),
                       stop_when_simple=False)
    Q, projected, normal = project_to_best_plane(A)
    assert np.abs((projected - projected.mean(0)) @ normal).max() < 1e-12  # planar
    if linear_motion_is_simple(Q, 1e-9):
        for t in np.linspace(0, 1, 11):
            assert min_segment_distance(A + t * (projected - A)) > 0
    # A loop wrapped around a cylinder collides with itself on the way to its projection.
    W = wrapped_rectangle()
    assert not linear_motion_is_simple(project_to_best_plane(W)[0], 1e-9)


def test_annealing_unfolds_a_wrapped_loop_and_is_reproducible():
    W = wrapped_rectangle()
    Q, info = unfold_loop(W, np.random.default_rng(0))
    assert info["method"] == "annealing" and info["sa_steps"] > 0
    assert linear_motion_is_simple(Q, 1e-5 * mean_edge(W))
    Q2, info2 = unfold_loop(W, np.random.default_rng(0))
    assert np.array_equal(Q, Q2) and info == info2


def test_a_knotted_loop_fails_clearly_after_its_restarts():
    with pytest.raises(HoleFillError, match="unfolding failed: no annealing run out of 5 .*knotted"):
        unfold_loop(trefoil(), np.random.default_rng(0), max_restarts=5)


@pytest.mark.parametrize("loop, message", [
    (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]], float), "touches itself"),
    (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), "zero-area"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], float), "non-finite"),
    (np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0], [2, 1, 0]], float), "touches itself"),  # a bow tie
])
def test_degenerate_loops_fail_clearly(loop, message):
    with pytest.raises(HoleFillError, match=message):
        unfold_loop(loop, np.random.default_rng(0))
