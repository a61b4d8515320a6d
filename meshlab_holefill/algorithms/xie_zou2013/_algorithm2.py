"""HPDE Algorithm 2, steps 2-7 in the paper's order, with the attempts and fallbacks the filter adds.

Xie and Zou 2013. :func:`patch_hole` runs, for one hole:

* step 2 (Sec. 4.2, :mod:`.sections`): EdgeLen, the base points, their normals and the Eq. 8
  segmentation (:func:`boundary_step`);
* steps 3-5 (Sec. 4.3-4.5, :func:`.prediction.predict_points`): correspondences, section
  planes and the DE prediction of the points, once per prediction (segmented or not);
* step 6 (Sec. 4.6, :func:`.triangulation.triangulate_layout`): the constrained triangulation
  of one layout, fold-overs detected (:mod:`.folds`);
* step 7 (Sec. 4.7, :func:`smooth_and_optimise`): smoothing (:mod:`.smoothing`), decimation and
  min-angle swaps (:mod:`.optimisation`), then beyond the paper the ``relax`` rounds and the
  guarded quality pass (:mod:`.quality_pass`);

trying the layouts in :func:`attempt_order` until one is clean, and the loop-only
triangulation (:func:`loop_only_patch`) as the last resort. The readings behind each choice
are in the module docstring of :mod:`.differential_evolution`.
"""
from __future__ import annotations

import functools
import itertools
import time
from dataclasses import dataclass

import numpy as np

from ...core.border_bend import border_bend
from ...core.least_bend import least_bend_triangulations
from ...core.patch import Patch
from ...errors import HoleFillError
from ...geometry.laplacian import tangential_umbrella_smoothing
from ...geometry.quality import triangle_quality
from . import folds
from . import optimisation as optimisation_steps
from . import prediction as prediction_steps
from . import quality_pass
from . import sections
from . import smoothing as smoothing_steps
from . import triangulation

__all__ = ["PredictionOptions", "SmoothingOptions", "OptimisationOptions", "patch_hole", "boundary_step",
           "attempt_order", "smooth_and_optimise", "loop_only_patch"]

OUTLIER_ROUNDS = 4  # rounds of leaving out prediction points on faces that stay folded
LAST_RESORT_ANGLE = np.radians(175.0)  # largest crease the loop-only last resort accepts
LAST_RESORT_FLOORS = (0.4, 0.6)  # quality pass floors of the loop-only last resort (splits give it inner vertices)
MIN_COVERAGE = 0.5  # a pairing keeping fewer base points than this share yields to the other choice
GOOD_KEPT_SHARE = 0.5  # a layout keeping fewer prediction points is used only if no other keeps more
RELAX_ROUNDS = 3  # rounds of sliver collapse + obtuse-edge splits + tangential relaxation + swaps (relax)
SLIVER_ANGLE = np.radians(140.0)  # a free vertex this flat against a loop edge is collapsed onto it
# A fold among triangles of loop vertices only, all within a stretch of at most this many loop
# edges, is the loop's own shape (a zigzag notch of a border cut through triangles), kept as
# the ears are. bunny.obj without its lowest tenth by height (a nearly planar 231-edge loop)
# failed every attempt on such folds spanning 4 and 6 edges; with 8 it closes, and no hole of
# the benchmark or of 32 cuts by height (bunny, bone, airplane, cow) changes.
NOTCH_SPAN = 8
QUALITY_TARGET = 0.5  # relax: free vertices of triangles with 2r/R below this are moved (improve_worst_vertices)


@dataclass(frozen=True)
class PredictionOptions:
    """Steps 2-5: the segmentation and correspondence angles (degrees) and the DE settings."""

    critical_dihedral: float = 90.0
    critical_intersection: float = 12.0
    population_factor: float = 3.0
    mutation: float = 0.8
    crossover: float = 0.05
    generations: int = 100
    seed: int = 0
    arc_tangent: str = "secant"

    def de_options(self):
        """Keyword arguments of :func:`.prediction.predict_y`."""
        return dict(N_factor=self.population_factor, F=self.mutation, CR=self.crossover,
                    generations=self.generations, seed=self.seed)


@dataclass(frozen=True)
class SmoothingOptions:
    """Step 7, first half: the smoothing operator, its NumSmooth passes and its settings."""

    operator: str = "taubin"
    passes: int = 60
    taubin_lambda: float = smoothing_steps.TAUBIN_LAMBDA
    taubin_pass_band: float = 0.0
    anchor: float = 0.0


@dataclass(frozen=True)
class OptimisationOptions:
    """Step 7, second half: the decimation Rate, and beyond the paper ``relax`` and ``quality_floor``."""

    decimation_rate: float = 0.6
    relax: int = 0
    quality_floor: float = 0.0


