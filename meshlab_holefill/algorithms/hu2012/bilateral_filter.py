"""Bilateral mesh filtering of selected vertices (Fleishman et al. 2003, as used by Hu et al. Sec. III.D)."""
from __future__ import annotations

import numpy as np

from ...geometry.sets import unique_ints
from ...geometry.quality import cross_rows, triangle_quality, vertex_normals
from ._bilateral_kernels import refuse_slivers, ring_log_weights, ring_step

__all__ = ["bilateral_filter"]


def _radius_pairs(V, movable, rho, fixed_points):
    """(rows, cols) of every point within rho[row] of a movable vertex (Fleishman's N(v)).

    Columns index V followed by ``fixed_points``; a vertex is not its own neighbour.
    """
    from scipy.spatial import cKDTree

    X = V if fixed_points is None or len(fixed_points) == 0 else np.concatenate([V, fixed_points])
    mov = np.flatnonzero(movable)
    if len(mov) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), X
    lists = cKDTree(X).query_ball_point(V[mov], r=rho[mov], return_sorted=True)
    counts = np.fromiter((len(x) for x in lists), np.int64, len(lists))
    rows = np.repeat(mov, counts)
    cols = np.fromiter((j for x in lists for j in x), np.int64, int(counts.sum()))
    keep = rows != cols
    return rows[keep], cols[keep], X


def _ring_pairs(F, n):
    """(rows, cols) of the 1-ring adjacency, ordered by row then column, once each: the entries
    of ``one_ring_matrix(F, n).tocoo()`` (a canonical CSR matrix), without building it."""
    F = np.asarray(F, np.int64)
    i = np.concatenate([F[:, 0], F[:, 1], F[:, 2], F[:, 1], F[:, 2], F[:, 0]])
    j = np.concatenate([F[:, 1], F[:, 2], F[:, 0], F[:, 0], F[:, 1], F[:, 2]])
    keys = unique_ints(i * n + j)
    return keys // n, keys % n


def _row_maxima(rows, values, n):
    """Largest value per row (-inf for rows without values) for sorted ``rows``: np.maximum.at's
    answer (maxima are exact, NaN propagates in both), by one reduceat."""
    out = np.full(n, -np.inf)
    if len(rows) == 0:
        return out
    starts = np.flatnonzero(np.concatenate([[True], rows[1:] != rows[:-1]]))
    out[rows[starts]] = np.maximum.reduceat(values, starts)
    return out


def _refuse_slivers(V_old, V_new, F, moved, min_quality):
    """Undo the moves that would push an incident face below min(min_quality, its quality before).

    Moves are undone vertex by vertex around each offending face, a few passes until no face
    offends (a face made of unmoved vertices keeps its quality, so this terminates). Compiled
    (:func:`._bilateral_kernels.refuse_slivers`, the bits of :func:`_refuse_slivers_numpy`).
    """
    F = np.ascontiguousarray(F, np.int64)
    if len(F) and (F.min() < 0 or F.max() >= len(V_old)):
        return _refuse_slivers_numpy(V_old, V_new, F, moved, min_quality)
    return refuse_slivers(np.ascontiguousarray(V_old, np.float64), np.ascontiguousarray(V_new, np.float64), F,
                          np.ascontiguousarray(moved, bool), float(min_quality))


