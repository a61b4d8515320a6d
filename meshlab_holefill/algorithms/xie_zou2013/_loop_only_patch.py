"""HPDE's last resort, beyond the paper: a patch of the loop alone, when every layout of Algorithm 2 fails.

:func:`loop_only_patch` triangulates the loop by Liepa's weights (or flat in the PCA plane, or by
the compiled least-bend triangulations for long loops), then relaxes it and raises its quality
with splits, and refines and fairs it as Liepa does where that bends less against the surface
(else refines it alone), each kept only if clean. :mod:`._algorithm2` calls it after the last layout.
"""
from __future__ import annotations

import itertools

import numpy as np

from ...core.border_bend import border_bend
from ...core.least_bend import least_bend_triangulations
from ...core.patch import Patch
from ...errors import HoleFillError
from ...geometry.laplacian import tangential_umbrella_smoothing
from ...geometry.quality import triangle_quality
from ...geometry.refine import refine_patch
from ...geometry.topology import boundary_edges_and_chords
from . import folds
from . import optimisation as optimisation_steps
from . import quality_pass
from . import triangulation
from ..hu2012.fairing import fair_patch_in_context
from ._smooth_and_optimise import RELAX_ROUNDS

__all__ = ["loop_only_patch", "faired_where_less_bent", "LAST_RESORT_ANGLE"]

LAST_RESORT_ANGLE = np.radians(175.0)  # largest crease the loop-only last resort accepts
LAST_RESORT_FLOORS = (0.4, 0.6)  # quality pass floors of the loop-only last resort (splits give it inner vertices)


def loop_only_patch(ctx, base, normals, seg, mesh_normals, optimisation, info, fair=True):
    """Last resort (beyond the paper): the loop alone, triangulated by Liepa's weights or flat in the PCA plane.

    Loops longer than ``folds.LOOP_TRIANGULATION_SIZE`` take the compiled least-bend triangulations
    (:func:`meshlab_holefill.core.least_bend.least_bend_triangulations`, the same weights) after the plane.

    Teeth of a crumpled scan border force sharp creases there, so up to LAST_RESORT_ANGLE is
    accepted (a triangle flipped onto its neighbour is at 180 degrees). The first candidate
    that duplicates no mesh edge, has no sharper fold and does not cross the rings is relaxed
    (``relax``: its splits give it interior vertices) and raised by the quality pass with
    splits (``quality_floor``), each kept only if clean; then, with ``fair``, refined and faired
    where that bends less against the surface (:func:`faired_where_less_bent`).

    Returns
    -------
    Patch or None
        With ``info`` (updated with the quality pass's counts); None when no candidate is clean.
    """
    k = ctx.size
    P = ctx.points
    blocked = folds.crossing_triangles(ctx)  # loop triangles crossing the rings (none found past its size cap)
    candidates = [folds.loop_triangulation(P, mesh_normals, ctx.forbidden_edges,
                                           max_size=folds.LOOP_TRIANGULATION_SIZE, blocked=blocked)[0]]
    try:
        pmap = triangulation.plane_map_for(base, normals, seg, False)
        candidates.append(triangulation.triangulate_projection(P, np.zeros((0, 3)), pmap, 0.0)[1])
    except HoleFillError:
        pass
    fe = np.sort(np.asarray(ctx.forbidden_edges, np.int64).reshape(-1, 2), axis=1)
    # Loops too long for folds.loop_triangulation: the compiled least-bend triangulations, lazily.
    for F in itertools.chain(candidates, least_bend_triangulations(ctx) if k > folds.LOOP_TRIANGULATION_SIZE else ()):
        if F is None or len(F) == 0:
            continue
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        if len(fe) and np.isin(fe[:, 0] * k + fe[:, 1], E[:, 0] * k + E[:, 1]).any():
            continue
        if folds.local_folds(P, F, mesh_normals, max_angle=LAST_RESORT_ANGLE).any():
            continue
        if folds.intersects_surroundings(ctx, P, F):
            continue
        V = P
        if optimisation.relax > 0:
            V, F = _relax_loop_only(ctx, P, F, mesh_normals, optimisation.relax)
        if optimisation.quality_floor > 0:
            V, F = _raise_loop_only_quality(ctx, V, F, mesh_normals, info, blocked)
        patch = Patch(vertices=V[k:], faces=F, info=info)
        return faired_where_less_bent(ctx, patch, mesh_normals, optimisation, blocked) if fair else patch
    return None


