"""Compiled kernels of the DE run (numba): the element-wise steps of one generation, fused.

Each kernel does, element by element, the same IEEE operations in the same order as the
numpy expression it replaces (no fastmath, no contraction to FMA), so the results are bit
for bit those of the numpy code (tests/algorithms/xie_zou2013/test_de_kernels.py checks it
against the numpy reference kept there). The transcendental step (arctan2 of the turning
angles) stays in numpy, whose SIMD arctan2 differs from libm's in the last bits, and so does the
sum of squares (numpy's einsum accumulates with fused multiply-adds): a generation of the Eq. 14
objective is one kernel for the trial vectors and the turning terms their crossover changed,
numpy's arctan2 of those, one kernel for the trial angles and their sums, numpy's einsum, then
one kernel for the selection, the reflection and the terms of the reflected ones.
"""
from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["reflect_moved", "trial_vectors", "mutate_crossover", "select", "turning_terms", "trial_changed_terms",
           "trial_changed_terms_into", "select_reflect_terms",
           "renew_variation", "masked_row_sums", "changed_masked_row_sums"]


@njit(cache=True)
def _reflected(x, lo, hi):
    """Eq. 5: a component below ``lo`` reflected about it, then one above ``hi`` about that (kept within the bounds)."""
    y = x
    if x < lo:
        y = min(2.0 * lo - x, hi)
    if y > hi:
        y = max(2.0 * hi - y, lo)
    return y


@njit(cache=True)
def reflect_moved(X, lower, upper):
    """(reflected X, moved): Eq. 5 on X (B, N, n) with bounds (B, n); moved (B, N) bool: any component changed."""
    B, N, n = X.shape
    out = np.empty_like(X)
    moved = np.zeros((B, N), np.bool_)
    for b in range(B):
        for i in range(N):
            for j in range(n):
                x = X[b, i, j]
                y = _reflected(x, lower[b, j], upper[b, j])
                out[b, i, j] = y
                if y != x:
                    moved[b, i] = True
    return out, moved


@njit(cache=True)
def trial_vectors(X, r1, r2, r3, u_take, rn, F, CR):
    """Eq. 2 and 3: U = where(u_take <= CR or j == rn, X[r1] + F (X[r2] - X[r3]), X), (B, N, n)."""
    B, N, n = X.shape
    U = np.empty_like(X)
    for b in range(B):
        for i in range(N):
            _trial_row(U, X, u_take, b, i, r1[b, i], r2[b, i], r3[b, i], rn[b, i], F, CR)
    return U


@njit(cache=True)
def _trial_row(U, X, u_take, b, i, r1, r2, r3, r, F, CR):
    """Eq. 2 and 3 for individual i of problem b: U[b, i] from X[b, r1] + F (X[b, r2] - X[b, r3]) and X[b, i]."""
    for j in range(X.shape[2]):
        if u_take[b, i, j] <= CR or j == r:
            U[b, i, j] = X[b, r1, j] + F * (X[b, r2, j] - X[b, r3, j])
        else:
            U[b, i, j] = X[b, i, j]


@njit(cache=True)
def select(X, fX, U, fU, active):
    """Eq. 4 in place: X[b, i] = U[b, i] and fX[b, i] = fU[b, i] where fU <= fX on active rows."""
    B, N, n = X.shape
    for b in range(B):
        for i in range(N):
            if active[b, i] and fU[b, i] <= fX[b, i]:
                fX[b, i] = fU[b, i]
                for j in range(n):
                    X[b, i, j] = U[b, i, j]


@njit(cache=True)
def _chain_ys(sy, Y, a, i, seg_y_add):
    """sy (m + 3) = [0, diff((0, Y[a, i], 0)), 0] + seg_y_add[a]: the y of candidate (a, i)'s chain segments."""
    m = Y.shape[2]
    prev = 0.0
    sy[0] = 0.0 + seg_y_add[a, 0]
    for j in range(m):
        y = Y[a, i, j]
        sy[j + 1] = (y - prev) + seg_y_add[a, j + 1]
        prev = y
    sy[m + 1] = (0.0 - prev) + seg_y_add[a, m + 1]
    sy[m + 2] = 0.0 + seg_y_add[a, m + 2]