def _refuse_slivers_numpy(V_old, V_new, F, moved, min_quality):
    """:func:`_refuse_slivers` in numpy (the reference of the compiled guard)."""
    q_old = triangle_quality(V_old, F)
    floor = np.minimum(q_old, min_quality)
    n_old = cross_rows(V_old[F[:, 1]] - V_old[F[:, 0]], V_old[F[:, 2]] - V_old[F[:, 0]])
    V = V_new.copy()
    moved = moved.copy()
    for _ in range(len(V)):
        n_new = cross_rows(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        bad = (triangle_quality(V, F) < floor * (1 - 1e-12)) | (np.einsum("ij,ij->i", n_old, n_new) <= 0)
        bad &= moved[F].any(axis=1)
        if not bad.any():
            break
        back = np.unique(F[bad].ravel())
        back = back[moved[back]]
        V[back] = V_old[back]
        moved[back] = False
    return V


def _valid_faces(F, n):
    """Whether the compiled ring iteration may index V (n rows) by F."""
    F = np.asarray(F)
    return F.ndim == 2 and F.shape[1] == 3 and np.issubdtype(F.dtype, np.integer) and (
        len(F) == 0 or (F.min() >= 0 and F.max() < n))


def bilateral_filter(V, F, movable, sigma_c, sigma_s, iterations=3, *, neighbourhood="ring", fixed_points=None,
                     radius=2.0, min_quality=None, compiled=True):
    """Move vertices along their normals by the bilateral filter (Hu et al. Sec. III.D, Eq. 3-4).

    For a vertex v with unit normal n (area-weighted) and neighbours q_i:
    t_i = |v - q_i|, h_i = <n, v - q_i>, w_i = exp(-t_i^2 / (2 sigma_c^2)) exp(-h_i^2 / (2 sigma_s^2)),
    and v <- v - n * sum(w_i h_i) / sum(w_i). The paper prints ``v + n d``; with its own
    definition of h that would push a vertex away from its neighbours, so we follow
    Fleishman et al.'s original sign, which moves it toward them.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    movable : (n,) bool
        Vertices to filter (the patch interior); the others stay fixed.
    sigma_c, sigma_s : float or (n,) float64
        Closeness and feature-preserving widths, per vertex or global.
    iterations : int
    neighbourhood : {"ring", "radius"}
        "ring" (default): the 1-ring of v, as the paper's pseudo-code says. "radius": every
        point closer than rho = ``radius`` * sigma_c (Eq. 4's N(u), Fleishman et al.'s rho = 2
        sigma_c), among V and ``fixed_points``.
    fixed_points : (p, 3) float64, optional
        Points that are neighbours with "radius" but never move (the surrounding mesh's
        vertices around a hole).
    radius : float
        rho / sigma_c for "radius".
    min_quality : float, optional
        Guard: after each iteration, moves that would leave a face with quality 2r/R below
        min(min_quality, its quality before the iteration), or flip it, are undone. None
        (default) moves every vertex.
    compiled : bool
        With the "ring" neighbourhood, run each iteration's normals, weights and moves compiled
        (:mod:`._bilateral_kernels`, the same bits); False runs numpy only.

    Returns
    -------
    V : (n, 3) float64
    """
    V = np.array(V, np.float64)
    n = len(V)
    movable = np.ascontiguousarray(movable, bool)
    sc_all = np.ascontiguousarray(np.broadcast_to(np.asarray(sigma_c, np.float64), (n,)))
    ss_all = np.ascontiguousarray(np.broadcast_to(np.asarray(sigma_s, np.float64), (n,)))
    rows = cols = None
    if neighbourhood == "ring":
        rows, cols = _ring_pairs(F, n)
        keep = movable[rows]
        rows, cols = rows[keep], cols[keep]
    elif neighbourhood != "radius":
        raise ValueError(f"unknown neighbourhood {neighbourhood!r}")
    compiled = compiled and neighbourhood == "ring" and _valid_faces(F, n)
    F = np.ascontiguousarray(F, np.int64) if compiled else np.asarray(F)
    for _ in range(iterations):
        if compiled:
            N, h, z = ring_log_weights(V, F, rows, cols, sc_all, ss_all)
            V_new, moved = ring_step(V, N, rows, np.exp(z), h, movable)
        else:
            if neighbourhood == "radius":
                rows, cols, X = _radius_pairs(V, movable, radius * sc_all, fixed_points)
            else:
                X = V
            V_new, moved = _numpy_iteration(V, X, F, rows, cols, sc_all, ss_all, movable)
        V = V_new if min_quality is None else _refuse_slivers(V, V_new, F, moved, min_quality)
    return V


def _numpy_iteration(V, X, F, rows, cols, sc_all, ss_all, movable):
    """One iteration of :func:`bilateral_filter` in numpy: (moved vertices, which moved).

    Pairs (rows[p], cols[p]) join a vertex of V to its neighbour in X (V, or V then fixed points).
    """
    n = len(V)
    N = vertex_normals(V, F, n)
    sc, ss = sc_all[rows], ss_all[rows]
    D = V[rows] - X[cols]
    t2 = np.einsum("ij,ij->i", D, D)
    h = np.einsum("ij,ij->i", N[rows], D)
    # Work with log-weights so that a narrow closeness kernel does not underflow to 0/0.
    logw = -t2 / (2 * sc ** 2) - h ** 2 / (2 * ss ** 2)
    shift = _row_maxima(rows, logw, n)
    w = np.exp(logw - shift[rows])
    num = np.bincount(rows, weights=w * h, minlength=n)
    den = np.bincount(rows, weights=w, minlength=n)
    d = np.zeros(n)
    ok = movable & (den > 0)
    d[ok] = num[ok] / den[ok]
    V_new = V.copy()
    V_new[ok] -= N[ok] * d[ok, None]
    return V_new, ok & (d != 0)