@dataclass(frozen=True)
class _Hole:
    """What every attempt on one hole shares: the hole, the results of step 2 and the step-7 options."""

    ctx: object  # HoleContext
    base: sections.BasePoints
    normals: np.ndarray  # (n, 3) surface normals at the base points
    seg: dict  # sections.segment_boundary
    edge_len: float  # EdgeLen
    mesh_normals: np.ndarray  # (k, 3) normals of the border faces
    smoothing: SmoothingOptions
    optimisation: OptimisationOptions

    @functools.cached_property
    def development(self):
        """The 'development' layout's polygon, or None (:func:`.triangulation.loop_development`), found once."""
        return triangulation.loop_development(self.ctx, self.edge_len)


@dataclass
class _PatchCounts:
    """The patch of step 7 (loop vertices first, ``ids`` the prediction point of each V[k:]) and its counts."""

    V: np.ndarray
    F: np.ndarray
    ids: np.ndarray
    swaps: int = 0
    collapses: int = 0
    repairs: int = 0  # fold repairs after the swaps (those before the smoothing are counted apart)


@dataclass
class _CleanLayout:
    """A patch of one attempt with no fold-over left that does not cross the surrounding rings."""

    V: np.ndarray
    F: np.ndarray
    stats: dict
    edge_cleared: int
    outliers: int
    record: dict
    triangulation_seconds: float
    optimisation_seconds: float


def patch_hole(ctx, prediction, smoothing, optimisation, record=None, layouts="first"):
    """Algorithm 2, steps 2-7, for one hole (see :func:`.differential_evolution.fill`).

    Parameters
    ----------
    ctx : HoleContext
    prediction : PredictionOptions
    smoothing : SmoothingOptions
    optimisation : OptimisationOptions
    record : dict, optional
        Receives ``smoothed_points`` of the returned patch.
    layouts : {'first', 'smoothest'}
        Keep the first clean attempt of :func:`attempt_order`, or make them all and keep the
        patch with the smallest :func:`meshlab_holefill.core.border_bend.border_bend` (the first
        of equals), its ``info["layout_bends"]`` the bend of each attempt's patch.

    Returns
    -------
    Patch

    Raises
    ------
    HoleFillError
        Degenerate hole, or every attempt and the last resort failed (the reasons joined).
    """
    t0 = time.perf_counter()
    k = ctx.size
    edge_len, base, normals, seg = boundary_step(ctx, prediction.critical_dihedral)
    t1 = time.perf_counter()
    de_options = prediction.de_options()
    attempts = attempt_order(base, normals, seg, np.radians(prediction.critical_intersection))
    predictions, reasons, best = {}, [], None
    discs = {}  # prediction -> the disc's attempt, made beside the development's
    mesh_normals = folds.border_normals(ctx)
    hole = _Hole(ctx, base, normals, seg, edge_len, mesh_normals, smoothing, optimisation)
    prediction_seconds = 0.0
    made = []  # with layouts='smoothest': (bend, attempt's name, patch, record) of every attempt
    for segmented, layout in attempts:
        t2 = time.perf_counter()
        if segmented not in predictions:
            # Steps 3-5, once per prediction.
            predictions[segmented] = prediction_steps.predict_points(
                ctx, base, normals, seg["split"] if segmented else None, np.radians(prediction.critical_intersection),
                edge_len, de_options, prediction.arc_tangent)
        result = predictions[segmented]
        prediction_seconds += time.perf_counter() - t2
        name = f"{'segmented' if segmented else 'unsegmented'} prediction, {layout}"
        if layout == "disc" and segmented in discs:
            clean, reason = discs.pop(segmented)
        else:
            clean, reason = _layout_patch(hole, layout, result, name)
        if clean is None:
            reasons.append(reason)
            continue
        bends = None
        if layout == "development":
            # The disc, the other fallback layout, may continue the surface better (a cap round a knob).
            discs[segmented] = _layout_patch(hole, "disc", result, name.replace("development", "disc"))
            disc = discs[segmented][0]
            if disc is not None:
                bends = {"development": border_bend(ctx, clean.V[k:], clean.F),
                         "disc": border_bend(ctx, disc.V[k:], disc.F)}
                if bends["disc"] < bends["development"]:
                    clean, layout = disc, "disc"
        info = dict(result[3])
        # Points left out next to long loop edges (triangulation.EDGE_CLEARANCE) are not lost by the layout.
        kept = (clean.stats["kept"] + clean.edge_cleared) / max(info["predicted"], 1)
        info.update(base_points=len(base), segmented=bool(segmented), layout=layout,
                    dihedral_deg=None if seg["dihedral"] is None else float(np.degrees(seg["dihedral"])),
                    outliers=clean.outliers, rate=float((len(clean.V) - k) / max(info["predicted"], 1)),
                    kept_share=float(kept), boundary_seconds=t1 - t0, prediction_seconds=prediction_seconds,
                    triangulation_seconds=clean.triangulation_seconds,
                    optimisation_seconds=clean.optimisation_seconds, **clean.stats)
        if bends is not None:
            info["border_bends"] = bends
        patch = Patch(vertices=clean.V[k:], faces=clean.F, info=info)
        if layouts == "smoothest":
            made.append((border_bend(ctx, patch.vertices, patch.faces), name, patch, clean.record))
            continue
        if info["predicted"] == 0 or kept >= GOOD_KEPT_SHARE:
            if reasons:
                info["attempts_failed"] = "; ".join(reasons)
            if record is not None:
                record.update(clean.record)
            return patch
        # The layout lost many prediction points: keep it, but try the others first.
        if best is None or kept > best.info["kept_share"]:
            best, best_record = patch, clean.record
        reasons.append(f"{name}: kept only {kept:.0%} of the prediction points")
    if made:
        _, _, patch, kept_record = min(made, key=lambda m: m[0] if m[0] == m[0] else np.inf)  # NaN: no border edge
        patch.info["layout_bends"] = {name: float(b) for b, name, _, _ in made}
        if reasons:
            patch.info["attempts_failed"] = "; ".join(reasons)
        if record is not None:
            record.update(kept_record)
        return patch
    if best is not None:
        best.info["attempts_failed"] = "; ".join(reasons)
        if record is not None:
            record.update(best_record)
        return best
    info = {"base_points": len(base), "segmented": False, "layout": "loop only", "pairs": 0, "predicted": 0,
            "rate": 0.0, "attempts_failed": "; ".join(reasons), "boundary_seconds": t1 - t0,
            "prediction_seconds": prediction_seconds}
    patch = loop_only_patch(ctx, base, normals, seg, mesh_normals, optimisation, info)
    if patch is not None:
        return patch
    raise HoleFillError("; ".join(reasons))