@njit(cache=True)
def turning_terms(Y, seg_x, seg_y_add):
    """Arguments (cross, dot) of the turning angles' arctan2 for candidates Y (p, N, m) (see turning_angles)."""
    p, N, m = Y.shape
    K = m + 2
    cr = np.empty((p, N, K))
    dt = np.empty((p, N, K))
    sy = np.empty(m + 3)
    for a in range(p):
        for i in range(N):
            _chain_ys(sy, Y, a, i, seg_y_add)
            for k in range(K):
                x0, x1 = seg_x[a, k], seg_x[a, k + 1]
                y0, y1 = sy[k], sy[k + 1]
                cr[a, i, k] = x0 * y1 - y0 * x1
                dt[a, i, k] = x0 * x1 + y0 * y1
    return cr, dt


@njit(cache=True)
def mutate_crossover(X, u_index, u_rn, u_take, pop, dims, F, CR):
    """Algorithm 1, steps 4-6 from uniform draws: distinct r1, r2, r3, rn_i, then Eq. 2 and 3.

    r1 = floor(u0 N), r2 = floor(u1 (N - 1)) shifted past r1, r3 = floor(u2 (N - 2)) shifted past
    both (uniform, mutually different), rn_i = floor(u dims): the arithmetic of
    de_rand_1_bin._distinct_triples and of the trial_vectors kernel, fused.

    Parameters
    ----------
    X : (B, N, n) float64
    u_index : (3, B, N) float64, u_rn : (B, N) float64, u_take : (B, N, n) float64  uniforms in [0, 1)
    pop, dims : (B,) int64
    """
    B, N, n = X.shape
    U = np.empty_like(X)
    for b in range(B):
        Nb = np.float64(pop[b])
        db = np.float64(dims[b])
        for i in range(N):
            r1, r2, r3, r = _individual_draws(u_index, u_rn, b, i, Nb, db)
            _trial_row(U, X, u_take, b, i, r1, r2, r3, r, F, CR)
    return U


@njit(cache=True)
def _individual_draws(u_index, u_rn, b, i, Nb, db):
    """r1, r2, r3 and rn_i of individual i of problem b (population Nb, db used components), as in mutate_crossover."""
    r1 = np.int64(np.floor(u_index[0, b, i] * Nb))
    r2 = np.int64(np.floor(u_index[1, b, i] * (Nb - 1.0)))
    if r2 >= r1:
        r2 += 1
    lo, hi = min(r1, r2), max(r1, r2)
    r3 = np.int64(np.floor(u_index[2, b, i] * (Nb - 2.0)))
    if r3 >= lo:
        r3 += 1
    if r3 >= hi:
        r3 += 1
    return r1, r2, r3, np.int64(np.floor(u_rn[b, i] * db))


@njit(cache=True)
def trial_changed_terms(X, u_index, u_rn, u_take, pop, dims, F, CR, seg_x, seg_y_add):
    """(U, changed, cross, dot): the trial vectors of :func:`mutate_crossover` and the turning terms they change.

    Turning term k of :func:`turning_terms` reads components k - 2, k - 1 and k of its
    candidate (those within 0..n-1) and nothing else of it. A trial vector U[b, i] copies
    every component but its crossover ones (Eq. 3) from its parent X[b, i], so its terms
    are its parent's except those within two places after a crossover component: only
    these are computed (the same operations as :func:`turning_terms`, so the same numbers).
    :func:`trial_changed_terms_into` with new arrays (the padding rows of U are their parents').

    Returns
    -------
    U : (B, N, n) float64
    changed : (c,) int64  flat indices into (B, N, n + 2), ascending
    cross, dot : (c,) float64  the terms there
    """
    B, N, n = X.shape
    size = B * N * (n + 2)
    U = X.copy()
    changed = np.empty(size, np.int64)
    cross = np.empty(size)
    dot = np.empty(size)
    c = trial_changed_terms_into(X, u_index, u_rn, u_take, pop, dims, F, CR, seg_x, seg_y_add, U, changed, cross,
                                 dot)
    return U, changed[:c], cross[:c], dot[:c]


