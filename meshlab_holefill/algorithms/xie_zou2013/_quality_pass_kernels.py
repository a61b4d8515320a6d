"""Compiled kernel of the quality pass (numba): the candidate scores of the compass search.

:func:`star_candidate_scores` does, element by element, the IEEE operations of the numpy
``score`` it replaces in :meth:`.quality_pass._Patch.optimise_position` in the same order
(no fastmath): 2r/R of each star triangle with the moved corner at each candidate
position, the unit normals, the 60-degree turn tests and the objective, whose mean of 1 / q
is summed in numpy's pairwise order (:func:`._de_kernels._pairwise_sum`).
tests/algorithms/xie_zou2013/test_quality_pass_kernels.py checks it against that numpy code.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._de_kernels import _pairwise_sum
from ...geometry._vector_kernels import npmin as _npmin

__all__ = ["star_candidate_scores"]


@njit(cache=True)
def _triangle_terms(p0, p1, p2, out_cr):
    """2r/R of the triangle p0 p1 p2 as quality_pass._quality computes it (0 if degenerate); its cross product in out_cr."""
    e00, e01, e02 = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    e10, e11, e12 = p2[0] - p1[0], p2[1] - p1[1], p2[2] - p1[2]
    e20, e21, e22 = p0[0] - p2[0], p0[1] - p2[1], p0[2] - p2[2]
    a = np.sqrt(e10 * e10 + e11 * e11 + e12 * e12)
    b = np.sqrt(e20 * e20 + e21 * e21 + e22 * e22)
    c = np.sqrt(e00 * e00 + e01 * e01 + e02 * e02)
    m0, m1, m2 = -e20, -e21, -e22
    c0 = e01 * m2 - e02 * m1
    c1 = e02 * m0 - e00 * m2
    c2 = e00 * m1 - e01 * m0
    out_cr[0], out_cr[1], out_cr[2] = c0, c1, c2
    area2 = (c0 * c0 + c1 * c1 + c2 * c2) / 4.0
    den = (a + b + c) * a * b * c
    q = 16.0 * area2 / den if den > 0 else 0.0
    if q < 0.0:
        return 0.0
    if q > 1.0:
        return 1.0
    return q


@njit(cache=True)
def star_candidate_scores(P, corner, X, ref, nv, floor_min, floor, gain, turn_cos, energy_objective):
    """Objective of each candidate position of one corner of a triangle star.

    Parameters
    ----------
    P : (s, 3, 3) float64  corners of the star's triangles
    corner : (s,) int64  which corner of each triangle moves (the star's centre)
    X : (C, 3) float64  candidate positions
    ref : (s, 3) float64  reference unit normals; nv : (3,) the centre's unit normal
    floor_min, floor, gain, turn_cos : float  the guards and the 'min' objective's floor
    energy_objective : bool  True: mean 1 / q; False: -min(qmin, floor) + 1e-3 mean 1 / q

    Returns
    -------
    val : (C,) float64  inf where a guard fails
    qmin : (C,) float64  smallest quality of the star at each candidate
    N : (C, s, 3) float64  unit normals (cross / max(|cross|, 1e-300))
    """
    s = P.shape[0]
    C = X.shape[0]
    val = np.empty(C)
    qmin = np.empty(C)
    N = np.empty((C, s, 3))
    Q = np.empty((3, 3))
    inv = np.empty(s)
    cr = np.empty(3)
    for ci in range(C):
        ok = True
        mn = np.inf
        for f in range(s):
            for r in range(3):
                for d in range(3):
                    Q[r, d] = X[ci, d] if r == corner[f] else P[f, r, d]
            q = _triangle_terms(Q[0], Q[1], Q[2], cr)
            ln = np.sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2])
            ok = ok and ln > 0
            lm = max(ln, 1e-300)
            n0, n1, n2 = cr[0] / lm, cr[1] / lm, cr[2] / lm
            N[ci, f, 0], N[ci, f, 1], N[ci, f, 2] = n0, n1, n2
            ok = ok and n0 * ref[f, 0] + n1 * ref[f, 1] + n2 * ref[f, 2] > turn_cos
            ok = ok and n0 * nv[0] + n1 * nv[1] + n2 * nv[2] > turn_cos
            mn = _npmin(mn, q)  # numpy's min: a NaN, once met, is the minimum
            inv[f] = 1.0 / max(q, 1e-12)
        qmin[ci] = mn
        ok = ok and mn >= floor_min - gain
        energy = (0.0 + _pairwise_sum(inv, s)) / s
        v = energy if energy_objective else -min(mn, floor) + 1e-3 * energy
        val[ci] = v if ok else np.inf
    return val, qmin, N
