"""Polygon tests of geometry.segments against an exact O(m^2) pairwise reference.

is_simple_polygon and polygon_edges_touch are compared with exact rational orientation tests
(and the clearance with an independent pairwise distance computation).
"""
import numpy as np
from hypothesis import assume, given, settings, strategies as st

from meshlab_holefill.geometry.segments import is_simple_polygon
from exact_predicates import closed_segments_meet, orient, point_segment_distance


def _reference_simple(Q):
    """Exact O(m^2) test of a closed polygon: distinct vertices, non-adjacent edges disjoint,
    adjacent edges meeting only at their common vertex (no fold back), no degenerate triangle."""
    Q = [tuple(p) for p in Q]
    m = len(Q)
    if len(set(Q)) < m:
        return False
    if m == 3:
        return orient(*Q) != 0
    for i in range(m):
        p, v, q = Q[i - 1], Q[i], Q[(i + 1) % m]
        # Consecutive edges p-v, v-q overlap iff collinear and turning back (dot > 0).
        if orient(p, v, q) == 0 and (p[0] - v[0]) * (q[0] - v[0]) + (p[1] - v[1]) * (q[1] - v[1]) > 0:
            return False
        for j in range(i + 2, m):
            if i == 0 and j == m - 1:
                continue  # adjacent through the closing edge
            if closed_segments_meet(Q[i], Q[(i + 1) % m], Q[j], Q[(j + 1) % m]):
                return False
    return True


def _reference_clearance(Q):
    """d_MD in 2D: the smallest distance between non-adjacent edges, 0 when two of them meet;
    otherwise the distance of two disjoint 2D segments is attained at an end point."""
    m = len(Q)
    best = np.inf
    for i in range(m):
        for j in range(i + 2, m):
            if i == 0 and j == m - 1:
                continue
            a0, a1, b0, b1 = Q[i], Q[(i + 1) % m], Q[j], Q[(j + 1) % m]
            if closed_segments_meet(a0, a1, b0, b1):
                return 0.0
            best = min(best, point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1),
                       point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1))
    return best


def test_is_simple_polygon_on_hand_cases():
    square = np.array([[0, 0], [2, 0], [2, 2], [0, 2]], float)
    assert is_simple_polygon(square, 1e-9) and is_simple_polygon(square[::-1], 1e-9)
    assert not is_simple_polygon(square[[0, 2, 1, 3]], 1e-9)  # bow tie
    # A non-convex U whose arms are 0.2 apart: simple, with clearance 0.2.
    U = np.array([[0, 0], [3, 0], [3, 2], [1.6, 2], [1.6, 0.5], [1.4, 0.5], [1.4, 2], [0, 2]], float)
    assert is_simple_polygon(U, 0.19) and not is_simple_polygon(U, 0.21)
    # A spike folding back along its own edge.
    assert not is_simple_polygon(np.array([[0, 0], [2, 0], [1, 0], [0, 1]], float), 1e-9)
    # Triangles: simple unless degenerate.
    assert is_simple_polygon(np.array([[0, 0], [1, 0], [0, 1]], float), 1e-9)
    assert not is_simple_polygon(np.array([[0, 0], [1, 1], [2, 2]], float), 1e-9)


small_grid_point = st.tuples(st.integers(0, 4), st.integers(0, 4))


@settings(max_examples=200, deadline=None)
@given(st.lists(small_grid_point, min_size=3, max_size=7))
def test_is_simple_polygon_matches_exact_pairwise_intersection_on_a_grid(points):
    """On integer coordinates disjoint segments are at least ~1/8 apart, so eps = 1e-9 turns the
    clearance test into an exact simplicity test: touching and overlapping edges included."""
    Q = np.array(points, np.float64)
    expected = _reference_simple(points)
    assert is_simple_polygon(Q, 1e-9) is expected
    assert is_simple_polygon(Q, 1e-9, near=0.5) is expected
    # Orientation and starting vertex do not matter.
    assert is_simple_polygon(Q[::-1], 1e-9) is expected
    assert is_simple_polygon(np.roll(Q, 2, axis=0), 1e-9) is expected


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.floats(0, 2 * np.pi), st.floats(0.2, 2.0)), min_size=4, max_size=9),
       st.booleans(), st.floats(0.0, 0.5))
def test_is_simple_polygon_compares_the_clearance_with_eps(polar, star, eps):
    """Sorted by angle the points make a star-shaped (simple) polygon, unsorted mostly not; either
    way the answer is d_MD > eps with d_MD from an independent pairwise computation."""
    if star:
        polar = sorted(polar)
    Q = np.array([[r * np.cos(a), r * np.sin(a)] for a, r in polar])
    d = _reference_clearance(Q)
    assume(abs(d - eps) > 1e-9)
    assert is_simple_polygon(Q, eps) is bool(d > eps)
    assert is_simple_polygon(Q, eps, near=eps + 0.1) is bool(d > eps)


@settings(max_examples=200, deadline=None)
@given(st.lists(small_grid_point, min_size=4, max_size=8))
def test_polygon_edges_touch_is_any_pairwise_touch_of_non_adjacent_edges(points):
    """The vectorised test against the exact rational one, pair by pair."""
    from meshlab_holefill.geometry.segments import polygon_edges_touch, polygon_edges_touch_numpy

    Q = np.array(points, np.float64)
    k = len(Q)
    expected = any(closed_segments_meet(Q[i], Q[(i + 1) % k], Q[j], Q[(j + 1) % k])
                   for i in range(k) for j in range(i + 2, k) if not (i == 0 and j == k - 1))
    assert polygon_edges_touch(Q) is expected
    assert polygon_edges_touch(Q[::-1]) is expected
    assert polygon_edges_touch_numpy(Q) is polygon_edges_touch_numpy(Q, chunk=3) is expected