def boundary_step(ctx, critical_dihedral):
    """Step 2 (Sec. 4.2): EdgeLen, base points, their normals and the Eq. 8 segmentation.

    Parameters
    ----------
    ctx : HoleContext
    critical_dihedral : float
        A_c in degrees.

    Returns
    -------
    edge_len : float
    base : sections.BasePoints
    normals : (n, 3) float64
    seg : dict
        :func:`.sections.segment_boundary`.
    """
    edge_len = float(sections.ring_edge_length(ctx))
    if ctx.size < 3 or edge_len <= 0:
        raise HoleFillError("degenerate hole")
    base = sections.base_points(ctx.points, edge_len)
    normals = sections.base_point_normals(ctx.loop_normals, base)
    seg = sections.segment_boundary(base, normals, np.radians(critical_dihedral))
    return edge_len, base, normals, seg


def attempt_order(base, normals, seg, I_c):
    """The (segmented, layout) attempts in the order they are tried.

    The paper's choice (segmented prediction with two unfolded planes, or the unsegmented one
    with the PCA plane), then the other plane layout, then beyond the paper the loop's
    development and the disc with the same prediction, then the same layouts with the other
    prediction. Where the development gives a patch, :func:`patch_hole` makes the disc's too and
    keeps the one that bends less against the surface across the border
    (:func:`meshlab_holefill.core.border_bend.border_bend`, as curve unfolding chooses its domain).
    The development keeps a long strip a strip where the disc rounds it; the disc suits a cap
    round a knob, whose development the curvature distorts. Reading: a pairing that keeps fewer
    than half of the base points (the Eq. 9 pairs of a hole whose two PCA runs are its two long
    sides run along the boundary and are skipped by I_c) covers the hole badly; then the other
    choice goes first if it covers more.
    """
    first = bool(seg["segmented"])
    if seg["split"] is not None:
        coverage = {s: sections.pairing_coverage(base, normals, seg["split"] if s else None, I_c)
                    for s in (True, False)}
        if coverage[first] < MIN_COVERAGE and coverage[not first] > coverage[first]:
            first = not first
    choices = [first] + ([not first] if seg["split"] is not None else [])
    attempts = []
    for segmented in choices:
        plane_layouts = ["two planes", "plane"] if segmented else ["plane", "two planes"]
        if seg["split"] is None:
            plane_layouts = ["plane"]
        attempts += [(segmented, layout) for layout in plane_layouts + ["development", "disc"]]
    return attempts


