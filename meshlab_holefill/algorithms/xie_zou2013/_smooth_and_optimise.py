"""HPDE Algorithm 2, step 7 (Sec. 4.7) on one triangulated layout: smoothing, decimation, min-angle swaps.

Xie and Zou 2013. :func:`smooth_and_optimise` runs the paper's smoothing (:mod:`.smoothing`),
short-edge decimation at the Rate threshold and min-angle swaps (:mod:`.optimisation`), with the
fold repairs of :mod:`.folds`; beyond the paper, the ``relax`` rounds (sliver collapses,
obtuse-edge splits, tangential relaxation, apex moves) and the guarded quality pass
(:mod:`.quality_pass`). :mod:`._algorithm2` calls it on every layout it tries.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...geometry.laplacian import tangential_umbrella_smoothing
from . import folds
from . import optimisation as optimisation_steps
from . import quality_pass
from . import smoothing as smoothing_steps
from . import triangulation

__all__ = ["smooth_and_optimise", "NOTCH_SPAN", "RELAX_ROUNDS"]

RELAX_ROUNDS = 3  # rounds of sliver collapse + obtuse-edge splits + tangential relaxation + swaps (relax)
SLIVER_ANGLE = np.radians(140.0)  # a free vertex this flat against a loop edge is collapsed onto it
# A fold among triangles of loop vertices only, all within a stretch of at most this many loop
# edges, is the loop's own shape (a zigzag notch of a border cut through triangles), kept as
# the ears are. bunny.obj without its lowest tenth by height (a nearly planar 231-edge loop)
# failed every attempt on such folds spanning 4 and 6 edges; with 8 it closes, and no hole of
# the benchmark or of 32 cuts by height (bunny, bone, airplane, cow) changes.
NOTCH_SPAN = 8
QUALITY_TARGET = 0.5  # relax: free vertices of triangles with 2r/R below this are moved (improve_worst_vertices)


@dataclass
class _PatchCounts:
    """The patch of step 7 (loop vertices first, ``ids`` the prediction point of each V[k:]) and its counts."""

    V: np.ndarray
    F: np.ndarray
    ids: np.ndarray
    swaps: int = 0
    collapses: int = 0
    repairs: int = 0  # fold repairs after the swaps (those before the smoothing are counted apart)


def smooth_and_optimise(V, F, ids, ctx, edge_len, mesh_normals, smoothing, optimisation, record=None):
    """Step 7 (Sec. 4.7) with the fold repairs: smoothing, decimation, min-angle swaps.

    Beyond the paper: chords duplicating mesh edges are split first, folds are repaired after
    the smoothing and the swaps, then the ``relax`` rounds and the quality pass run.

    Parameters
    ----------
    V : (k + q, 3) float64  loop vertices first, then the triangulated prediction points
    F : (t, 3) int64
    ids : (q,) int64  prediction point of each V[k:]
    ctx : HoleContext
    edge_len : float  EdgeLen
    mesh_normals : (k, 3) float64  normals of the border faces (:func:`.folds.border_normals`)
    smoothing : SmoothingOptions
    optimisation : OptimisationOptions
    record : dict, optional
        Receives ``smoothed_points``: the smoothed prediction points SP_i of Sec. 4.7, before
        decimation (the points the errors of Eq. 17 are measured on).

    Returns
    -------
    V, F : the patch (loop vertices first)
    stats : dict  ``kept``, ``collapses``, ``swaps``, ``fold_repairs``, ``folds_left`` and more
    bad_ids : (r,) int64  prediction points on faces still folded (empty when the patch is clean)
    """
    k = ctx.size
    stats = {"kept": int(len(V) - k)}
    V, F, ids, repairs = _smooth(V, F, ids, ctx, mesh_normals, smoothing, stats, record)
    V, F, collapses, keep = optimisation_steps.decimate_short_edges(V, F, k, optimisation.decimation_rate * edge_len,
                                                                    ctx.forbidden_edges)
    ids = ids[keep[k:] - k]
    F, swaps = optimisation_steps.swap_edges_min_angle(V, F, ctx.forbidden_edges)
    V, F, more = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
    patch = _PatchCounts(V, F, ids, swaps, collapses, more)
    _relax(patch, ctx, edge_len, mesh_normals, optimisation.relax, stats)
    _quality_pass(patch, ctx, mesh_normals, optimisation.quality_floor, stats)
    V, F, ids = patch.V, patch.F, patch.ids
    stats.update(collapses=int(patch.collapses), swaps=int(patch.swaps), fold_repairs=int(repairs + patch.repairs))
    bad = folds.local_folds(V, F, mesh_normals)
    # A fold of an ear (three consecutive loop vertices), or among triangles of loop vertices
    # closing a notch of at most NOTCH_SPAN loop edges, is the boundary's own shape (a 3-edge
    # hole in a crumpled scan has no other patch; a border cut through triangles zigzags); it
    # is kept and counted, the filter's intersection check still applies. Any other fold must go.
    loop_only = folds.boundary_ears(F, k, NOTCH_SPAN)
    stats["boundary_folds"] = int((bad & loop_only).sum())
    stats["folds_left"] = int((bad & ~loop_only).sum())
    verts = np.unique(F[bad & ~loop_only].ravel())
    bad_ids = ids[verts[verts >= k] - k]
    return V, F, stats, bad_ids[bad_ids >= 0]


def _smooth(V, F, ids, ctx, mesh_normals, smoothing, stats, record):
    """The NumSmooth passes of Sec. 4.7, after splitting chords that duplicate mesh edges and repairing folds.

    Returns ``V, F, ids, repairs`` (ids -1 for the split vertices, which are no prediction points).
    """
    k = ctx.size
    n_before = len(V)
    V, F, splits = triangulation.split_forbidden_edges(V, F, ctx.forbidden_edges)
    ids = np.concatenate([ids, np.full(len(V) - n_before, -1, np.int64)])  # -1: not a prediction point
    stats["forbidden_splits"] = int(splits)
    V, F, repairs = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
    if smoothing.operator == "taubin":
        V = smoothing_steps.taubin_smooth(V, F, np.arange(len(V)) < k, passes=smoothing.passes,
                                          lam=smoothing.taubin_lambda, pass_band=smoothing.taubin_pass_band)
    else:
        V = smoothing_steps.curvature_smooth(V, F, k, ctx.vertices, ctx.faces, passes=smoothing.passes,
                                             anchor=smoothing.anchor,
                                             weights="scale" if smoothing.operator == "curvature_scaled"
                                             else "uniform")
    if record is not None:
        record["smoothed_points"] = V[k:][ids >= 0].copy()
    return V, F, ids, repairs


def _relax(patch, ctx, edge_len, mesh_normals, relax, stats):
    """Beyond the paper (``relax``): sliver collapses, obtuse-edge splits, tangential relaxation, apex moves.

    Updates ``patch`` (a :class:`_PatchCounts`) in place; undone (all but the fold repairs'
    count) when it folds what the repairs cannot unfold.
    """
    k = ctx.size
    V, F, ids, swaps, collapses = patch.V, patch.F, patch.ids, patch.swaps, patch.collapses
    splits = 0
    snapshot = (V, F, ids, swaps, collapses)
    for _ in range(RELAX_ROUNDS if relax > 0 else 0):
        # Not the vertices split off an obtuse edge: they start flat and the relaxation moves them.
        eligible = np.concatenate([np.zeros(k, bool), ids != -2])
        V, F, c, keep = optimisation_steps.decimate_short_edges(V, F, k, 1e-9 * edge_len, ctx.forbidden_edges,
                                                                max_rounds=5, sliver_angle=SLIVER_ANGLE,
                                                                sliver_eligible=eligible)
        ids = ids[keep[k:] - k]
        collapses += c
        n_before = len(V)
        V, F, s = optimisation_steps.split_obtuse_edges(V, F, k)
        ids = np.concatenate([ids, np.full(len(V) - n_before, -2, np.int64)])  # -2: obtuse split
        splits += s
        V, F, r3, keep = optimisation_steps.remove_valence_three(V, F, k, ctx.forbidden_edges)
        ids = ids[keep[k:] - k]
        collapses += r3
        V = tangential_umbrella_smoothing(V, F, np.arange(len(V)) < k, relax)
        F, more_swaps = optimisation_steps.swap_edges_min_angle(V, F, ctx.forbidden_edges)
        swaps += more_swaps
        if s == 0 and c == 0:
            break
    stats["obtuse_splits"] = int(splits)
    if relax > 0:
        # The swaps cannot lift a triangle whose long edge is on the loop: move its apex.
        moved = 0
        for _ in range(2):
            V, m_ = optimisation_steps.improve_worst_vertices(V, F, k, target=QUALITY_TARGET)
            F, more_swaps = optimisation_steps.swap_edges_min_angle(V, F, ctx.forbidden_edges)
            moved += m_
            swaps += more_swaps
            if m_ == 0 and more_swaps == 0:
                break
        stats["quality_moves"] = int(moved)
    if relax > 0 and folds.local_folds(V, F, mesh_normals).any():
        V, F, again = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
        patch.repairs += again
        if (folds.local_folds(V, F, mesh_normals) & ~folds.boundary_ears(F, k, NOTCH_SPAN)).any():
            V, F, ids, swaps, collapses = snapshot  # the relaxation folded what it could not repair: undo it
            stats["relax_undone"] = True
    patch.V, patch.F, patch.ids, patch.swaps, patch.collapses = V, F, ids, swaps, collapses


def _quality_pass(patch, ctx, mesh_normals, quality_floor, stats):
    """Beyond the paper (``quality_floor``): the guarded pass of :mod:`.quality_pass` on an unfolded patch.

    Guarded swaps / moves / collapses of the triangles below the floor; undone if it makes the
    patch cross the surrounding rings. Updates ``patch`` (a :class:`_PatchCounts`) in place.
    """
    k = ctx.size
    V, F, ids = patch.V, patch.F, patch.ids

    def fold_count(V_, F_):
        return int((folds.local_folds(V_, F_, mesh_normals) & ~folds.boundary_ears(F_, k, NOTCH_SPAN)).sum())

    if quality_floor > 0 and fold_count(V, F) == 0:
        Vq, Fq, keep, qstats = quality_pass.raise_min_quality(V, F, k, ctx.forbidden_edges, mesh_normals,
                                                              floor=quality_floor, fold_test=fold_count)
        if any(qstats.values()):
            crossing = folds.intersects_surroundings(ctx, Vq, Fq)
            if not crossing or folds.intersects_surroundings(ctx, V, F):
                patch.V, patch.F = Vq, Fq
                patch.ids = np.where(keep[k:] >= 0, ids[np.maximum(keep[k:] - k, 0)], -1)
                patch.swaps += qstats["swaps"]
                patch.collapses += qstats["collapses"]
                stats["quality_moves"] = stats.get("quality_moves", 0) + qstats["moves"]
                stats["quality_splits"] = qstats["splits"]
                stats["crossing"] = bool(crossing)
            else:
                stats["quality_pass_undone"] = True
