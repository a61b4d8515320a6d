"""Pfeifle-Seidel density refinement of geometry.refine."""
import numpy as np
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.geometry.refine import refine_patch, split_condition


def test_refinement_matches_the_boundary_density():
    k = 48
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    P = np.stack([np.cos(t), np.sin(t), np.zeros(k)], 1)
    F = np.array([[0, i, i + 1] for i in range(1, k - 1)])
    h = 2 * np.sin(np.pi / k)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    V, F2, scale, info = refine_patch(P, F, np.full(k, h), fixed_edges=loop)
    assert len(V) > k + 100  # interior filled with vertices
    assert not split_condition(V, F2, scale, np.sqrt(2))[0].any()  # converged
    E = np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    assert 0.7 < lengths.mean() / h < 1.4
    # Splits and swaps alone do not move vertices: fair quality, not the best.
    assert triangle_quality(V, F2).mean() > 0.7


def test_compiled_split_test_matches_the_numpy_code_bit_for_bit():
    from meshlab_holefill.geometry import _refine_kernels as RK
    from meshlab_holefill.geometry.refine import split_condition, split_condition_numpy

    rng = np.random.default_rng(4)
    for _ in range(50):
        V = rng.normal(size=(40, 3)) * 10.0 ** rng.integers(-3, 4)
        F = rng.integers(0, 40, (60, 3))
        scale = rng.uniform(0.1, 2.0, 40) * np.abs(V).max()
        alpha = float(rng.uniform(0.5, 3.0))
        mask, C, sc, sure = RK.split_test(V, F, scale, alpha)
        want = split_condition_numpy(V, F, scale, alpha)
        got = split_condition(V, F, scale, alpha)
        for x, y in zip(got, want):
            np.testing.assert_array_equal(x, y)
        if sure:
            np.testing.assert_array_equal(mask, want[0])
            np.testing.assert_array_equal(C.view(np.int64), want[1].view(np.int64))
            np.testing.assert_array_equal(sc.view(np.int64), want[2].view(np.int64))


def test_a_corner_angle_at_the_limit_is_left_to_numpy():
    from meshlab_holefill.geometry import _refine_kernels as RK
    from meshlab_holefill.geometry.refine import split_condition, split_condition_numpy

    t = 5 * np.pi / 6  # a corner of exactly 150 degrees up to rounding
    V = np.array([[0, 0, 0], [1, 0, 0], [np.cos(t), np.sin(t), 0]])
    F = np.array([[0, 1, 2]])
    assert not RK.split_test(V, F, np.full(3, 0.01), 1.4)[3]
    for x, y in zip(split_condition(V, F, np.full(3, 0.01), 1.4), split_condition_numpy(V, F, np.full(3, 0.01), 1.4)):
        np.testing.assert_array_equal(x, y)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_split_faces_puts_each_centroid_in_three_faces_that_tile_its_face(seed):
    from meshlab_holefill.geometry._refine_kernels import split_faces

    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(3, 20)), int(rng.integers(1, 15))
    V, scale = rng.random((n, 3)), rng.random(n)
    F = rng.integers(0, n, (m, 3))
    mask, C, sc = rng.random(m) < 0.5, rng.random((m, 3)), rng.random(m)
    V2, F2, scale2 = split_faces(V, F, scale, mask, C, sc)
    idx = np.flatnonzero(mask)
    c = n + np.arange(len(idx))  # new vertices in the order of their faces
    np.testing.assert_array_equal(V2, np.concatenate([V, C[idx]]))
    np.testing.assert_array_equal(scale2, np.concatenate([scale, sc[idx]]))
    np.testing.assert_array_equal(F2[~np.concatenate([mask, np.ones(2 * len(idx), bool)])], F[~mask])
    i, j, k = F[idx].T
    np.testing.assert_array_equal(F2[idx], np.stack([c, j, k], 1))
    np.testing.assert_array_equal(F2[m:], np.concatenate([np.stack([i, c, k], 1), np.stack([i, j, c], 1)]))