def _layout_patch(hole, layout, result, name):
    """Steps 6-7 for one attempt, leaving out prediction points on folds for up to OUTLIER_ROUNDS rounds.

    ``hole`` is the :class:`_Hole`, ``result`` the prediction of steps 3-5, ``name`` the attempt's label.

    Returns
    -------
    clean : _CleanLayout or None
    reason : str or None  why the attempt failed
    """
    ctx = hole.ctx
    excluded = np.zeros(len(result[0]), bool)
    for _ in range(OUTLIER_ROUNDS):
        try:
            t3 = time.perf_counter()
            tri_stats = {}
            V, F, ids = triangulation.triangulate_layout(
                ctx, hole.base, hole.normals, hole.seg, layout, result, hole.edge_len, excluded, tri_stats,
                development=hole.development if layout == "development" else None)
            t4 = time.perf_counter()
            attempt_record = {}
            V, F, stats, bad_ids = smooth_and_optimise(V, F, ids, ctx, hole.edge_len, hole.mesh_normals,
                                                       hole.smoothing, hole.optimisation, attempt_record)
            t5 = time.perf_counter()
        except HoleFillError as exc:
            return None, f"{name}: {exc}"
        crossing = stats.pop("crossing", None)  # known when the quality pass changed the patch
        if stats["folds_left"] == 0 and (folds.intersects_surroundings(ctx, V, F) if crossing is None
                                         else crossing):
            return None, f"{name}: patch crosses the surrounding mesh"
        if stats["folds_left"] == 0:
            return _CleanLayout(V, F, stats, tri_stats.get("edge_cleared", 0), int(excluded.sum()), attempt_record,
                                t4 - t3, t5 - t4), None
        if len(bad_ids) == 0:
            return None, f"{name}: fold-over after smoothing and mesh optimisation"
        excluded[bad_ids] = True
    return None, f"{name}: fold-over after smoothing and mesh optimisation ({OUTLIER_ROUNDS} rounds)"


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


def loop_only_patch(ctx, base, normals, seg, mesh_normals, optimisation, info):
    """Last resort (beyond the paper): the loop alone, triangulated by Liepa's weights or flat in the PCA plane.

    Loops longer than ``folds.LOOP_TRIANGULATION_SIZE`` take the compiled least-bend triangulations
    (:func:`meshlab_holefill.core.least_bend.least_bend_triangulations`, the same weights) after the plane.

    Teeth of a crumpled scan border force sharp creases there, so up to LAST_RESORT_ANGLE is
    accepted (a triangle flipped onto its neighbour is at 180 degrees). The first candidate
    that duplicates no mesh edge, has no sharper fold and does not cross the rings is relaxed
    (``relax``: its splits give it interior vertices) and raised by the quality pass with
    splits (``quality_floor``), each kept only if clean.

    Returns
    -------
    Patch or None
        With ``info`` (updated with the quality pass's counts); None when no candidate is clean.
    """
    k = ctx.size
    P = ctx.points
    candidates = [folds.loop_triangulation(P, mesh_normals, ctx.forbidden_edges,
                                           max_size=folds.LOOP_TRIANGULATION_SIZE,
                                           blocked=folds.crossing_triangles(ctx, folds.LOOP_TRIANGULATION_SIZE))[0]]
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
            V, F = _raise_loop_only_quality(ctx, V, F, mesh_normals, info)
        return Patch(vertices=V[k:], faces=F, info=info)
    return None


def _relax_loop_only(ctx, P, F, mesh_normals, relax):
    """Obtuse-edge splits and tangential relaxation of a loop-only patch; ``(P, F)`` back if not clean."""
    k = ctx.size
    Vr, Fr = P, F
    for _ in range(RELAX_ROUNDS):
        Vr, Fr, s_ = optimisation_steps.split_obtuse_edges(Vr, Fr, k)
        Vr = tangential_umbrella_smoothing(Vr, Fr, np.arange(len(Vr)) < k, relax)
        if s_ == 0:
            break
    if not folds.local_folds(Vr, Fr, mesh_normals, max_angle=LAST_RESORT_ANGLE).any() and \
            not folds.intersects_surroundings(ctx, Vr, Fr):
        return Vr, Fr
    return P, F


def _raise_loop_only_quality(ctx, V, F, mesh_normals, info):
    """The guarded quality pass with splits (a loop-only patch has no free vertex to move).

    Swaps may not create loop triangles that cross the rings. Each floor of
    LAST_RESORT_FLOORS is kept only if it raises the minimum quality without crossing.
    """
    k = ctx.size

    def fold_count(V_, F_):
        return int(folds.local_folds(V_, F_, mesh_normals, max_angle=LAST_RESORT_ANGLE).sum())

    blocked = folds.crossing_triangles(ctx)
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
