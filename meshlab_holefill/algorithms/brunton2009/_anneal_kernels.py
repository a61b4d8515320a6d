"""Compiled moves of the curve-unfolding annealing (Brunton et al. 2009, Sec. 3.1).

For one colour class of :func:`.annealing.anneal_loop`, :func:`propose_moves` makes the moves'
directions and lengths (:func:`.annealing._propose_moves`) and the geometry of their change of
E_PE (:func:`.annealing._energy_change`), and :func:`apply_moves` the clearance d_MD > eps
(:func:`.annealing._keep_clearance`) and the updates of the loop state; the random numbers,
arctan2, exp and the Metropolis rule stay numpy calls in between (numpy's vectorised arctan2
and exp differ from the C library's in the last bit). Every other quantity is computed by the
operations of the numpy code in the same order (cross products as ``cross_rows``, row sums and
norms added left to right as numpy adds three columns, no FMA contraction, the distance rows
written before the columns), so the annealed loop is the same to the last bit; the numpy steps
stay in :mod:`.annealing` as the reference the tests compare with. The numpy code spent most of
its time in the overhead of small array operations (a class holds m / 4 vertices, a run up to
5000 moves): 3.4 times less process time for the annealing on the benchmark's 45 cut holes.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...geometry.segments import _distance_rows

__all__ = ["propose_moves", "apply_moves"]


@njit(cache=True)
def _cross(a, b):
    """``cross_rows`` of two 3-vectors."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def _norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@njit(cache=True)
def _direction(g, u1, prev, cone, tan_cone):
    """The unit direction of one move: g normalised, or tilted within the cone around ``prev``."""
    if not cone:
        return g / _norm(g)
    dot = g[0] * prev[0] + g[1] * prev[1] + g[2] * prev[2]
    w = g - dot * prev
    wn = _norm(w)
    w = w / (wn if wn > 0 else 1.0)
    d = prev + (u1 * tan_cone) * w
    return d / _norm(d)


@njit(cache=True)
def propose_moves(P, N, D, J, G, U, last_dir, improving, d_md, eps, local_bound, tan_cone):
    """The moves of the vertices J of one colour class, as :func:`.annealing._propose_moves` and the
    geometric part of :func:`.annealing._energy_change`.

    ``last_dir`` is updated. The four angles each move changes are returned as the two arguments of
    their arctan2 (|n_1 x n_2| and n_1 . n_2): numpy's arctan2 (vectorised, not libm's) is
    applied by the caller, so the angles keep their last bits.

    Returns
    -------
    q : (b, 3) float64  new positions
    normals : (3, b, 3) float64  the new n_{j-2}, n_{j-1}, n_j
    y, x : (4, b) float64  arctan2 arguments of the new d_PE(p_{j-3}) .. d_PE(p_j)
    """
    m, b = P.shape[0], J.shape[0]
    q = np.empty((b, 3))
    normals = np.empty((3, b, 3))
    y = np.empty((4, b))
    x = np.empty((4, b))
    for i in range(b):
        j = J[i]
        jm, jp, jm2, jm3, jp2 = (j - 1) % m, (j + 1) % m, (j - 2) % m, (j - 3) % m, (j + 2) % m
        d = _direction(G[i], U[i, 1], last_dir[j], improving[j], tan_cone)
        last_dir[j] = d
        clearance = min(D[jm].min(), D[j].min()) if local_bound else d_md
        length = U[i, 0] * 0.5 * max(eps, clearance)
        q[i] = P[j] + length * d
        normals[0, i] = _cross(P[jm2] - P[jm], q[i] - P[jm])
        normals[1, i] = _cross(P[jm] - q[i], P[jp] - q[i])
        normals[2, i] = _cross(q[i] - P[jp], P[jp2] - P[jp])
        pairs = ((N[jm3], normals[0, i]), (normals[0, i], normals[1, i]), (normals[1, i], normals[2, i]),
                 (normals[2, i], N[jp]))
        for t in range(4):
            n1, n2 = pairs[t]
            y[t, i] = _norm(_cross(n1, n2))
            x[t, i] = n1[0] * n2[0] + n1[1] * n2[1] + n1[2] * n2[2]
    return q, normals, y, x


@njit(cache=True)
def _keep_clearance(P, J, q, acc, mask, near, eps):
    """``annealing._keep_clearance``: the moves kept, the loop with them, the moved segments and their rows."""
    m, b = P.shape[0], J.shape[0]
    trial = P.copy()
    moved = np.zeros(0, np.int64)
    rows = np.zeros((0, m))
    for _ in range(3):
        if not acc.any():
            return acc, trial, moved, rows
        trial = P.copy()
        is_moved = np.zeros(m, np.bool_)
        for i in range(b):
            if acc[i]:
                trial[J[i]] = q[i]
                is_moved[(J[i] - 1) % m] = True
                is_moved[J[i]] = True
        ends = np.empty_like(trial)
        ends[: m - 1] = trial[1:]
        ends[m - 1] = trial[0]
        moved = np.flatnonzero(is_moved)
        rows = _distance_rows(trial[moved], ends[moved], trial, ends, mask[moved], near, False)
        is_bad = np.zeros(m, np.bool_)
        any_bad = False
        for r in range(moved.shape[0]):
            if rows[r].min() <= eps:
                is_bad[moved[r]] = True
                any_bad = True
        if not any_bad:
            return acc, trial, moved, rows
        for i in range(b):
            if is_bad[J[i]] or is_bad[(J[i] - 1) % m]:
                acc[i] = False
    acc[:] = False
    return acc, trial, moved, rows


@njit(cache=True)
def apply_moves(P, N, T, D, J, q, normals, angles, acc, mask, near, eps):
    """The moves ``acc`` (Metropolis) of one class that keep d_MD > eps, applied to the state in place.

    As :func:`.annealing._keep_clearance` and the updates of :func:`.annealing.anneal_loop`: P, the
    triple normals N, the d_PE terms T and the segment distances D.

    Returns
    -------
    acc : (b,) bool  the moves kept
    d_md : float  the clearance after them (-1 when none was kept: unchanged)
    """
    m = P.shape[0]
    acc, trial, moved, rows = _keep_clearance(P, J, q, acc, mask, near, eps)
    if not acc.any():
        return acc, -1.0
    for i in range(J.shape[0]):
        if acc[i]:
            j = J[i]
            N[(j - 2) % m], N[(j - 1) % m], N[j] = normals[0, i], normals[1, i], normals[2, i]
            T[(j - 3) % m], T[(j - 2) % m] = angles[0, i], angles[1, i]
            T[(j - 1) % m], T[j] = angles[2, i], angles[3, i]
    P[:] = trial
    for r in range(moved.shape[0]):
        D[moved[r], :] = rows[r]
    # Columns after rows, as numpy: distances are symmetric only to rounding. Row by row, so that
    # the writes run along memory.
    for i in range(m):
        for r in range(moved.shape[0]):
            D[i, moved[r]] = rows[r, i]
    return acc, D.min()
