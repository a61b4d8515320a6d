"""Density-matching refinement of a hole patch (Pfeifle and Seidel, as given by Hu et al. Sec. III.C)."""
from __future__ import annotations

import numpy as np

from ._refine_kernels import split_faces, split_test
from .flips import relax_edges
from .quality import corner_angles

__all__ = ["split_condition", "refine_patch"]


def split_condition(V, F, scale, alpha):
    """Faces to split by the centroid rule (Hu et al. Sec. III.C, Step 2).

    A face (i, j, k) with centroid c and sigma(c) = mean of the corner scales is split when,
    for every corner m, alpha * |c - v_m| > sigma(c) and alpha * |c - v_m| > sigma(v_m),
    and its largest angle is below 5 pi / 6.

    Returns
    -------
    mask : (m,) bool
    centroids : (m, 3) float64
    centroid_scale : (m,) float64
    """
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    if V.ndim == 2 and V.shape[1] == 3 and F.ndim == 2 and F.shape[1] == 3 and len(F) and \
            np.shape(scale) == (len(V),) and 0 <= F.min() and F.max() < len(V):
        mask, C, sc, sure = split_test(np.ascontiguousarray(V), np.ascontiguousarray(F),
                                       np.ascontiguousarray(scale, np.float64), float(alpha))
        if sure:  # the same bits as the numpy code below, which decides the rest
            return mask, C, sc
    return split_condition_numpy(V, F, scale, alpha)


def split_condition_numpy(V, F, scale, alpha):
    """:func:`split_condition` in numpy (the reference of the compiled test)."""
    C = V[F].mean(axis=1)
    sc = scale[F].mean(axis=1)
    dist = alpha * np.linalg.norm(V[F] - C[:, None, :], axis=2)
    mask = np.all(dist > sc[:, None], axis=1) & np.all(dist > scale[F], axis=1)
    mask &= corner_angles(V, F).max(axis=1) < 5.0 * np.pi / 6.0
    return mask, C, sc


def refine_patch(V, F, scale, alpha=np.sqrt(2.0), fixed_edges=None, max_iterations=200, allowed=None,
                 criterion="sphere", relax=None):
    """Refine a patch until its density matches the scale of its boundary (Hu et al. Sec. III.C).

    Step 1 (the scales of the boundary vertices) is the caller's ``scale``. Steps 2-5:
    split every face meeting :func:`split_condition` at its centroid into three (the new
    vertex inherits sigma(c)), relax interior edges by the circumsphere test until no edge
    swaps (:func:`relax_edges`), and repeat until no face is split. The paper relaxes the
    three edges of each split face first and then all interior edges; relaxing all interior
    edges after each round of splits reaches the same fixed point.

    Parameters
    ----------
    V : (n, 3) float64
        Patch vertices (boundary vertices included).
    F : (m, 3) int64
    scale : (n,) float64
        sigma(v) of each vertex (average incident edge length in the surrounding mesh for
        boundary vertices).
    alpha : float
        Density control factor (sqrt(2) in the paper).
    fixed_edges : (p, 2) int, optional
        Edges never swapped nor created (the hole boundary and forbidden chords).
    max_iterations : int
        Bound on split rounds (convergence normally takes far fewer).
    allowed : callable, optional
        Passed to :func:`relax_edges` to veto swaps.
    criterion : {"sphere", "angles"}
        Relaxation test, passed to :func:`relax_edges`.
    relax : callable, optional
        ``relax(V, F) -> (F, swaps)`` run instead of ``relax_edges(V, F, fixed_edges,
        allowed=allowed, criterion=criterion)`` (a caller's faster equivalent).

    Returns
    -------
    V : (n + s, 3) float64
    F : (m + 2 s, 3) int64
    scale : (n + s,) float64
    info : dict  with ``split_rounds`` and ``swaps``
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    scale = np.asarray(scale, np.float64)
    if relax is None:
        def relax(V, F):
            return relax_edges(V, F, fixed_edges, allowed=allowed, criterion=criterion)
    swaps = 0
    rounds = 0
    F, s = relax(V, F)
    swaps += s
    for rounds in range(1, max_iterations + 1):
        mask, C, sc = split_condition(V, F, scale, alpha)
        if not mask.any():
            rounds -= 1
            break
        V, F, scale = split_faces(np.ascontiguousarray(V), np.ascontiguousarray(F), np.ascontiguousarray(scale),
                                  mask, C, sc)
        F, s = relax(V, F)
        swaps += s
    return V, F, scale, {"split_rounds": rounds, "swaps": swaps}
