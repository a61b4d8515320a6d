"""Compiled geometry of the quality pass (numba): candidate scores, the guards and the compass search.

Each kernel does, element by element, the IEEE operations of the numpy code it replaces in
the numpy quality pass (:mod:`._quality_pass_numpy`) in the same order (no fastmath), so the
results are the same bits:

* :func:`star_candidate_scores` is the ``score`` of ``_Patch.optimise_position``: 2r/R of
  each star triangle with the moved corner at each candidate position, the unit normals, the
  60-degree turn tests and the objective, whose mean of 1 / q is summed in numpy's pairwise
  order (:func:`._de_kernels._pairwise_sum`);
* :func:`compass_search` is the whole of ``optimise_position``, the loop-edge test of the
  best candidates included, :func:`valid` is ``_Patch.valid``.

Dots follow the numpy call they replace: ``np.einsum("ij,ij->i")`` sums products 0 and 2
first (:func:`...geometry._vector_kernels.dot3`), ``np.linalg.norm`` and the dot of two vectors
(BLAS ddot) add the products in order, and the product of a (s, 3) matrix with a vector, for
s > 1, is BLAS dgemv, whose kernel fuses multiply-adds (:func:`gemv_row`). numpy's argsort of
the candidates' values orders equal values its own way (not stably with its SIMD sorts): only
when two finite values are equal is it called (in object mode), otherwise the order is that of the values. tests/algorithms/xie_zou2013/test_quality_pass_kernels.py and
test_quality_pass_compiled.py check the kernels against that numpy code.
"""
from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, objmode, types
from numba.core import cgutils
from numba.extending import intrinsic

from ._de_kernels import _pairwise_sum
from ...geometry._vector_kernels import cross3, dot3, norm3, npmin

__all__ = ["star_candidate_scores", "compass_search", "valid", "border_ok", "gemv_row", "pairwise_mean",
           "min_of"]

_PAIRWISE_BLOCK = 128


