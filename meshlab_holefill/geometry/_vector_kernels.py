"""Scalar 3-vector helpers of the compiled kernels (numba): numpy's row operations on 3-tuples, bit for bit.

Kernels that redo numpy code element by element (the triangle-triangle queries, the edge flips,
the refinement's split test, the hu2012 and xie_zou2013 kernels) build on these helpers to get
the numpy code's bits: each does the IEEE operations of the numpy expression it stands for, in
the same order (no fastmath, no contraction to FMA). Row norms add the squares left to right, as
numpy's add.reduce does (:func:`norm3`); row dots add in np.einsum's order (:func:`dot3`);
:func:`npmax` and :func:`npmin` propagate NaN as np.maximum and np.minimum do. A vector is a
tuple of three floats, so no array is allocated. tests/geometry/test_vector_kernels.py checks
the dot and the norm against numpy.

The module imports nothing from the package, so that every kernel module can import it.
"""
from __future__ import annotations

import math

from numba import njit

__all__ = ["sub3", "add3", "scale3", "div3", "dot3", "norm3", "cross3", "unit3", "npmax", "npmin", "face_corner"]


@njit(cache=True)
def sub3(a, b):
    """a - b, per coordinate."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def add3(a, b):
    """a + b, per coordinate."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@njit(cache=True)
def scale3(a, t):
    """a * t for a scalar t, per coordinate."""
    return (a[0] * t, a[1] * t, a[2] * t)


@njit(cache=True)
def div3(a, t):
    """a / t for a scalar t, per coordinate."""
    return (a[0] / t, a[1] / t, a[2] / t)


@njit(cache=True)
def dot3(a, b):
    """np.einsum("ij,ij->i") (and "kij,kj->ki") on rows of three, bit for bit.

    numpy's einsum sums two lanes at a time (SIMD, from a zero accumulator): lane 0 gets products
    0 and 2, lane 1 product 1, and the lanes are added last. tests/geometry/test_vector_kernels.py
    checks this against np.einsum.
    """
    return ((a[0] * b[0] + 0.0) + a[2] * b[2]) + (a[1] * b[1] + 0.0)


@njit(cache=True)
def norm3(a):
    """np.linalg.norm(axis=1) of a row of three, bit for bit."""
    s = 0.0  # np.linalg.norm(axis=1): sqrt of add.reduce of the squares
    s += a[0] * a[0]
    s += a[1] * a[1]
    s += a[2] * a[2]
    return math.sqrt(s)


@njit(cache=True)
def cross3(a, b):
    """np.cross of two rows of three (each coordinate one difference of two products)."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def unit3(a):
    """a divided by its :func:`norm3`, or a itself when that norm is not > 0."""
    ln = norm3(a)
    return div3(a, ln if ln > 0 else 1.0)


@njit(cache=True)
def npmax(a, b):
    """np.maximum: NaN if either is NaN (ties of +-0 may differ in sign only, which no caller sees)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


@njit(cache=True)
def npmin(a, b):
    """np.minimum: NaN if either is NaN (ties of +-0 may differ in sign only, which no caller sees)."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a <= b else b


@njit(cache=True)
def face_corner(V, F, f, k):
    """Corner k of face f, V[F[f, k]], as a 3-tuple."""
    v = F[f, k]
    return (V[v, 0], V[v, 1], V[v, 2])
