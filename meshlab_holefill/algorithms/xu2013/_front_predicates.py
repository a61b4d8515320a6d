"""Geometric predicates of the advancing front (:mod:`meshlab_holefill.algorithms.xu2013.advancing_front`).

Small 3-vectors are plain tuples (the front works one step at a time, where numpy's call
overhead dominates); batches of candidate pairs use row-wise numpy. The per-step tests run
compiled (:mod:`._front_kernels`, the same operations); the functions here are their
reference.
"""
from __future__ import annotations

import math

import numpy as np

from ...geometry.quality import cross_rows

__all__ = ["sub", "dot", "cross", "norm", "scaled", "unit", "front_angle", "direction_angle", "segments_cross",
           "dot_rows", "point_triangle_distance", "segments_hit_triangles"]

# The plane of the two front edges is used when its normal is within 30 degrees of the
# reference normal and the edges make an angle of at least ~8.6 degrees (sin > 0.15).
PLANE_MIN_COS = 0.866
PLANE_MIN_SIN = 0.15


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


def scaled(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def unit(a):
    n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n) if n > 0.0 else a


def front_angle(v, p, q, n_ref):
    """Front angle at v and the normal of the plane it is measured in (Sec. 3.2, Step 2).

    The uncovered region lies to the left of the front p -> v -> q seen from the normal
    side, so the angle is measured counter-clockwise from (q - v) to (p - v) about the plane
    normal m: the normal of the plane of the two front edges oriented like ``n_ref`` (the
    angle is reflex when they disagree), or ``n_ref`` itself with the edges projected on
    its plane when the edge plane is unreliable (see module docstring).

    Parameters
    ----------
    v, p, q : 3-tuples of float
        The vertex and its previous and next front neighbours.
    n_ref : 3-tuple of float
        Unit reference normal at v.

    Returns
    -------
    theta : float in [0, 2 pi)
    m : 3-tuple, unit plane normal
    """
    a, b = sub(q, v), sub(p, v)
    c = cross(a, b)
    s, la, lb = norm(c), norm(a), norm(b)
    if la == 0.0 or lb == 0.0:
        return 0.0, n_ref
    cos_ref = dot(c, n_ref)
    if s > PLANE_MIN_SIN * la * lb and abs(cos_ref) >= PLANE_MIN_COS * s:
        sign = 1.0 if cos_ref >= 0.0 else -1.0
        m = scaled(c, sign / s)
        theta = math.atan2(sign * s, dot(a, b))
    else:
        m = n_ref
        theta = direction_angle(a, b, m)
    if theta < 0.0:
        theta += 2.0 * math.pi
    return theta, m


def direction_angle(ref, d, m):
    """Counter-clockwise angle about unit m from ref to d, both projected on m's plane, in [0, 2 pi)."""
    t = math.atan2(dot(m, cross(ref, d)), dot(ref, d) - dot(ref, m) * dot(d, m))
    return t + 2.0 * math.pi if t < 0.0 else t


def segments_cross(a0, a1, b0, b1):
    """Do 2D segments a0a1 and b0b1 cross or touch (collinear overlap included)?"""
    def orient(p, q, r):
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    scale = max(abs(a1[0] - a0[0]), abs(a1[1] - a0[1]), abs(b1[0] - b0[0]), abs(b1[1] - b0[1]))
    eps = 1e-9 * scale * scale
    o1, o2 = orient(a0, a1, b0), orient(a0, a1, b1)
    if (o1 > eps and o2 > eps) or (o1 < -eps and o2 < -eps):
        return False
    o3, o4 = orient(b0, b1, a0), orient(b0, b1, a1)
    if (o3 > eps and o4 > eps) or (o3 < -eps and o4 < -eps):
        return False
    if abs(o1) <= eps and abs(o2) <= eps:
        # Collinear: overlap of the projections on the longer axis, and (within the tolerance)
        # on the other, which two zero-length segments on one vertical line need.
        axis = 0 if abs(a1[0] - a0[0]) + abs(b1[0] - b0[0]) >= abs(a1[1] - a0[1]) + abs(b1[1] - b0[1]) else 1
        lo_a, hi_a = sorted((a0[axis], a1[axis]))
        lo_b, hi_b = sorted((b0[axis], b1[axis]))
        other, tol = 1 - axis, 1e-9 * scale
        return (hi_a >= lo_b and hi_b >= lo_a and max(a0[other], a1[other]) + tol >= min(b0[other], b1[other])
                and max(b0[other], b1[other]) + tol >= min(a0[other], a1[other]))
    return True


def dot_rows(a, b):
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def point_triangle_distance(x, T):
    """Distances from point x (3,) to triangles T (t, 3, 3), (t,) float64."""
    A, B, C = T[:, 0], T[:, 1], T[:, 2]
    n = cross_rows(B - A, C - A)
    nn = dot_rows(n, n)
    # Inside the prism over the triangle: distance to the plane.
    w = x - A
    ok = nn > 0
    t = np.where(ok, dot_rows(w, n) / np.where(ok, nn, 1.0), 0.0)
    p = x - t[:, None] * n
    inside = ok.copy()
    for U, W in ((A, B), (B, C), (C, A)):
        inside &= dot_rows(cross_rows(W - U, p - U), n) >= 0.0
    best = np.where(inside, np.abs(t) * np.sqrt(nn), np.inf)
    for U, W in ((A, B), (B, C), (C, A)):
        e = W - U
        ee = np.maximum(dot_rows(e, e), 1e-300)
        s = np.clip(dot_rows(x - U, e) / ee, 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(x - (U + s[:, None] * e), axis=1))
    return best


def segments_hit_triangles(P0, P1, T, tol):
    """Does segment P0[i]P1[i] meet triangle T[i] (touching within ``tol`` counts)? (n,) bool.

    Coplanar pairs are not reported (the front-angle and crossing checks cover the plane).
    """
    A, B, C = T[:, 0], T[:, 1], T[:, 2]
    n = cross_rows(B - A, C - A)
    scale = np.linalg.norm(n, axis=1)
    s0 = dot_rows(P0 - A, n)
    s1 = dot_rows(P1 - A, n)
    eps = tol * scale
    crosses_plane = ~(((s0 > eps) & (s1 > eps)) | ((s0 < -eps) & (s1 < -eps))) & ~((np.abs(s0) <= eps) & (np.abs(s1) <= eps))
    d = P1 - P0

    def side(U, W):
        return dot_rows(cross_rows(U - P0, W - P0), d)

    e1, e2, e3 = side(A, B), side(B, C), side(C, A)
    # side() is a triple product (length^3): tol (a length) times |d| times the triangle's size
    lim = tol * np.sqrt(scale) * np.linalg.norm(d, axis=1)
    inside = ((e1 >= -lim) & (e2 >= -lim) & (e3 >= -lim)) | ((e1 <= lim) & (e2 <= lim) & (e3 <= lim))
    return crosses_plane & inside