def test_compiled_edge_touch_test_equals_numpy_on_random_loops():
    # Jittered circles, some folded (a vertex pulled across), with repeated points and NaNs.
    from meshlab_holefill.geometry.segments import polygon_edges_touch, polygon_edges_touch_numpy

    rng = np.random.default_rng(2)
    seen = set()
    for t in range(300):
        k = int(rng.integers(3, 40))
        angle = np.sort(rng.uniform(0, 2 * np.pi, k))
        Q = np.stack([np.cos(angle), np.sin(angle)], axis=1) * rng.uniform(0.5, 1.5, (k, 1))
        if t % 3 == 0:
            Q[rng.integers(0, k)] *= -0.5
        if t % 7 == 0:
            Q[rng.integers(0, k)] = Q[rng.integers(0, k)]
        if t % 29 == 0:
            Q[rng.integers(0, k), rng.integers(0, 2)] = np.nan
        want = polygon_edges_touch_numpy(Q)
        assert polygon_edges_touch(Q) is want
        seen.add(want)
    assert seen == {True, False}


# ----------------------------------------------------------------- compiled distance kernels

def _numpy_distance_rows(A0, A1, B0, B1, allowed, near):
    """The numpy formulation the compiled segment_distance_rows reproduces bit for bit (oracle)."""
    from meshlab_holefill.geometry.segments import segment_distances

    ca, cb = 0.5 * (A0 + A1), 0.5 * (B0 + B1)
    ra = 0.5 * np.sqrt(((A1 - A0) ** 2).sum(axis=1))
    rb = 0.5 * np.sqrt(((B1 - B0) ** 2).sum(axis=1))
    rows = np.sqrt(((ca[:, None, :] - cb[None, :, :]) ** 2).sum(axis=2)) - ra[:, None] - rb[None, :]
    rows[~allowed] = np.inf
    i, j = np.nonzero(rows <= near)
    rows[i, j] = segment_distances(A0[i], A1[i], B0[j], B1[j])
    return rows


def _random_segments(rng, n, d):
    """Segments of random length, some near-degenerate or points (the clamping branches)."""
    A0 = rng.normal(size=(n, d)) * rng.choice([1e-3, 1.0, 1e3])
    return A0, A0 + rng.normal(size=(n, d)) * rng.choice([1.0, 1e-9, 0.0], size=(n, 1))


def test_segment_distance_rows_equals_the_numpy_formulas_bit_for_bit():
    from meshlab_holefill.geometry.segments import segment_distance_rows

    rng = np.random.default_rng(0)
    for t in range(300):
        d = 2 + t % 2
        na, nb = rng.integers(1, 25, 2)
        A0, A1 = _random_segments(rng, na, d)
        B0, B1 = _random_segments(rng, nb, d)
        if t % 3 == 0:  # parallel copies: the denom <= 1e-14 a e branch
            k = min(na, nb)
            B0[:k], B1[:k] = A0[:k] + 0.1, A1[:k] + 0.1
        allowed = rng.random((na, nb)) < 0.8
        near = float(rng.choice([0.5, 2.0, np.inf]))
        expected = _numpy_distance_rows(A0, A1, B0, B1, allowed, near)
        np.testing.assert_array_equal(segment_distance_rows(A0, A1, B0, B1, allowed, near), expected)


def test_segment_distance_matrix_equals_the_numpy_formulas_bit_for_bit():
    from meshlab_holefill.geometry.segments import nonadjacent_mask, segment_distance_matrix, segment_distances

    rng = np.random.default_rng(1)
    for t in range(200):
        m, d = int(rng.integers(3, 30)), 2 + t % 2
        P = rng.normal(size=(m, d)) * rng.choice([1e-3, 1.0, 1e3])
        if t % 4 == 0:
            P[1] = P[0]  # a point segment
        Q = np.roll(P, -1, axis=0)
        exact = segment_distances(P[:, None, :], Q[:, None, :], P[None, :, :], Q[None, :, :])
        exact[~nonadjacent_mask(m)] = np.inf
        np.testing.assert_array_equal(segment_distance_matrix(P), exact)
        near = float(rng.choice([0.1, 1.0]))
        np.testing.assert_array_equal(segment_distance_matrix(P, near),
                                      _numpy_distance_rows(P, Q, P, Q, nonadjacent_mask(m), near))


@settings(max_examples=150, deadline=None)
@given(st.integers(4, 40), st.floats(0.0, 0.3), st.floats(0.0, 0.6), st.booleans(), st.integers(0, 2**31 - 1))
def test_is_simple_polygon_stops_early_with_the_answer_of_the_full_matrix(m, noise, eps, with_near, seed):
    """The compiled early-exit test gives the answer of ``min_segment_distance(Q, near) > eps``
    (the full distance matrix) on jittered circles, simple or not, with and without ``near``."""
    from meshlab_holefill.geometry.segments import min_segment_distance

    rng = np.random.default_rng(seed)
    angle = np.sort(rng.uniform(0, 2 * np.pi, m))
    Q = np.stack([np.cos(angle), np.sin(angle)], axis=1) + rng.normal(0, noise, (m, 2))
    near = eps + 0.2 if with_near else None
    assert is_simple_polygon(Q, eps, near) is bool(min_segment_distance(Q, near) > eps)
