"""Hu et al. Sec. III.B-C: the hole-border sector test (LoopSectors), compiled and numpy."""
import numpy as np


def random_loop_sectors(rng):
    """A bumpy loop of 3-29 points around the z axis with noisy normals, and its LoopSectors: (k, P, sectors)."""
    from meshlab_holefill.algorithms.hu2012.hole_guards import LoopSectors

    k = int(rng.integers(3, 30))
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    P = np.stack([np.cos(t), np.sin(t), 0.2 * rng.normal(size=k)], axis=1)
    N = np.array([0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=(k, 3))
    return k, P, LoopSectors(P, N)


def test_compiled_sector_test_answers_as_the_numpy_code():
    rng = np.random.default_rng(8)
    for _ in range(30):
        k, P, sectors = random_loop_sectors(rng)
        i = rng.integers(0, k, 200)
        targets = np.concatenate([rng.normal(size=(190, 3)), P[rng.integers(0, k, 10)]])  # loop points too
        np.testing.assert_array_equal(sectors.contains(i, targets), sectors.contains_numpy(i, targets))


def test_compiled_swap_sector_test_answers_as_the_numpy_code_at_both_ends():
    rng = np.random.default_rng(9)
    for _ in range(30):
        k, P, sectors = random_loop_sectors(rng)
        V = np.concatenate([P, 0.5 * rng.normal(size=(20, 3))])  # loop first, then interior points
        B = np.stack([rng.integers(0, len(V), 200), rng.integers(0, len(V), 200), rng.integers(0, len(V), 200)], 1)
        oracle = np.ones(len(B), bool)
        for end, other in ((B[:, 1], B[:, 2]), (B[:, 2], B[:, 1])):
            on_loop = end < k
            oracle[on_loop] &= sectors.contains_numpy(end[on_loop], V[other[on_loop]])
        assert (~oracle).any() and oracle.any()
        np.testing.assert_array_equal(sectors.swaps_allowed(V, B), oracle)


def test_a_direction_on_the_sector_bound_is_left_to_numpy():
    from meshlab_holefill.algorithms.hu2012._sector_kernels import sector_contains
    from meshlab_holefill.algorithms.hu2012.hole_guards import LoopSectors

    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    sectors = LoopSectors(P, np.tile([0.0, 0.0, 1.0], (3, 1)))
    i = np.array([0, 0])
    targets = np.array([[2.0, 0.0, 0.0], [0.5, 0.5, 0.0]])  # along the next edge (angle 0), and inside
    assert not sector_contains(sectors.points, sectors.u, sectors.w, sectors.limit, i, targets, 0.0)[1]
    np.testing.assert_array_equal(sectors.contains(i, targets, margin=0.0), sectors.contains_numpy(i, targets, 0.0))
    assert sectors.contains(i[1:], targets[1:]).tolist() == [True]
