"""Constrained Delaunay triangulation of geometry.triangulate."""
import numpy as np
import pytest

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
