"""Sec. 3.1's test of an unfolding: the loop projected to its best-fitting plane, reached by linear motion.
"""
from __future__ import annotations

import numpy as np

from ...geometry.pca import fit_plane, project_to_plane
from ...geometry.segments import is_simple_polygon, keeps_clearance

__all__ = ["project_to_best_plane", "projection_is_simple", "linear_motion_is_simple"]


def projection_is_simple(P, mask, eps, near):
    """Sec. 3.1's projection test at a stage start, m >= 4.

    ``linear_motion_is_simple(project_to_best_plane(P)[0], eps, near)``.

    The same projection and the same distances, with the loop's
    mask of non-adjacent segments built once per run and the test stopping at the first pair
    closer than eps (most stages' projections cross themselves). The stage tests were a third of
    the annealing's time under cProfile, np.cross and the mask most of it.
    """
    centroid, normal, _, _ = fit_plane(P)
    Q = project_to_plane(P, centroid, normal)
    return bool(keeps_clearance(Q, np.ascontiguousarray(np.roll(Q, -1, axis=0)), mask, float(near), float(eps)))


def project_to_best_plane(P):
    """Orthogonal projection of a loop onto its best-fitting (least-squares) plane (Sec. 3.1).

    Parameters
    ----------
    P : (m, 3) float64

    Returns
    -------
    Q : (m, 2) float64
        Coordinates in an orthonormal frame (u, v) of the plane, (u, v, normal) right-handed.
    projected : (m, 3) float64
        The projected points in space.
    normal : (3,) float64
    """
    P = np.asarray(P, np.float64)
    centroid, normal, _, _ = fit_plane(P)
    Q = project_to_plane(P, centroid, normal)
    projected = P - np.outer((P - centroid) @ normal, normal)
    return Q, projected, normal


def linear_motion_is_simple(Q, eps, near=None):
    """Whether a simple loop reaches its projection by linear motion without self-intersection.

    Sec. 3.1 accepts the unfolding only if the annealed loop can be moved to its projection
    onto its best-fitting plane by linear motions of the vertices without self-intersection.
    This test is exact and reduces to the end point: under the motion p(t) = p + t (proj(p) -
    p) every point keeps its in-plane coordinates and its height above the plane is scaled by
    (1 - t). Two points of two segments coincide at time t < 1 only if they have the same
    in-plane position and equal heights, and heights scaled by the common factor (1 - t) are
    equal exactly when they were equal at t = 0, where the loop is simple (d_MD > eps). So the
    motion is free of self-intersection iff the projected polygon is simple; it is required to
    keep the clearance d_MD > eps, like the annealing. Q is the (m, 2) projected polygon; ``eps``
    and ``near`` are as for :func:`meshlab_holefill.geometry.segments.is_simple_polygon`, which decides.
    """
    return is_simple_polygon(Q, eps, near)
