"""HPDE Algorithm 2, steps 2-7 in the paper's order, with the attempts and fallbacks the filter adds.

Xie and Zou 2013. :func:`patch_hole` runs, for one hole:

* step 2 (Sec. 4.2, :mod:`.sections`): EdgeLen, the base points, their normals and the Eq. 8
  segmentation (:func:`boundary_step`);
* steps 3-5 (Sec. 4.3-4.5, :func:`.prediction.predict_points`): correspondences, section
  planes and the DE prediction of the points, once per prediction (segmented or not);
* step 6 (Sec. 4.6, :func:`.triangulation.triangulate_layout`): the constrained triangulation
  of one layout, fold-overs detected (:mod:`.folds`);
* step 7 (Sec. 4.7, :func:`._smooth_and_optimise.smooth_and_optimise`): smoothing
  (:mod:`.smoothing`), decimation and min-angle swaps (:mod:`.optimisation`), then beyond the
  paper the ``relax`` rounds and the guarded quality pass (:mod:`.quality_pass`);

trying the layouts in :func:`attempt_order` until one is clean, and the loop-only
triangulation (:func:`._loop_only_patch.loop_only_patch`) as the last resort and as the rival
of a fallback layout's patch (:func:`_bends_more_than_loop_only`). The readings behind each choice
are in the module docstring of :mod:`.differential_evolution`.
"""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field

import numpy as np

from ...core.border_bend import border_bend
from ...core.patch import Patch, validate_patch
from ...errors import HoleFillError
from . import folds
from . import prediction as prediction_steps
from . import sections
from . import smoothing as smoothing_steps
from . import triangulation
from ._loop_only_patch import faired_where_less_bent, loop_only_patch
from ._smooth_and_optimise import smooth_and_optimise

__all__ = ["PredictionOptions", "SmoothingOptions", "OptimisationOptions", "patch_hole", "boundary_step",
           "attempt_order"]

# Rounds of leaving out prediction points on faces that stay folded (beyond the paper). Over the
# layout attempts of the benchmark's cases, of scripts/unseen_holes.py (seeds 1-6), large_holes.py,
# strip_holes.py and noisy_holes.py, no attempt was clean after a third or fourth round and one
# (a 308-edge hole of large_holes.py) after the second: more rounds only prolong failing attempts.
OUTLIER_ROUNDS = 2
MIN_COVERAGE = 0.5  # a pairing keeping fewer base points than this share yields to the other choice
GOOD_KEPT_SHARE = 0.5  # a layout keeping fewer prediction points is used only if no other keeps more


