"""The bilateral filter of Hu et al. Sec. III.D (after Fleishman et al.)."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter
from meshlab_holefill.geometry.quality import triangle_quality
from conftest import grid


def test_bilateral_filter_pulls_a_bump_back_and_keeps_a_plane():
    V, F = grid(7, 7)
    movable = np.zeros(len(V), bool)
    centre = 24
    movable[centre] = True
    flat = bilateral_filter(V, F, movable, 0.1, 0.5, iterations=3)
    assert np.allclose(flat, V)
    bumped = V.copy()
    bumped[centre, 2] = 0.05
    out = bilateral_filter(bumped, F, movable, sigma_c=1 / 6, sigma_s=0.5 / 6, iterations=3)
    assert abs(out[centre, 2]) < 0.05 * 0.5
    assert np.array_equal(out[~movable], bumped[~movable])


def _symmetric_fan(r0, z0, r1, z1):
    """Vertex 0 at the origin with the 1-ring (r0, 0, z0), (0, r1, z1), (-r0, 0, z0), (0, -r1, z1).

    The ring is symmetric under (x, y) -> (-x, -y), so the area-weighted normal at vertex 0 is
    exactly +z, and each neighbour's h = <n, v - q> is minus its height.
    """
    V = np.array([[0, 0, 0], [r0, 0, z0], [0, r1, z1], [-r0, 0, z0], [0, -r1, z1]], float)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    movable = np.array([True, False, False, False, False])
    return V, F, movable


def _fleishman_height(ts, hs, sigma_c, sigma_s, range_term=True):
    """Height of v = 0 after one step: v - n sum(w h) / sum(w) with h = -z, i.e. sum(w z) / sum(w)."""
    ts, zs = np.asarray(ts, float), -np.asarray(hs, float)
    w = np.exp(-ts ** 2 / (2 * sigma_c ** 2) - (zs ** 2 / (2 * sigma_s ** 2) if range_term else 0))
    return float((w * zs).sum() / w.sum())


def test_bilateral_step_is_the_fleishman_weighted_average_of_the_one_ring():
    """One step moves v along n by sum(w_i h_i) / sum(w_i), w_i = exp(-t^2/2sc^2) exp(-h^2/2ss^2).

    The near neighbours (distance 1, height 0.1) and the far ones (distance 2, height 0.4) make
    the closeness and the range kernels weigh differently, so exchanging sigma_c and sigma_s (or
    dropping either kernel) changes the result.
    """
    V, F, movable = _symmetric_fan(1.0, 0.1, 2.0, 0.4)
    sigma_c, sigma_s = 1.0, 0.25
    # By hand: t^2 = 1.01 and 4.16, h = -0.1 and -0.4;
    # log w = -1.01/2 - 0.01/0.125 = -0.585 and -4.16/2 - 0.16/0.125 = -3.36.
    w_near, w_far = np.exp(-0.585), np.exp(-3.36)
    expected = (0.1 * w_near + 0.4 * w_far) / (w_near + w_far)
    assert expected == pytest.approx(0.117607, abs=1e-6)
    assert expected == pytest.approx(_fleishman_height([1.01 ** 0.5, 4.16 ** 0.5], [-0.1, -0.4], sigma_c, sigma_s))
    out = bilateral_filter(V, F, movable, sigma_c, sigma_s, iterations=1)
    assert out[0] == pytest.approx([0, 0, expected], abs=1e-12)
    assert np.array_equal(out[1:], V[1:])
    # Per-vertex widths: the moving vertex's own sigma_c, sigma_s are used, not its neighbours'.
    sc = np.array([sigma_c, 50.0, 0.01, 7.0, 3.0])
    ss = np.array([sigma_s, 0.01, 50.0, 3.0, 7.0])
    assert bilateral_filter(V, F, movable, sc, ss, iterations=1)[0] == pytest.approx([0, 0, expected], abs=1e-12)
    # Exchanging the two widths gives a clearly different point (the near neighbours dominate).
    swapped = _fleishman_height([1.01 ** 0.5, 4.16 ** 0.5], [-0.1, -0.4], sigma_s, sigma_c)
    assert abs(swapped - expected) > 0.01


def test_bilateral_range_term_downweights_a_neighbour_across_a_crease():
    """The feature-preserving kernel exp(-h^2 / 2 sigma_s^2) weighs a neighbour 0.5 along the
    normal (across a crease) less than the closeness kernel alone, so v moves less toward it,
    the less the narrower sigma_s is."""
    V, F, movable = _symmetric_fan(1.0, 0.0, 1.0, 0.5)  # two neighbours in v's plane, two 0.5 up
    sigma_c = 1.0
    t = np.sqrt([1.0, 1.25])
    closeness_only = _fleishman_height(t, [0.0, -0.5], sigma_c, 1.0, range_term=False)
    heights = []
    for sigma_s in (0.1, 0.2, 0.4, 1.0):
        # By hand: near pair w = exp(-1/2), far pair w = exp(-1.25/2 - 0.25/(2 sigma_s^2)).
        w_near, w_far = np.exp(-0.5), np.exp(-0.625 - 0.125 / sigma_s ** 2)
        expected = 0.5 * w_far / (w_near + w_far)
        out = bilateral_filter(V, F, movable, sigma_c, sigma_s, iterations=1)
        assert out[0] == pytest.approx([0, 0, expected], abs=1e-12)
        heights.append(out[0, 2])
    assert np.all(np.diff(heights) > 0) and heights[-1] < closeness_only
    assert heights[0] < 1e-3 * closeness_only  # sigma_s = 0.1: the crease is kept


def test_bilateral_guard_refuses_a_move_that_flips_a_face_of_good_quality():
    """min_quality also undoes moves that turn a face over, even when its 2r/R stays good.

    v = (0, 0, 1) is a roof over a thin rectangle (two steep faces along it) with two neighbours
    far below (z = -3) at the ends; its normal is +z by symmetry and the mean height of its ring
    is -1, so with (nearly) equal weights v moves to z = -1: the steep faces are mirrored through
    z = 0, same quality but reversed normals, and the other faces become better shaped.
    """
    V = np.array([[0, 0, 1.0], [2, 0, -3], [1, 0.2, 0], [-1, 0.2, 0], [-2, 0, -3], [-1, -0.2, 0], [1, -0.2, 0]])
    F = np.array([[0, i, i % 6 + 1] for i in range(1, 7)])
    movable = np.arange(7) == 0

    def cross(X):
        return np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])

    free = bilateral_filter(V, F, movable, 1e3, 1e3, iterations=1)
    assert free[0] == pytest.approx([0, 0, -1], abs=1e-4)
    flipped = np.einsum("ij,ij->i", cross(V), cross(free)) <= 0
    assert flipped.tolist() == [False, True, False, False, True, False]
    # The quality test alone would accept the move: no face drops below min(0.5, its old quality).
    assert np.all(triangle_quality(free, F) >= np.minimum(triangle_quality(V, F), 0.5))
    guarded = bilateral_filter(V, F, movable, 1e3, 1e3, iterations=1, min_quality=0.5)
    assert np.all(np.einsum("ij,ij->i", cross(V), cross(guarded)) > 0)
    assert np.array_equal(guarded, V)  # the only move was the flipping one


def test_compiled_sliver_guard_matches_the_numpy_code_bit_for_bit():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import _refuse_slivers, _refuse_slivers_numpy
    from conftest import grid

    rng = np.random.default_rng(6)
    for trial in range(40):
        V, F = grid(int(rng.integers(3, 9)), int(rng.integers(3, 9)))
        V = V + rng.normal(scale=0.05, size=V.shape)
        moved = rng.random(len(V)) < 0.6
        V_new = V + moved[:, None] * rng.normal(scale=10.0 ** rng.uniform(-3, 0), size=V.shape)
        floor = float(rng.uniform(0.0, 1.0))
        got = _refuse_slivers(V, V_new, F, moved, floor)
        want = _refuse_slivers_numpy(V, V_new, F, moved, floor)
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))


def test_ring_pairs_are_the_entries_of_the_one_ring_matrix():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import _ring_pairs, _row_maxima
    from meshlab_holefill.geometry.topology import one_ring_matrix

    rng = np.random.default_rng(7)
    for _ in range(30):
        n = int(rng.integers(3, 40))
        F = rng.integers(0, n, (int(rng.integers(1, 60)), 3))
        A = one_ring_matrix(F, n).tocoo()
        rows, cols = _ring_pairs(F, n)
        np.testing.assert_array_equal(rows, A.row)
        np.testing.assert_array_equal(cols, A.col)
        values = rng.normal(size=len(rows))
        expected = np.full(n, -np.inf)
        np.maximum.at(expected, rows, values)
        np.testing.assert_array_equal(_row_maxima(rows, values, n), expected)


def test_compiled_ring_iterations_match_the_numpy_code_bit_for_bit():
    from meshlab_holefill.geometry._quality_kernels import unit_vertex_normals
    from meshlab_holefill.geometry.quality import vertex_normals_numpy

    rng = np.random.default_rng(11)
    for trial in range(40):
        V, F = grid(int(rng.integers(3, 9)), int(rng.integers(3, 9)))
        V = V + rng.normal(scale=10.0 ** rng.uniform(-3, -0.5), size=V.shape)
        F = F[rng.random(len(F)) < 0.9] if trial % 3 == 0 else F  # vertices without faces too
        np.testing.assert_array_equal(unit_vertex_normals(V, np.asarray(F, np.int64), len(V)).view(np.int64),
                                      vertex_normals_numpy(V, F, len(V)).view(np.int64))
        movable = rng.random(len(V)) < 0.7
        scale = 10.0 ** rng.uniform(-2, 0, len(V)) if trial % 2 else 0.3  # per-vertex or global widths
        guard = None if trial % 4 == 0 else float(rng.uniform(0.0, 0.6))
        args = (V, F, movable, 0.1 * scale, 0.5 * scale, int(rng.integers(1, 4)))
        got = bilateral_filter(*args, min_quality=guard)
        want = bilateral_filter(*args, min_quality=guard, compiled=False)
        assert np.any(got != V)  # the filter moved something
        np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64))
