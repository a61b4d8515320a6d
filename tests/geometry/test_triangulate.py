"""Constrained Delaunay triangulation of geometry.triangulate."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.geometry.triangulate import triangulate_polygon
from meshlab_holefill.core.patch import HoleFillError


def test_constrained_triangulation_keeps_the_polygon_and_adds_no_point():
    # An L-shaped (non-convex) polygon.
    Q = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    P, T = triangulate_polygon(Q)
    assert len(P) == 6 and len(T) == 4
    edges = {tuple(sorted(e)) for t in T for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    assert all(tuple(sorted((i, (i + 1) % 6))) in edges for i in range(6))
    A = P[T]
    signed = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    assert np.all(signed > 0)
    P2, T2 = triangulate_polygon(Q[::-1])
    A = P2[T2]
    signed = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    assert np.all(signed < 0)


def test_constrained_triangulation_rejects_a_self_intersecting_polygon():
    bowtie = np.array([[0, 0], [2, 2], [2, 0], [0, 2]], float)  # edges (0,1) and (2,3) cross at (1,1)
    with pytest.raises(HoleFillError, match="polygon is not simple"):
        triangulate_polygon(bowtie)


def test_constrained_triangulation_rejects_coincident_vertices_before_triangle_crashes():
    # A polygon through the same point twice (an unwelded border vertex); Triangle segfaults on it.
    pinched = np.array([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2], [1, 1]], float)
    with pytest.raises(HoleFillError, match="two vertices at the same position"):
        triangulate_polygon(pinched)
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    with pytest.raises(HoleFillError, match="two vertices at the same position"):
        triangulate_polygon(square, extra_points=np.array([[0.5, 0.5], [0.5, 0.5]]))


@pytest.mark.parametrize("scale", [1e-9, 1e-4, 1.0, 1e4, 1e9])
def test_area_bounded_refinement_does_not_depend_on_the_unit(scale):
    """The area bound reaches Triangle whatever its exponent (it reads digits and '.' only)."""
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    circle = np.stack([np.cos(t), np.sin(t)], axis=1)
    edge = np.linalg.norm(circle[1] - circle[0])
    P, T = triangulate_polygon(circle * scale, max_area=np.sqrt(3) / 4 * (edge * scale) ** 2, min_angle=30)
    # about pi / (sqrt(3)/4 edge^2) = 1170 triangles at unit scale; rounding of the scaled input moves it a little
    assert 1100 < len(T) < 1250
    u, w = P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
    assert area.max() <= np.sqrt(3) / 4 * (edge * scale) ** 2 * (1 + 1e-9)
    assert area.sum() == pytest.approx(0.5 * 64 * np.sin(2 * np.pi / 64) * scale ** 2, rel=1e-9)


@settings(max_examples=300, deadline=None)
@given(st.integers(1, 12), st.integers(0, 2**31 - 1), st.booleans(), st.booleans())
def test_repeated_points_are_found_as_numpy_unique_finds_them(n, seed, with_nan, signed_zeros):
    """The coincident-point test before Triangle answers as len(np.unique(points, axis=0)) < n:
    coordinates compared as numbers, so 0.0 and -0.0 coincide and NaN coincides with nothing."""
    from meshlab_holefill.geometry.triangulate import _has_repeated_rows

    rng = np.random.default_rng(seed)
    points = rng.integers(-1, 2, (n, 2)).astype(float)  # few values: repeats are common
    if with_nan:
        points[rng.integers(0, n, 2)] = np.nan
    if signed_zeros:
        points[points == 0] = -0.0
    assert _has_repeated_rows(points) == (len(np.unique(points, axis=0)) < n)


@settings(max_examples=100, deadline=None)
@given(st.integers(3, 40), st.integers(0, 2**31 - 1))
def test_polygon_area_and_perimeter_are_the_rolled_formulas_bit_for_bit(m, seed):
    from meshlab_holefill.geometry.triangulate import polygon_perimeter, polygon_signed_area

    Q = np.random.default_rng(seed).normal(size=(m, 2)) * 10.0 ** np.random.default_rng(seed).integers(-6, 6)
    x, y = Q[:, 0], Q[:, 1]
    assert polygon_signed_area(Q) == 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    assert polygon_perimeter(Q) == float(np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1).sum())
