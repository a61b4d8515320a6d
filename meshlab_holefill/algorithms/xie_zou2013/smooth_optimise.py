"""HPDE step 7 (Xie and Zou 2013, Sec. 4.7): smoothing and mesh optimisation of the patch.

The paper's step smooths the triangulation of the loop and the prediction points (NumSmooth
passes), collapses edges shorter than the Rate threshold and swaps edges to raise the minimum
angle. :func:`smooth_and_optimise` runs it with what the filter adds around it: splits of edges
the mesh already has, fold repairs, the ``relax`` rounds and the final quality pass
(beyond the paper, each documented in :mod:`.differential_evolution`).
"""
from __future__ import annotations

import numpy as np

from ...geometry.laplacian import tangential_umbrella_smoothing
from . import folds
from . import triangulation as mesh_steps
from . import optimisation
from . import quality_pass as hpde_quality
from . import smoothing as smoothing_steps

RELAX_ROUNDS = 3  # rounds of sliver collapse + obtuse-edge splits + tangential relaxation + swaps (relax)
SLIVER_ANGLE = np.radians(140.0)  # a free vertex this flat against a loop edge is collapsed onto it
QUALITY_TARGET = 0.5  # relax: free vertices of triangles with 2r/R below this are moved (improve_worst_vertices)


def smooth_and_optimise(V, F, ids, ctx, edge_len, mesh_normals, num_smooth, decimation_rate, relax=0,
                        smoothing="taubin", record=None, anchor=0.0, quality_floor=0.0,
                        pass_band=0.0, taubin_lambda=smoothing_steps.TAUBIN_LAMBDA):
    """Step 7 (Sec. 4.7) with the fold repairs: smoothing, decimation, min-angle swaps.

    ``record`` (a dict, optional) receives ``smoothed_points``: the smoothed prediction points
    SP_i of Sec. 4.7, before decimation (the points the errors of Eq. 17 are measured on).

    Returns
    -------
    V, F : the patch (loop vertices first)
    stats : dict  ``kept``, ``collapses``, ``swaps``, ``fold_repairs``
    bad_ids : (r,) int64  prediction points on faces still folded (empty when the patch is clean)
    """
    k = ctx.size
    stats = {"kept": int(len(V) - k)}
    n_before = len(V)
    V, F, splits = mesh_steps.split_forbidden_edges(V, F, ctx.forbidden_edges)
    ids = np.concatenate([ids, np.full(len(V) - n_before, -1, np.int64)])  # -1: not a prediction point
    stats["forbidden_splits"] = int(splits)
    V, F, repairs = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
    if smoothing == "taubin":
        V = smoothing_steps.taubin_smooth(V, F, np.arange(len(V)) < k, passes=num_smooth, lam=taubin_lambda,
                                          pass_band=pass_band)
    else:
        V = smoothing_steps.curvature_smooth(V, F, k, ctx.vertices, ctx.faces, passes=num_smooth, anchor=anchor,
                                             weights="scale" if smoothing == "curvature_scaled" else "uniform")
    if record is not None:
        record["smoothed_points"] = V[k:][ids >= 0].copy()
    V, F, collapses, keep = optimisation.decimate_short_edges(V, F, k, decimation_rate * edge_len, ctx.forbidden_edges)
    ids = ids[keep[k:] - k]
    F, swaps = optimisation.swap_edges_min_angle(V, F, ctx.forbidden_edges)
    V, F, more = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
    splits = 0
    snapshot = (V, F, ids, swaps, collapses)
    for _ in range(RELAX_ROUNDS if relax > 0 else 0):
        # Not the vertices split off an obtuse edge: they start flat and the relaxation moves them.
        eligible = np.concatenate([np.zeros(k, bool), ids != -2])
        V, F, c, keep = optimisation.decimate_short_edges(V, F, k, 1e-9 * edge_len, ctx.forbidden_edges, max_rounds=5,
                                                        sliver_angle=SLIVER_ANGLE, sliver_eligible=eligible)
        ids = ids[keep[k:] - k]
        collapses += c
        n_before = len(V)
        V, F, s = optimisation.split_obtuse_edges(V, F, k)
        ids = np.concatenate([ids, np.full(len(V) - n_before, -2, np.int64)])  # -2: obtuse split
        splits += s
        V, F, r3, keep = optimisation.remove_valence_three(V, F, k, ctx.forbidden_edges)
        ids = ids[keep[k:] - k]
        collapses += r3
        V = tangential_umbrella_smoothing(V, F, np.arange(len(V)) < k, relax)
        F, more_swaps = optimisation.swap_edges_min_angle(V, F, ctx.forbidden_edges)
        swaps += more_swaps
        if s == 0 and c == 0:
            break
    stats["obtuse_splits"] = int(splits)
    if relax > 0:
        # The swaps cannot lift a triangle whose long edge is on the loop: move its apex.
        moved = 0
        for _ in range(2):
            V, m_ = optimisation.improve_worst_vertices(V, F, k, target=QUALITY_TARGET)
            F, more_swaps = optimisation.swap_edges_min_angle(V, F, ctx.forbidden_edges)
            moved += m_
            swaps += more_swaps
            if m_ == 0 and more_swaps == 0:
                break
        stats["quality_moves"] = int(moved)
    if relax > 0 and folds.local_folds(V, F, mesh_normals).any():
        V, F, again = folds.repair_folds(V, F, k, ctx.forbidden_edges, mesh_normals)
        more += again
        if (folds.local_folds(V, F, mesh_normals) & ~folds.boundary_ears(F, k)).any():
            V, F, ids, swaps, collapses = snapshot  # the relaxation folded what it could not repair: undo it
            stats["relax_undone"] = True
    def fold_count(V_, F_):
        return int((folds.local_folds(V_, F_, mesh_normals) & ~folds.boundary_ears(F_, k)).sum())

    if quality_floor > 0 and fold_count(V, F) == 0:
        # Beyond the paper (hpde_quality): guarded swaps / moves / collapses of the triangles
        # below the floor; undone if it makes the patch cross the surrounding rings.
        Vq, Fq, keep, qstats = hpde_quality.raise_min_quality(V, F, k, ctx.forbidden_edges, mesh_normals,
                                                               floor=quality_floor, fold_test=fold_count)
        if any(qstats.values()):
            crossing = folds.intersects_surroundings(ctx, Vq, Fq)
            if not crossing or folds.intersects_surroundings(ctx, V, F):
                V, F, ids = Vq, Fq, np.where(keep[k:] >= 0, ids[np.maximum(keep[k:] - k, 0)], -1)
                swaps += qstats["swaps"]
                collapses += qstats["collapses"]
                stats["quality_moves"] = stats.get("quality_moves", 0) + qstats["moves"]
                stats["quality_splits"] = qstats["splits"]
                stats["crossing"] = bool(crossing)
            else:
                stats["quality_pass_undone"] = True
    stats.update(collapses=int(collapses), swaps=int(swaps), fold_repairs=int(repairs + more))
    bad = folds.local_folds(V, F, mesh_normals)
    # A fold of an ear (three consecutive loop vertices) is the boundary's own shape (a 3-edge
    # hole in a crumpled scan has no other patch); it is kept and counted, the filter's
    # intersection check still applies. Any other fold must go.
    loop_only = folds.boundary_ears(F, k)
    stats["boundary_folds"] = int((bad & loop_only).sum())
    stats["folds_left"] = int((bad & ~loop_only).sum())
    verts = np.unique(F[bad & ~loop_only].ravel())
    bad_ids = ids[verts[verts >= k] - k]
    return V, F, stats, bad_ids[bad_ids >= 0]
