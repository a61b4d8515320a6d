"""Compiled kernel of the smoothing of Sec. 4.7 (numba): the lambda|mu passes of Taubin's filter.

Each pass does, element by element, the IEEE operations of the scipy/numpy expression
``V[free] += factor * (Wf @ V - V[free])`` in the same order (scipy's CSR product sums each
row's entries in storage order from 0; no FMA contraction), so the result is bit for bit
that of the expression (tests/algorithms/xie_zou2013/test_de_kernels.py checks it).
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["umbrella_passes"]


@njit(cache=True)
def umbrella_passes(V, free_rows, indptr, indices, data, factors, passes):
    """``passes`` times, for each factor in turn: V[free] += factor * (Wf @ V - V[free]), in place.

    Parameters
    ----------
    V : (n, 3) float64, C-contiguous
    free_rows : (f,) int64  the free vertices (rows of Wf, ascending)
    indptr, indices, data : the CSR arrays of Wf (f, n)
    factors : (2,) float64  lambda, mu
    passes : int
    """
    f = len(free_rows)
    M = np.empty((f, 3))
    for _ in range(passes):
        for factor in factors:
            for r in range(f):
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                for jj in range(indptr[r], indptr[r + 1]):
                    a = data[jj]
                    j = indices[jj]
                    s0 += a * V[j, 0]
                    s1 += a * V[j, 1]
                    s2 += a * V[j, 2]
                M[r, 0] = s0
                M[r, 1] = s1
                M[r, 2] = s2
            for r in range(f):
                v = free_rows[r]
                for c in range(3):
                    x = V[v, c]
                    V[v, c] = x + factor * (M[r, c] - x)
