"""Geometric predicates of the advancing front (xu2013._front_predicates) against brute-force references.

segments_cross is compared with exact rational orientation tests, point_triangle_distance with
a two-variable quadratic program solved in barycentric coordinates (and bracketed by dense
sampling).
"""
import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from meshlab_holefill.algorithms.xu2013._front_predicates import point_triangle_distance, segments_cross
from exact_predicates import closed_segments_meet, orient, point_segment_distance


@pytest.mark.parametrize("a0, a1, b0, b1, expected", [
    ((0, 0), (2, 2), (0, 2), (2, 0), True),    # proper crossing
    ((0, 0), (2, 0), (1, 0), (1, 3), True),    # T: an end point on the other's interior
    ((0, 0), (2, 0), (2, 0), (3, 5), True),    # shared end point
    ((0, 0), (2, 0), (1, 0), (5, 0), True),    # collinear overlap
    ((0, 0), (4, 4), (1, 1), (2, 2), True),    # collinear, one inside the other
    ((0, 0), (2, 0), (2, 0), (5, 0), True),    # collinear, touching at an end point
    ((0, 0), (2, 0), (3, 0), (5, 0), False),   # collinear, disjoint
    ((0, 0), (0, 2), (0, 3), (0, 5), False),   # collinear along y, disjoint
    ((0, 0), (2, 0), (0, 1), (2, 1), False),   # parallel
    ((0, 0), (2, 0), (1, 1e-3), (3, 5), False),  # misses by far more than the tolerance
    ((0, 0), (2, 2), (3, 0), (2.5, 1), False),  # the lines cross, the segments do not
])
def test_segments_cross_on_hand_cases(a0, a1, b0, b1, expected):
    assert segments_cross(a0, a1, b0, b1) is expected
    # Symmetric in the two segments and in the direction of each.
    assert segments_cross(b0, b1, a0, a1) is expected
    assert segments_cross(a1, a0, b1, b0) is expected


grid_point = st.tuples(st.integers(-5, 5), st.integers(-5, 5))


@settings(max_examples=200, deadline=None)
@given(grid_point, grid_point, grid_point, grid_point)
def test_segments_cross_matches_exact_rational_test_on_a_grid(a0, a1, b0, b1):
    """Integer coordinates: crossings, touchings and collinear overlaps are frequent and exact, and
    the tolerance 1e-9 scale^2 is far below the smallest non-zero orientation (1)."""
    assume(a0 != a1 and b0 != b1)
    expected = closed_segments_meet(a0, a1, b0, b1)
    assert segments_cross(a0, a1, b0, b1) is expected
    assert segments_cross(b1, b0, a0, a1) is expected
    # Scaling by a power of two and translating keep every orientation sign exactly.
    s = lambda p: (0.125 * p[0] + 3.0, 0.125 * p[1] - 7.0)  # noqa: E731
    assert segments_cross(s(a0), s(a1), s(b0), s(b1)) is expected


coordinate = st.floats(-10, 10, allow_nan=False, allow_infinity=False)


float_point = st.tuples(coordinate, coordinate)


@settings(max_examples=200, deadline=None)
@given(float_point, float_point, float_point, float_point)
def test_segments_cross_matches_exact_rational_test_away_from_degeneracy(a0, a1, b0, b1):
    """Arbitrary float segments whose exact orientations are all clear of the tolerance band."""
    scale = max(abs(a1[0] - a0[0]), abs(a1[1] - a0[1]), abs(b1[0] - b0[0]), abs(b1[1] - b0[1]))
    assume(scale > 1e-3)
    orients = [orient(a0, a1, b0), orient(a0, a1, b1), orient(b0, b1, a0), orient(b0, b1, a1)]
    assume(all(abs(o) > 1e-6 * scale * scale for o in orients))
    assert segments_cross(a0, a1, b0, b1) is closed_segments_meet(a0, a1, b0, b1)


def test_segments_cross_of_two_points_is_their_equality():
    assert segments_cross((0.0, 0.0), (0.0, 0.0), (0.0, 1.0), (0.0, 1.0)) is False
    assert segments_cross((0.0, 0.0), (0.0, 0.0), (1.0, 0.0), (1.0, 0.0)) is False
    assert segments_cross((0.5, 2.0), (0.5, 2.0), (0.5, 2.0), (0.5, 2.0)) is True