@njit(cache=True)
def trial_changed_terms_into(X, u_index, u_rn, u_take, pop, dims, F, CR, seg_x, seg_y_add, U, changed, cross, dot):
    """:func:`trial_changed_terms` written into U (B, N, n) and the first c entries of changed, cross, dot; returns c.

    The arrays are the DE run's own, reused every generation: fresh ones of a large batch
    (41 sections of 51 components, 153 individuals) cost as much in first-touch page faults
    as the arithmetic. One pass per individual copies its parent, lists its crossover
    components (ascending), computes those by Eq. 2 and then the terms at j, j + 1, j + 2 of
    each (each term once, ascending): the same numbers as :func:`mutate_crossover` and
    :func:`turning_terms`. The padding rows (i >= pop[b], a tenth of the suite's) are left
    out: Eq. 4 never takes them, so their rows of U are not written and none of their terms
    listed. The crossover test is counted, not branched on, and the chain's y come from the
    trial row padded with two zeros on each side (:func:`_padded_chain_y`): the branches of
    the sparse crossover (5 %) and of the chain's ends were mispredicted often enough to cost
    a third of the kernel.
    """
    B, N, n = X.shape
    K = n + 2
    taken = np.empty(n, np.int64)
    padded = np.zeros(n + 4)  # [0, 0, U[b, i], 0, 0]
    c = 0
    for b in range(B):
        Nb = np.float64(pop[b])
        db = np.float64(dims[b])
        for i in range(pop[b]):  # the padding rows are never selected
            r1, r2, r3, r = _individual_draws(u_index, u_rn, b, i, Nb, db)
            t = 0
            for j in range(n):
                x = X[b, i, j]
                U[b, i, j] = x
                padded[j + 2] = x
                taken[t] = j  # t <= j: kept only if j is a crossover component
                t += (u_take[b, i, j] <= CR) | (j == r)
            for q in range(t):
                j = taken[q]
                v = X[b, r1, j] + F * (X[b, r2, j] - X[b, r3, j])
                U[b, i, j] = v
                padded[j + 2] = v
            base = (b * N + i) * K
            after = 0  # terms before this one are already out
            for q in range(t):
                j = taken[q]
                first = max(j, after)
                y0 = _padded_chain_y(padded, seg_y_add, b, first)
                for k in range(first, j + 3):
                    y1 = _padded_chain_y(padded, seg_y_add, b, k + 1)
                    x0, x1 = seg_x[b, k], seg_x[b, k + 1]
                    changed[c] = base + k
                    cross[c] = x0 * y1 - y0 * x1
                    dot[c] = x0 * x1 + y0 * y1
                    c += 1
                    y0 = y1
                after = j + 3
    return c


@njit(cache=True)
def _padded_chain_y(padded, seg_y_add, b, k):
    """y of chain segment k (the sy[k] of :func:`_chain_ys`) from padded = [0, 0, Y[a, i], 0, 0].

    (padded[k + 1] - padded[k]) + seg_y_add[b, k]: at the ends the difference is 0.0 - 0.0 or
    y - 0.0 or 0.0 - y, the very operations of :func:`_chain_ys` (0.0 - 0.0 is +0.0 exactly).
    """
    return (padded[k + 1] - padded[k]) + seg_y_add[b, k]


@njit(cache=True)
def _variation(square_sum, total, count):
    """Eq. 14 from the sums of one candidate: np.maximum(square_sum - total * total / count, 0.0)."""
    v = square_sum - total * total / count
    if v >= 0.0 or v != v:  # NaN passes, as through np.maximum
        return v
    return 0.0


@njit(cache=True)
def select_reflect_terms(X, fX, U, square_sum, total, count, active, angles, trial_angles, lower, upper, seg_x,
                         seg_y_add):
    """Eq. 4 in place with f(U) from its turning-angle sums, then Eq. 5 and the turning terms of what it moved.

    Selection: where the active trial U[b, i] is no worse (f from :func:`_variation`, count (B,)
    angles per problem), it replaces X[b, i], its f and its turning angles (trial_angles[b, i]).
    Every individual of X is inside the bounds after a generation (Eq. 5 maps into [l, u]), so
    only the trials just taken can have moved: the reflection (Eq. 5, as :func:`reflect_moved`)
    runs on their rows alone, and the rows that keep their parent stay as they are, which is
    what reflecting them gives.

    Returns
    -------
    order : (B, K) int64
        Per problem the reflected rows first, then the others (both ascending), K = the largest count.
    counts : (B,) int64
        Rows the reflection moved.
    cross, dot : (B, K, n + 2)
        Turning terms of X[b, order[b]] after the reflection.
    """
    B, N, n = X.shape
    moved = np.zeros((B, N), np.bool_)
    counts = np.zeros(B, np.int64)
    for b in range(B):
        for i in range(N):
            if active[b, i]:
                f = _variation(square_sum[b, i], total[b, i], count[b])
                if f <= fX[b, i]:
                    fX[b, i] = f
                    angles[b, i] = trial_angles[b, i]
                    moved[b, i] = _take_reflected(X, U, lower, upper, b, i)
                    counts[b] += moved[b, i]
    order, G = _gather_moved(X, moved, counts)
    cross, dot = turning_terms(G, seg_x, seg_y_add)
    return order, counts, cross, dot


