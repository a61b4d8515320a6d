"""Compiled rounds of the tangential umbrella smoothing (numba), bit for bit the numpy/scipy code of
:func:`.laplacian.tangential_umbrella_smoothing_numpy`.

Each round does, element by element, that code's IEEE operations in its order: the vertex normals of
:func:`._quality_kernels.unit_vertex_normals`, scipy's CSR product ``A @ V`` (each row's entries summed in
storage order from 0.0, times the stored 1.0), the division by the degree, the normal part removed with
np.einsum's row dot (:func:`._vector_kernels.dot3`) and the step added to the free rows.
tests/geometry/test_laplacian.py checks it against the numpy code.
"""
from __future__ import annotations

from numba import njit

from ._quality_kernels import unit_vertex_normals
from ._vector_kernels import dot3

__all__ = ["tangential_umbrella_rounds"]


@njit(cache=True)
def tangential_umbrella_rounds(V, F, indptr, indices, free, iterations, step):
    """``iterations`` rounds of tangential umbrella smoothing of the rows ``free`` of V, in place.

    Parameters
    ----------
    V : (n, 3) float64, C-contiguous
    F : (m, 3) int64  valid indices
    indptr, indices : the CSR arrays of the (n, n) adjacency of F (canonical: sorted, no duplicates)
    free : (s,) int64  the vertices that move
    iterations : int
    step : float
    """
    n = V.shape[0]
    D = V.copy()  # only the free rows are written and read
    for _ in range(iterations):
        N = unit_vertex_normals(V, F, n)
        for v in free:
            count = indptr[v + 1] - indptr[v]
            degree = max(float(count), 1.0)
            for c in range(3):
                s = 0.0
                for p in range(indptr[v], indptr[v + 1]):
                    s += 1.0 * V[indices[p], c]
                D[v, c] = s / degree - V[v, c]
            along = dot3((D[v, 0], D[v, 1], D[v, 2]), (N[v, 0], N[v, 1], N[v, 2]))
            for c in range(3):
                D[v, c] = D[v, c] - along * N[v, c]
        for v in free:
            for c in range(3):
                V[v, c] = V[v, c] + step * D[v, c]