@intrinsic
def _fma(typingctx, a, b, c):
    """a * b + c rounded once (LLVM's fma intrinsic)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        return builder.call(cgutils.get_or_insert_function(builder.module, fnty, "llvm.fma.f64"), args)

    return sig, codegen


@njit(cache=True)
def gemv_row(a, b, rows):
    """Row i of ``A @ b`` for A (rows, 3) and b (3,) as numpy computes it: a . b.

    One row is BLAS ddot (products added in order); more rows go to OpenBLAS's dgemv, whose
    kernel computes fma(a2, b2, fma(a0, b0, a1 b1)).
    """
    if rows == 1:
        return ((0.0 + a[0] * b[0]) + a[1] * b[1]) + a[2] * b[2]
    return _fma(a[2], b[2], _fma(a[0], b[0], a[1] * b[1]))


@njit(cache=True)
def pairwise_mean(a, n):
    """np.mean of a[:n] (n >= 1): numpy's pairwise sum from a zero, over n.

    Above 128 terms numpy sums the halves (the first a multiple of 8) recursively; the
    recursion is unrolled on a stack (numba's cache does not load self-recursive functions).
    """
    if n <= _PAIRWISE_BLOCK:
        return (0.0 + _pairwise_sum(a, n)) / n
    lo, size, value = np.empty(64, np.int64), np.empty(64, np.int64), np.empty(64)
    state = np.zeros(64, np.int64)  # halves summed into value: 0 none, 1 the first, 2 both
    lo[0], size[0], top = 0, n, 0
    total = 0.0
    while top >= 0:
        m = size[top]
        if m <= _PAIRWISE_BLOCK or state[top] == 2:
            part = _pairwise_sum(a[lo[top]:lo[top] + m], m) if m <= _PAIRWISE_BLOCK else value[top]
            top -= 1
            if top < 0:
                total = part
            elif state[top] == 0:
                value[top], state[top] = part, 1
                half = size[top] // 2
                half -= half % 8
                top += 1
                lo[top], size[top], state[top] = lo[top - 1] + half, size[top - 1] - half, 0
            else:
                value[top], state[top] = value[top] + part, 2
            continue
        half = m // 2
        half -= half % 8
        top += 1
        lo[top], size[top], state[top] = lo[top - 1], half, 0
    return (0.0 + total) / n


@njit(cache=True)
def _triangle_terms(p0, p1, p2, out_cr):
    """2r/R of the triangle p0 p1 p2 as ``_quality`` computes it (0 if degenerate); its cross product in out_cr."""
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
def _scores_into(P, corner, X, count, ref, nv, floor_min, floor, gain, turn_cos, energy_objective, val, qmin, N):
    """:func:`star_candidate_scores` of the first ``count`` rows of X into val, qmin, N."""
    s = P.shape[0]
    Q = np.empty((3, 3))
    inv = np.empty(s)
    cr = np.empty(3)
    for ci in range(count):
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
            mn = npmin(mn, q)  # numpy's min: a NaN, once met, is the minimum
            inv[f] = 1.0 / max(q, 1e-12)
        qmin[ci] = mn
        ok = ok and mn >= floor_min - gain
        energy = (0.0 + _pairwise_sum(inv, s)) / s
        v = energy if energy_objective else -min(mn, floor) + 1e-3 * energy
        val[ci] = v if ok else np.inf


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
    C = X.shape[0]
    val, qmin, N = np.empty(C), np.empty(C), np.empty((C, P.shape[0], 3))
    _scores_into(P, corner, X, C, ref, nv, floor_min, floor, gain, turn_cos, energy_objective, val, qmin, N)
    return val, qmin, N


@njit(cache=True)
def _on_loop_edge(u, w, k):
    return u < k and w == (u + 1) % k


@njit(cache=True)
def border_ok(T, N, k, border, border_cos):
    """_Patch.border_ok: triangles T (s, 3) with unit normals N (s, 3) bend < 150 degrees across loop edges."""
    for i in range(T.shape[0]):
        for c in range(3):
            u = T[i, c]
            if _on_loop_edge(u, T[i, (c + 1) % 3], k) and dot3(N[i], border[u]) < border_cos:
                return False
    return True


@njit(cache=True)
def _has_loop_edge(T, k):
    for i in range(T.shape[0]):
        for c in range(3):
            if _on_loop_edge(T[i, c], T[i, (c + 1) % 3], k):
                return True
    return False


@njit(cache=True)
def _drop_bent_best(val, N, count, T, k, border, border_cos):
    """The loop of ``score`` over ``np.argsort(val[:count])``: the best finite value failing the
    loop-edge test (N (C, s, 3) unit normals) set to inf, then the next, up to one that passes.

    Without equal finite values numpy's order of those is that of the values (and the loop
    stops at the first value that is not finite, whose order among them does not matter).
    """
    for a in range(count):
        if val[a] == -np.inf:
            return  # sorted first, not finite: the loop stops at once
        for b in range(a + 1, count):
            if val[a] == val[b] and np.isfinite(val[a]):
                with objmode(order="int64[:]"):
                    order = np.argsort(val[:count])
                for j in order:
                    if not np.isfinite(val[j]) or border_ok(T, N[j], k, border, border_cos):
                        return
                    val[j] = np.inf
                return
    while True:
        j = -1
        for i in range(count):
            if np.isfinite(val[i]) and (j < 0 or val[i] < val[j]):
                j = i
        if j < 0 or border_ok(T, N[j], k, border, border_cos):
            return
        val[j] = np.inf


@njit(cache=True)
def _argmin(val, count):
    """np.argmin: the first NaN if any, else the first smallest."""
    j = 0
    for i in range(count):
        if val[i] != val[i]:
            return i
        if val[i] < val[j]:
            j = i
    return j


@njit(cache=True, error_model="numpy")
def compass_search(T, P, corner, ref, nv, x, h, energy_objective, floor_min, ctx, steps=24):
    """_Patch.optimise_position: compass search in the tangent plane (normal nv) for the corner ``corner`` of T.

    Parameters
    ----------
    T : (s, 3) int64  the triangles; P : (s, 3, 3) float64 their corners
    corner : (s,) int64  the moving corner of each triangle (-1: none)
    ref : (s, 3) float64  reference unit normals; nv : (3,) the tangent plane's normal
    x : (3,) float64  start; h : float  first step
    energy_objective : bool  minimise mean 1 / q (else the 'min' objective)
    floor_min : float  the star's minimum must stay >= floor_min
    ctx : tuple  the pass's constants (:func:`._quality_pass_ops.context`)

    Returns
    -------
    x : (3,) float64  best position found; value : float  its objective (lower is better);
    qmin : float  its smallest quality
    """
    k, floor, gain, turn_cos, border_cos, border, has_border = ctx[0], ctx[1], ctx[2], ctx[3], ctx[4], ctx[5], ctx[6]
    cos_d, sin_d = ctx[9], ctx[10]
    t1 = cross3(nv, (1.0, 0.0, 0.0))
    if norm3(t1) < 0.5:
        t1 = cross3(nv, (0.0, 1.0, 0.0))
    ln = norm3(t1)
    t1 = (t1[0] / ln, t1[1] / ln, t1[2] / ln)
    t2 = cross3(nv, t1)
    D = np.empty((8, 3))
    for j in range(8):
        D[j, 0] = cos_d[j] * t1[0] + sin_d[j] * t2[0]
        D[j, 1] = cos_d[j] * t1[1] + sin_d[j] * t2[1]
        D[j, 2] = cos_d[j] * t1[2] + sin_d[j] * t2[2]
    bent = has_border and _has_loop_edge(T, k)
    s = T.shape[0]
    X, val, qm, N = np.empty((8, 3)), np.empty(8), np.empty(8), np.empty((8, s, 3))
    x = x.copy()
    for d in range(3):
        X[0, d] = x[d]
    _scores_into(P, corner, X, 1, ref, nv, floor_min, floor, gain, turn_cos, energy_objective, val, qm, N)
    if bent:
        _drop_bent_best(val, N, 1, T, k, border, border_cos)
    best, best_min = val[0], qm[0]
    h_min = 1e-2 * h
    for _ in range(steps):
        for j in range(8):
            for d in range(3):
                X[j, d] = x[d] + h * D[j, d]
        _scores_into(P, corner, X, 8, ref, nv, floor_min, floor, gain, turn_cos, energy_objective, val, qm, N)
        if bent:
            _drop_bent_best(val, N, 8, T, k, border, border_cos)
        j = _argmin(val, 8)
        margin = 0.0
        if np.isfinite(best):
            margin = abs(best)
            if 1.0 > margin:  # Python's max(abs(best), 1.0)
                margin = 1.0
        if np.isfinite(val[j]) and val[j] < best - 1e-9 * margin:
            for d in range(3):
                x[d] = X[j, d]
            best, best_min = val[j], qm[j]
        else:
            h *= 0.5
            if h < h_min:
                break
    return x, best, best_min


@njit(cache=True)
def valid(T, P, ref, ctx, q):
    """_Patch.valid: new triangles T (s, 3) with corners P (s, 3, 3) against unit normals ref (s, 3).

    Their qualities go into q (s,); False where numpy returns None (a degenerate triangle, a
    turn of 60 degrees or more from ref, or a loop-edge bend of 150 degrees or more).
    """
    k, turn_cos, border_cos, border, has_border = ctx[0], ctx[3], ctx[4], ctx[5], ctx[6]
    s = T.shape[0]
    N = np.empty((s, 3))
    cr = np.empty(3)
    for i in range(s):
        q[i] = _triangle_terms(P[i, 0], P[i, 1], P[i, 2], cr)
        length = norm3(cr)
        if length <= 0:
            return False
        for d in range(3):
            N[i, d] = cr[d] / length
        if dot3(N[i], ref[i]) <= turn_cos:
            return False
    return not has_border or border_ok(T, N, k, border, border_cos)


@njit(cache=True)
def min_of(q, n):
    """np.min of q[:n] (NaN propagating)."""
    m = q[0]
    for i in range(1, n):
        m = npmin(m, q[i])
    return m

