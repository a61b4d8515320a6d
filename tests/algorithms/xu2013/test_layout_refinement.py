"""A planar layout whose lift stretches it is refined to the boundary's density before the Poisson solve."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.algorithms.xu2013.advancing_front import advancing_front_triangulation
from meshlab_holefill.algorithms.xu2013.poisson_patch import LIFT_STRETCH, harmonic_lift, lift_stretch, refine_layout
from meshlab_holefill.geometry.quality import unique_edges


def circle(k, radius=1.0):
    t = 2.0 * np.pi * np.arange(k) / k
    return np.stack([radius * np.cos(t), radius * np.sin(t), np.zeros(k)], axis=1)


def ellipse(k, aspect):
    """An ellipse of perimeter 2 pi and the given aspect ratio, k points at equal arc length."""
    t = np.linspace(0.0, 2.0 * np.pi, 20001)
    Q = np.stack([np.cos(t), np.sin(t) / aspect], axis=1)
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(Q, axis=0), axis=1))])
    s = np.arange(k) * arc[-1] / k
    E = np.stack([np.interp(s, arc, Q[:, 0]), np.interp(s, arc, Q[:, 1])], axis=1) * (2.0 * np.pi / arc[-1])
    return np.column_stack([E, np.zeros(k)])


def interior_edge_mean(X, F, k):
    E = unique_edges(F)
    E = E[(E >= k).any(axis=1)]
    return np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1).mean()


def layout_of(k=40, aspect=1.0):
    """The advancing front on an ellipse of perimeter 2 pi (the unit circle's): (D, F)."""
    D = ellipse(k, aspect)
    new, F, _ = advancing_front_triangulation(D, (), 0.75, reference_normal=(0.0, 0.0, 1.0))
    return np.concatenate([D, new]), F


def signed_areas(D, F):
    a, b, c = D[F[:, 0], :2], D[F[:, 1], :2], D[F[:, 2], :2]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


@pytest.mark.parametrize("radius", [1.0, 2.5])
def test_lift_of_a_flat_loop_does_not_stretch(radius):
    D, F = layout_of()
    X = harmonic_lift(D, F, circle(40, radius))
    assert lift_stretch(X, D, F, 40) == pytest.approx(1.0, abs=0.01)


@settings(max_examples=15, deadline=None)
@given(aspect=st.floats(2.5, 5.0), k=st.integers(24, 64))
def test_refined_layout_lifts_at_the_boundary_density(aspect, k):
    """A layout smaller than the surface its boundary spans (an ellipse lifted onto a circle of equal perimeter)."""
    D, F = layout_of(k, aspect)
    P = circle(k)
    X = harmonic_lift(D, F, P)
    stretch = lift_stretch(X, D, F, k)
    assert stretch > LIFT_STRETCH
    boundary_edge = np.linalg.norm(P - np.roll(P, -1, axis=0), axis=1).mean()
    before = interior_edge_mean(X, F, k) / boundary_edge
    planar_edge = np.linalg.norm(D[:k] - np.roll(D[:k], -1, axis=0), axis=1).mean()
    D2, F2 = refine_layout(D, F, k, (), planar_edge / stretch)
    X2 = harmonic_lift(D2, F2, P)
    after = interior_edge_mean(X2, F2, k) / boundary_edge
    assert abs(after - 1.0) < abs(before - 1.0) and 0.75 < after < 1.2
    # still a planar triangulation of the same disc: the layout first, every face counter-clockwise,
    # each boundary edge in one face, the area unchanged, Euler characteristic 1
    np.testing.assert_array_equal(D2[:len(D)], D)
    assert signed_areas(D2, F2).min() > 0
    assert signed_areas(D2, F2).sum() == pytest.approx(signed_areas(D, F).sum())
    directed = {tuple(e) for e in np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])}
    assert all((i, (i + 1) % k) in directed for i in range(k))
    assert len(D2) - len(unique_edges(F2)) + len(F2) == 1


def test_forbidden_boundary_pairs_are_not_joined():
    k = 40
    D, F = layout_of(k)
    forbidden = np.array([[0, 20], [5, 25]])
    D2, F2 = refine_layout(D, F, k, forbidden, 0.05)
    edges = {tuple(sorted(e)) for e in unique_edges(F2)}
    assert (0, 20) not in edges and (5, 25) not in edges
