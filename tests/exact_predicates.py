"""Exact references for 2D segment predicates (rational orientation tests), shared by the predicate tests.

Used by tests/geometry/test_segments.py and tests/algorithms/xu2013/test_front_predicates.py.
"""
from fractions import Fraction

import numpy as np


def orient(p, q, r):
    """Exact orientation of (p, q, r): twice the signed area, as a Fraction (floats are exact)."""
    p, q, r = ([Fraction(c) for c in pt] for pt in (p, q, r))
    return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])


def on_segment(p, q, r):
    """r collinear with p, q lies in the closed box of p, q (hence on the closed segment pq)."""
    return min(p[0], q[0]) <= r[0] <= max(p[0], q[0]) and min(p[1], q[1]) <= r[1] <= max(p[1], q[1])


def closed_segments_meet(a0, a1, b0, b1):
    """Textbook exact test: do the closed segments a0a1 and b0b1 share a point?"""
    o1, o2 = orient(a0, a1, b0), orient(a0, a1, b1)
    o3, o4 = orient(b0, b1, a0), orient(b0, b1, a1)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return (o1 == 0 and on_segment(a0, a1, b0)) or (o2 == 0 and on_segment(a0, a1, b1)) or \
           (o3 == 0 and on_segment(b0, b1, a0)) or (o4 == 0 and on_segment(b0, b1, a1))


def point_segment_distance(x, p, q):
    x, p, q = (np.asarray(v, np.float64) for v in (x, p, q))
    e = q - p
    s = np.clip(np.dot(x - p, e) / np.dot(e, e), 0.0, 1.0) if np.dot(e, e) > 0 else 0.0
    return float(np.linalg.norm(x - (p + s * e)))