@dataclass(frozen=True)
class PredictionOptions:
    """Steps 2-5: the segmentation and correspondence angles (degrees) and the DE settings."""

    critical_dihedral: float = 90.0
    critical_intersection: float = 12.0
    population_factor: float = 3.0
    mutation: float = 0.8
    crossover: float = 0.05
    generations: int = prediction_steps.NUM_ITER
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
    # With ``ctx.crossings_allowed``: the first attempt whose patch was refused only for crossing
    # the surroundings, as (attempt's name, _CleanLayout), the hole's patch if nothing else is.
    crossing: list = field(default_factory=list)

    @functools.cached_property
    def development(self):
        """The 'development' layout's polygon, or None (:func:`.triangulation.loop_development`), found once."""
        return triangulation.loop_development(self.ctx, self.edge_len)


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

    def loop_only(failed, fair=True):
        """The loop-only patch (None where it is not clean), its info naming the attempts ``failed``."""
        info = {"base_points": len(base), "segmented": False, "layout": "loop only", "pairs": 0, "predicted": 0,
                "rate": 0.0, "attempts_failed": "; ".join(failed), "boundary_seconds": t1 - t0,
                "prediction_seconds": prediction_seconds}
        return loop_only_patch(ctx, base, normals, seg, mesh_normals, optimisation, info, fair=fair)

    for position, (segmented, layout) in enumerate(attempts):
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
            clean, layout, bends = _less_bent_of_development(ctx, clean, discs[segmented][0])
        info = _attempt_info(ctx, result, base, seg, segmented, layout, clean, bends,
                             boundary_seconds=t1 - t0, prediction_seconds=prediction_seconds)
        kept = info["kept_share"]
        patch = Patch(vertices=clean.V[k:], faces=clean.F, info=info)
        if layouts == "smoothest":
            made.append((border_bend(ctx, patch.vertices, patch.faces), name, patch, clean.record))
            continue
        if info["predicted"] == 0 or kept >= GOOD_KEPT_SHARE:
            if position > 0:  # the paper's own attempt failed: this is a fallback layout's patch
                kept_name = f"{name.rsplit(', ', 1)[0]}, {layout}"  # the disc, where it beat the development
                guard = _bends_more_than_loop_only(ctx, patch, kept_name, reasons,
                                                   lambda failed: loop_only(failed, fair=False))
                if guard is not None:  # compared as the loop's own triangulation, then faired where that bends less
                    return faired_where_less_bent(ctx, guard, mesh_normals, optimisation)
            return _returned(patch, clean.record, reasons, record)
        # The layout lost many prediction points: keep it, but try the others first.
        if best is None or kept > best.info["kept_share"]:
            best, best_record = patch, clean.record
        reasons.append(f"{name}: kept only {kept:.0%} of the prediction points")
    if made:
        _, _, patch, kept_record = min(made, key=lambda m: m[0] if m[0] == m[0] else np.inf)  # NaN: no border edge
        patch.info["layout_bends"] = {name: float(b) for b, name, _, _ in made}
        return _returned(patch, kept_record, reasons, record)
    if best is not None:
        return _returned(best, best_record, reasons, record)
    patch = loop_only(reasons)
    if patch is not None:
        return patch
    if hole.crossing:  # crossings allowed: the first attempt refused only for crossing
        name, clean = hole.crossing[0]
        segmented, layout = name.startswith("segmented"), name.rsplit(", ", 1)[1]
        info = _attempt_info(ctx, predictions[segmented], base, seg, segmented, layout, clean, None,
                             boundary_seconds=t1 - t0, prediction_seconds=prediction_seconds)
        info["crossing_surroundings"] = True
        return _returned(Patch(vertices=clean.V[k:], faces=clean.F, info=info), clean.record, reasons, record)
    raise HoleFillError("; ".join(reasons))


def _bends_more_than_loop_only(ctx, patch, name, reasons, loop_only):
    """The loop-only patch where it bends less against the surface than the fallback layout's ``patch``, else None.

    Beyond the paper. A fallback layout (the development, the disc, the other plane layout or
    prediction) runs where the paper's own layout failed, which is where the predictions stray
    most: a bump that no arc of Sec. 4.5 follows, a noisy border, a loop wrapped round a part.
    The loop's own least-bend triangulation (the last resort, :func:`._loop_only_patch.loop_only_patch`)
    is made too and kept where its :func:`meshlab_holefill.core.border_bend.border_bend` is
    smaller, the criterion that already chooses between the development and the disc. Only after
    a failed paper layout: against every first clean patch the coarse loop-only patch won on small
    holes by its coarseness alone (docs/notes/xie_zou2013_hpde.md, tried and not kept). ``name``
    is the attempt's label, ``reasons`` the attempts that failed before it (the loop-only patch's
    report names them and this one); ``loop_only(reasons)`` makes the loop-only patch or None.
    """
    failed = reasons + [f"{name}: bends more against the surface than the loop-only patch"]
    alternative = loop_only(failed)
    if alternative is None:
        return None
    if not border_bend(ctx, alternative.vertices, alternative.faces) < border_bend(ctx, patch.vertices, patch.faces):
        return None
    return alternative


def _less_bent_of_development(ctx, development, disc):
    """The development's patch or the disc's (None: no clean disc), whichever bends less against the surface.

    Returns (the kept layout's patch, its name, the two bends or None); a tie keeps the development.
    """
    if disc is None:
        return development, "development", None
    k = ctx.size
    bends = {"development": border_bend(ctx, development.V[k:], development.F),
             "disc": border_bend(ctx, disc.V[k:], disc.F)}
    if bends["disc"] < bends["development"]:
        return disc, "disc", bends
    return development, "development", bends


