"""Plane fitting and plane frames of geometry.pca."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.pca import fit_plane, project_to_plane


def test_pca_plane_of_tilted_points():
    rng = np.random.default_rng(0)
    P = rng.uniform(-1, 1, size=(50, 3))
    n = np.array([1.0, 2.0, 2.0]) / 3
    P -= np.outer(P @ n, n)
    c, normal, w, axes = fit_plane(P + 5)
    assert abs(abs(normal @ n) - 1) < 1e-12 and w[0] < 1e-14
    Q = project_to_plane(P + 5, c, normal)
    assert Q.shape == (50, 2)
    # The points lie in the plane, so the projection is rigid: every pairwise distance is kept.
    assert np.allclose(np.linalg.norm(Q[:, None] - Q[None], axis=2), np.linalg.norm(P[:, None] - P[None], axis=2),
                       atol=1e-12)


def _unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda n: np.linalg.norm(n) > 0.1),
       st.lists(st.floats(-3, 3), min_size=3, max_size=3),
       st.lists(st.floats(-2, 2), min_size=12, max_size=12))
def test_project_to_plane_is_rigid_and_counter_clockwise_seen_from_the_normal(normal, centroid, coords):
    """The contract of pca.project_to_plane: orthonormal 2D coordinates, CCW seen from ``normal``."""
    n = _unit(normal)
    c = np.array(centroid)
    # An orthonormal basis (e1, e2) of the plane with e1 x e2 = n, built independently of pca.
    e1 = _unit(np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0]))
    e2 = np.cross(n, e1)
    uv = np.array(coords[:8]).reshape(4, 2)
    heights = np.array(coords[8:])
    P = c + uv[:, :1] * e1 + uv[:, 1:] * e2
    Q = project_to_plane(P, c, n)
    # In-plane points: Q is a rotation of uv, so the Gram matrix (all lengths and angles) is kept.
    assert np.allclose(Q @ Q.T, uv @ uv.T, atol=1e-9)
    # A triangle counter-clockwise about n (e1 -> e2 is a positive turn) keeps twice its signed
    # area, +1, in 2D: the 2D frame is a rotation of (e1, e2), not a reflection.
    tri = np.array([c, c + e1, c + e2])
    a, b, d = project_to_plane(tri, c, n)
    assert (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]) == pytest.approx(1.0)
    # Viewed from -n the same triangle is clockwise.
    a, b, d = project_to_plane(tri, c, -n)
    assert (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]) == pytest.approx(-1.0)
    # Off-plane offsets along n are dropped: the projection is orthogonal.
    assert np.allclose(project_to_plane(P + heights[:, None] * n, c, n), Q, atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda n: np.linalg.norm(n) > 0.1))
def test_plane_frame_is_right_handed_and_np_cross_to_the_bit(normal):
    from meshlab_holefill.geometry.pca import plane_frame

    u, v = plane_frame(normal)
    n = _unit(normal)
    assert np.array_equal(v, np.cross(n, u))  # the frame's bits do not depend on how the product is written
    assert abs(u @ n) < 1e-12 and abs(u @ v) < 1e-12 and abs(np.linalg.norm(v) - 1) < 1e-12
    assert np.linalg.det(np.stack([u, v, n])) > 0