def faired_where_less_bent(ctx, patch, mesh_normals, optimisation, blocked=None):
    """A loop-only patch refined and faired as Liepa's fill is, where that bends less against the surface;
    else refined alone, where that is clean.

    The least-bend triangulation of the loop and its splits lie across the hole as a near-flat
    sheet. Liepa refines such a patch to the density of the surrounding mesh and fairs it; so
    does this last resort: the refinement of :func:`meshlab_holefill.geometry.refine.refine_patch`
    (centroid splits and relaxation swaps; the loop's vertices at their rings' mean edge length,
    the splits' vertices at the loop's mean, the loop edges and chords fixed), then the
    thin-plate energy with the hole's rings fixed (:func:`..hu2012.fairing.fair_patch_in_context`),
    so the patch continues the surface's slope across the border. The faired patch is kept only
    when it is clean (no fold beyond LAST_RESORT_ANGLE, no crossing of the rings), bends less
    against the surface across the border (:func:`meshlab_holefill.core.border_bend.border_bend`,
    the criterion that chooses between the layouts) and, after the guarded quality pass has run
    again on it, has no triangle poorer than the patch had or than the pass's first floor (swaps
    may not create loop triangles crossing the rings: ``blocked``, :func:`.folds.crossing_triangles`,
    found here when not given). ``info["faired"]`` says it was kept.

    Where the faired patch is not kept (on a jagged scan border it can cross the rings), the
    refined patch is kept instead when the refinement added vertices, it is clean and, after the
    quality pass, it has no triangle poorer than the patch had: it lies on the patch's own
    triangles at the surrounding density, where the coarse triangulation of a long loop holds
    slivers (a 97-edge occlusion hole of a noisy range scan: quality 0.011 -> 0.558).
    ``info["refined"]`` says so.

    Returns
    -------
    Patch  the faired patch, the refined one, or ``patch``
    """
    k = ctx.size
    V, F, info = patch.all_points(ctx.points), patch.faces, patch.info
    scale = np.r_[ctx.edge_scale, np.full(len(V) - k, float(np.mean(ctx.edge_scale)))]
    Vr, Fr, _, _ = refine_patch(V, F, scale, fixed_edges=boundary_edges_and_chords(k, ctx.forbidden_edges),
                                criterion="angles")
    if len(Vr) == k:  # no inner vertex to fair or to add
        return patch
    poorest = triangle_quality(V, F).min()

    def raised(X, faces):
        nonlocal blocked
        counts = dict(info)
        if optimisation.quality_floor > 0:
            blocked = folds.crossing_triangles(ctx) if blocked is None else blocked
            X, faces = _raise_loop_only_quality(ctx, X, faces, mesh_normals, counts, blocked)
        return X, faces, counts

    faired = Vr.copy()
    faired[k:] = fair_patch_in_context(ctx.vertices, ctx.faces, k, Vr[k:], Fr, order=2)
    if _clean(ctx, faired, Fr, mesh_normals) and border_bend(ctx, faired[k:], Fr) < border_bend(ctx, V[k:], F):
        X, faces, counts = raised(faired, Fr)
        if triangle_quality(X, faces).min() >= min(poorest, LAST_RESORT_FLOORS[0]):
            info.update(counts, faired=True)
            return Patch(vertices=X[k:], faces=faces, info=info)
    if len(Vr) > len(V) and _clean(ctx, Vr, Fr, mesh_normals):
        X, faces, counts = raised(Vr, Fr)
        if triangle_quality(X, faces).min() >= poorest:
            info.update(counts, refined=True)
            return Patch(vertices=X[k:], faces=faces, info=info)
    return patch


def _clean(ctx, X, F, mesh_normals):
    """Finite, no fold sharper than LAST_RESORT_ANGLE, no crossing of the rings."""
    if not np.all(np.isfinite(X)) or folds.local_folds(X, F, mesh_normals, max_angle=LAST_RESORT_ANGLE).any():
        return False
    return not folds.intersects_surroundings(ctx, X, F)


def _relax_loop_only(ctx, P, F, mesh_normals, relax):
    """Obtuse-edge splits and tangential relaxation of a loop-only patch; ``(P, F)`` back if not clean."""
    k = ctx.size
    Vr, Fr = P, F
    for _ in range(RELAX_ROUNDS):
        Vr, Fr, s_ = optimisation_steps.split_obtuse_edges(Vr, Fr, k)
        Vr = tangential_umbrella_smoothing(Vr, Fr, np.arange(len(Vr)) < k, relax)
        if s_ == 0:
            break
    if _clean(ctx, Vr, Fr, mesh_normals):
        return Vr, Fr
    return P, F


def _raise_loop_only_quality(ctx, V, F, mesh_normals, info, blocked):
    """The guarded quality pass with splits (a loop-only patch has no free vertex to move).

    Swaps may not create loop triangles that cross the rings (``blocked``,
    :func:`.folds.crossing_triangles`). Each floor of LAST_RESORT_FLOORS is kept only if it raises
    the minimum quality without crossing.
    """
    k = ctx.size

    def fold_count(V_, F_):
        return int(folds.local_folds(V_, F_, mesh_normals, max_angle=LAST_RESORT_ANGLE).sum())

    for floor in LAST_RESORT_FLOORS:
        Vq, Fq, _, qstats = quality_pass.raise_min_quality(
            V, F, k, ctx.forbidden_edges, mesh_normals, floor=floor, fold_test=fold_count, blocked=blocked,
            split=True)
        if any(qstats.values()) and not folds.intersects_surroundings(ctx, Vq, Fq) and \
                triangle_quality(Vq, Fq).min() >= min(floor, triangle_quality(V, F).min()):
            V, F = Vq, Fq
            for key, value in qstats.items():
                info[f"quality_{key}"] = info.get(f"quality_{key}", 0) + value
    return V, F