def _attempt_info(ctx, result, base, seg, segmented, layout, clean, bends, boundary_seconds, prediction_seconds):
    """The report of one attempt's patch: the prediction's counts, the layout's, and the seconds so far."""
    k = ctx.size
    info = dict(result[3])
    # Points left out next to long loop edges (triangulation.EDGE_CLEARANCE) are not lost by the layout.
    kept = (clean.stats["kept"] + clean.edge_cleared) / max(info["predicted"], 1)
    info.update(base_points=len(base), segmented=bool(segmented), layout=layout,
                dihedral_deg=None if seg["dihedral"] is None else float(np.degrees(seg["dihedral"])),
                outliers=clean.outliers, rate=float((len(clean.V) - k) / max(info["predicted"], 1)),
                kept_share=float(kept), boundary_seconds=boundary_seconds, prediction_seconds=prediction_seconds,
                triangulation_seconds=clean.triangulation_seconds,
                optimisation_seconds=clean.optimisation_seconds, **clean.stats)
    if bends is not None:
        info["border_bends"] = bends
    return info


def _returned(patch, patch_record, reasons, record):
    """``patch``, with the attempts that failed before it named and ``record`` given its smoothed points."""
    if reasons:
        patch.info["attempts_failed"] = "; ".join(reasons)
    if record is not None:
        record.update(patch_record)
    return patch


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
    with the PCA plane), then beyond the paper the loop's development and the disc with the same
    prediction, then the other plane layout, then the same layouts with the other prediction
    (its plane layouts first). Reading: after the paper's choice, the other plane layout contradicts
    the A_c test just made (two planes across a boundary it found planar, or one plane across
    a crease), where the development and the disc follow the loop. Tried before them, it made
    the patches of 10 of the 354 unseen holes of ``scripts/unseen_holes.py`` (seeds 1-6), 6 of
    which were further from the removed surface than now (a drilled box's 76-edge hole 36.14
    against 15.96 per mille; the worst loss, an interpenetrating part's 100-edge hole, 4.59
    against 5.26). Where the development gives a patch, :func:`patch_hole` makes the disc's too and
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
        def coverage(segmented):
            return sections.pairing_coverage(base, normals, seg["split"] if segmented else None, I_c)

        # The other pairing is found only when the first covers too little (most holes never need it).
        covered = coverage(first)
        if covered < MIN_COVERAGE and coverage(not first) > covered:
            first = not first
    choices = [first] + ([not first] if seg["split"] is not None else [])
    attempts = []
    for segmented in choices:
        plane_layouts = ["two planes", "plane"] if segmented else ["plane", "two planes"]
        if seg["split"] is None:
            plane_layouts = ["plane"]
        layouts = plane_layouts[:1] + ["development", "disc"] + plane_layouts[1:] if not attempts else \
            plane_layouts + ["development", "disc"]
        attempts += [(segmented, layout) for layout in layouts]
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
        if stats["folds_left"] == 0:
            crosses = folds.intersects_surroundings(ctx, V, F) if crossing is None else crossing
            # A crossing patch is refused; with crossings allowed, the first valid one is kept for last.
            kept_for_last = crosses and ctx.crossings_allowed and not hole.crossing
            if crosses and not kept_for_last:
                return None, f"{name}: patch crosses the surrounding mesh"
            try:
                validate_patch(Patch(vertices=V[ctx.size:], faces=F), ctx.points, ctx.forbidden_edges)
            except HoleFillError as exc:  # not a disc closing the loop once: the next attempt may be
                return None, f"{name}: patch crosses the surrounding mesh" if crosses else f"{name}: {exc}"
            clean = _CleanLayout(V, F, stats, tri_stats.get("edge_cleared", 0), int(excluded.sum()), attempt_record,
                                 t4 - t3, t5 - t4)
            if crosses:
                hole.crossing.append((name, clean))
                return None, f"{name}: patch crosses the surrounding mesh"
            return clean, None
        if len(bad_ids) == 0:
            return None, f"{name}: fold-over after smoothing and mesh optimisation"
        excluded[bad_ids] = True
    return None, f"{name}: fold-over after smoothing and mesh optimisation ({OUTLIER_ROUNDS} rounds)"