@njit(cache=True)
def _take_reflected(X, U, lower, upper, b, i):
    """X[b, i] = U[b, i] reflected into the bounds (Eq. 5, as :func:`reflect_moved`); True if any component moved."""
    moved = False
    for j in range(X.shape[2]):
        x = U[b, i, j]
        y = _reflected(x, lower[b, j], upper[b, j])
        X[b, i, j] = y
        moved |= y != x
    return moved


@njit(cache=True)
def _gather_moved(X, moved, counts):
    """(order (B, K), G (B, K, n)): per problem the moved rows, then the others, up to K = max counts; their X rows."""
    B, N, n = X.shape
    K = counts.max() if B else 0
    order = np.empty((B, K), np.int64)
    G = np.empty((B, K, n))
    for b in range(B):
        r = 0
        for i in range(N):  # the moved rows, then the others up to K
            if moved[b, i]:
                order[b, r] = i
                r += 1
        for i in range(N):
            if r < K and not moved[b, i]:
                order[b, r] = i
                r += 1
        for r in range(K):
            for j in range(n):
                G[b, r, j] = X[b, order[b, r], j]
    return order, G


@njit(cache=True)
def renew_variation(fX, order, counts, square_sum, total, count, angles, reflected_angles):
    """Algorithm 1, step 9: fX[b, order[b, r]] = f of the r-th reflected individual, r < counts[b].

    Its turning angles reflected_angles[b, r] replace angles[b, order[b, r]] too.
    """
    for b in range(len(counts)):
        for r in range(counts[b]):
            fX[b, order[b, r]] = _variation(square_sum[b, r], total[b, r], count[b])
            angles[b, order[b, r]] = reflected_angles[b, r]


# numpy sums blocks of up to this many numbers with 8 accumulators; longer rows it halves
# recursively (not replicated here: recursion does not survive numba's cache).
PAIRWISE_BLOCK = 128


@njit(cache=True)
def _pairwise_sum(a, n):
    """numpy's pairwise summation of a[:n] for n <= PAIRWISE_BLOCK: 8 accumulators, then the rest in order."""
    if n < 8:
        res = -0.0
        for i in range(n):
            res += a[i]
        return res
    r0, r1, r2, r3, r4, r5, r6, r7 = a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7]
    i = 8
    while i < n - n % 8:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res


@njit(cache=True)
def masked_row_sums(beta, valid):
    """beta *= valid[:, None, :] in place, then beta.sum(axis=2) in numpy's order, (p, N); valid (p, K).

    For K <= PAIRWISE_BLOCK (numpy's reduction of a row: 0.0 + its pairwise sum).
    """
    p, N, K = beta.shape
    total = np.empty((p, N))
    for a in range(p):
        for i in range(N):
            row = beta[a, i]
            for k in range(K):
                row[k] = row[k] * valid[a, k]
            total[a, i] = 0.0 + _pairwise_sum(row, K)
    return total


@njit(cache=True)
def changed_masked_row_sums(parent, changed, beta, valid, out):
    """out = parent but out.flat[changed] = beta * valid there; returns out.sum(axis=2) in numpy's order, (p, N).

    The trial angles of a fused generation and their :func:`masked_row_sums` in one pass:
    parent (p, N, K) holds masked angles (masking them again changes no bit), changed (c,)
    ascending flat indices into (p, N, K), beta (c,) their unmasked angles, valid (p, K).
    For K <= PAIRWISE_BLOCK.
    """
    p, N, K = parent.shape
    total = np.empty((p, N))
    c = 0
    for a in range(p):
        for i in range(N):
            for k in range(K):  # element by element: a slice assignment per row cost more than the copy
                out[a, i, k] = parent[a, i, k]
            base = (a * N + i) * K
            while c < len(changed) and changed[c] < base + K:
                k = changed[c] - base
                out[a, i, k] = beta[c] * valid[a, k]
                c += 1
            total[a, i] = 0.0 + _pairwise_sum(out[a, i], K)
    return total