def _reference_distance(x, T):
    """Minimise |A + s (B - A) + t (C - A) - x| over s, t >= 0, s + t <= 1 (a convex QP).

    The unconstrained minimiser (normal equations) is the answer when it is feasible; otherwise
    the constrained one lies on the boundary, i.e. on one of the three edges.
    """
    A, B, C = T
    E = np.stack([B - A, C - A], axis=1)
    s, t = np.linalg.solve(E.T @ E, E.T @ (x - A))
    if s >= 0 and t >= 0 and s + t <= 1:
        return float(np.linalg.norm(A + E @ [s, t] - x))
    return min(point_segment_distance(x, A, B), point_segment_distance(x, B, C),
               point_segment_distance(x, C, A))


def _sampled_distance(x, T, n=60):
    """Minimum distance to the barycentric grid of spacing 1/n: an upper bound on the true
    distance that exceeds it by at most the longest edge / n."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1))
    keep = i + j <= n
    s, t = i[keep] / n, j[keep] / n
    P = T[0] + s[:, None] * (T[1] - T[0]) + t[:, None] * (T[2] - T[0])
    return float(np.linalg.norm(P - x, axis=1).min())


def test_point_triangle_distance_in_each_voronoi_region():
    T = np.array([[[0, 0, 0], [4, 0, 0], [0, 3, 0]]], float)
    cases = [
        ((1, 1, 2.5), 2.5),               # above the interior: the height
        ((1, 1, -0.5), 0.5),              # below: unsigned
        ((1, 1, 0), 0.0),                 # in the triangle
        ((2, -1, 1), np.sqrt(2)),         # beside edge AB (closest point (2, 0, 0))
        ((-2, 1, 0), 2.0),                # beside edge CA
        ((4, 3, 0), 12 / 5),              # beyond hypotenuse BC (line 3x + 4y = 12)
        ((-1, -2, 2), 3.0),               # beyond vertex A
        ((6, -1, 0), np.sqrt(5)),         # beyond vertex B
    ]
    for x, expected in cases:
        assert point_triangle_distance(np.array(x, float), T)[0] == pytest.approx(expected, abs=1e-12)


def test_point_triangle_distance_of_a_degenerate_triangle_is_the_distance_to_its_segment():
    # Collinear corners: the "triangle" is the segment from (0,0,0) to (2,0,0).
    T = np.array([[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 0, 0], [0, 0, 0], [2, 0, 0]]], float)
    assert point_triangle_distance(np.array([1.0, 3.0, 4.0]), T) == pytest.approx([5.0, 5.0])
    assert point_triangle_distance(np.array([5.0, 0.0, 4.0]), T) == pytest.approx([5.0, 5.0])


def _well_shaped(T, min_ratio=0.05):
    """2 * area / longest edge^2 above min_ratio (no needle or sliver)."""
    area2 = np.linalg.norm(np.cross(T[1] - T[0], T[2] - T[0]))
    longest = max(np.sum((T[k] - T[(k + 1) % 3]) ** 2) for k in range(3))
    return area2 > min_ratio * longest and longest > 1e-2


vec3 = st.tuples(*[st.floats(-2, 2)] * 3)


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(vec3, vec3, vec3), min_size=1, max_size=5), st.tuples(*[st.floats(-3, 3)] * 3))
def test_point_triangle_distance_matches_a_brute_force_minimum(triangles, x):
    T = np.array(triangles, np.float64)
    assume(all(_well_shaped(t) for t in T))
    x = np.array(x, np.float64)
    d = point_triangle_distance(x, T)  # all rows at once: rows must not leak into each other
    assert d.shape == (len(T),)
    for k, t in enumerate(T):
        assert d[k] == pytest.approx(_reference_distance(x, t), rel=1e-9, abs=1e-9)
        # Independent bracket by sampling: d <= sampled <= d + longest edge / n.
        n = 60
        sampled = _sampled_distance(x, t, n)
        longest = max(np.linalg.norm(t[i] - t[(i + 1) % 3]) for i in range(3))
        assert d[k] <= sampled + 1e-12
        assert sampled <= d[k] + longest / n + 1e-12


@settings(max_examples=100, deadline=None)
@given(st.tuples(vec3, vec3, vec3), st.floats(0.01, 0.98), st.floats(0.01, 0.98), st.floats(-3, 3))
def test_point_triangle_distance_over_the_interior_is_the_offset_along_the_normal(tri, s, t, h):
    T = np.array([tri], np.float64)
    assume(_well_shaped(T[0]) and s + t < 0.99)
    A, B, C = T[0]
    n = np.cross(B - A, C - A)
    n /= np.linalg.norm(n)
    x = A + s * (B - A) + t * (C - A) + h * n
    assert point_triangle_distance(x, T)[0] == pytest.approx(abs(h), rel=1e-9, abs=1e-9)
