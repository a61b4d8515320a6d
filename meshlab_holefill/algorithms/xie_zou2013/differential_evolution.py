"""Hole patching by point correspondences, differential evolution and constrained triangulation (HPDE).

Xie and Zou, "A triangulation-based hole patching method using differential evolution",
Computer-Aided Design 45 (2013), Algorithm 2, steps 2-7: base points at equal arc length on
the boundary are split in two by PCA when the boundary folds (Sec. 4.2), paired across the
hole (Sec. 4.3); through each pair a section plane cuts the ring of border triangles
(Sec. 4.4); on it, points between two circular arcs given by the end tangents are predicted
with equal spacing and, by DE/rand/1/bin, equal turning angles (Sec. 4.5); the projected
boundary and predicted points are triangulated with the boundary kept (Sec. 4.6), then
smoothed, decimated and edge-swapped (Sec. 4.7). Step 1 (smoothing noisy input) is not used.

Readings of passages the paper leaves open (each documented at the function that makes it):

* Sec. 4.2. EdgeLen = mean edge length of the triangles touching the loop (the ring of Fig.
  4). Eq. 8: each PCA run holds at least max(4, ceil(n / 6)) base points; the dihedral angle
  is pi minus the angle between the surface-oriented plane normals, and "smaller than A_c"
  has a 0.1 degree slack (the cube of Fig. 15(b) meets at exactly pi/2 and is segmented, and so
  is a right-angled edge of a remeshed, decimated part, whose fitted planes meet at
  90.007-90.021 degrees; `scripts/unseen_holes.py --groups cad`: 6 of 33 holes change, their
  mean 5.99 -> 1.80 per mille, the group's 11.67 -> 10.91).
* Sec. 4.3. The boundary direction at a base point (Q_t Q_{t+1}, Fig. 2) is that of the base
  points two either side, and the intersection angle is measured towards the hole, so a
  linking line leaving the hole fails I_c too; the failing end of a pair is skipped alone,
  both ends when both fail. Eq. 10 tries every start and minimises over the starts whose
  pairs mostly (>= 1/2) pass I_c; a pairing (Eq. 9 or 10) keeping fewer than half of the
  base points yields to the other choice when that one keeps more.
* Sec. 4.4. Eq. 11 uses one-sided differences at the ends of the chain and the surface
  normal where the chord sheet's normal leans more than 45 degrees from it. AP is where the
  section plane leaves the border triangle of the base point; TV = BP - AP.
* Sec. 4.5. Arcs are at most half circles; a pair whose end tangents point away from each
  other is dropped. Eq. 14 minimises the sum of squared deviations of the m + 2 turning
  angles along AP_i, P_1, PP_1..PP_m, P_2, AP_{n-i+1} from their mean; the population is
  the Eq. 16 vector plus copies perturbed by up to 1/4 of the bound width; NumIter
  (``generations``) = 20, a small constant as Sec. 4.8 asks (measured against 5-100 in
  :func:`.prediction.predict_y`); Algorithm 1 is followed literally (selection on the raw
  trial, then reflection, then the objective renewed).
* Sec. 4.5 arcs: the start angle is that of TV = BP - AP, the paper's words (option
  ``arc_tangent='circle'``: the tangent of the circle through AP, BP and the other base
  point, exact on a sphere; sphere experiment MPE 2.85e-2 -> 2.10e-2, but worse on the
  scanned benchmark meshes, whose short AP segments make it noisy).
* Sec. 4.6. The fitting plane's normal is the principal axis nearest the mean surface normal
  when the smallest-spread axis is more than 60 degrees from it (narrow bent holes).
  Prediction points outside the projected boundary polygon or within 0.25 EdgeLen
  of it are left out; beyond the paper, also a point that the triangulation makes the apex
  of a triangle on a loop edge of length L > 2 EdgeLen while within 0.35 L of that edge
  (``triangulation.EDGE_CLEARANCE``, ``LONG_EDGE``; the rest is then triangulated again): range-scan
  borders have loop edges of 2-4 EdgeLen, and such an apex makes a sliver (angle ~145
  degrees, 2r/R 0.1-0.25) that the decimation and the swaps of Sec. 4.7 cannot remove (with
  the pass of ``quality_floor``, face000.ply natural holes 3, 13, 23: min quality 0.098 /
  0.240 / 0.148 -> 0.51 / 0.59 / 0.55). Points left out this way do not count as lost by
  the layout (the kept share that ranks layouts).
  Layouts are tried until one gives a patch without fold-over and not
  crossing the surrounding rings: the paper's choice, then (beyond the paper) the loop's
  development or a disc, the other plane layout, then the same with the other prediction
  (segmented / not). Fold-overs:
  a face turned against its projection plane after the mapping back, or two neighbouring
  faces (or a face and the mesh face across a loop edge) bent by more than 150 degrees;
  swaps and local relaxation repair what they can, prediction points left on folds are
  dropped for up to 2 rounds. A loop-only triangulation with Liepa's weights is the last
  resort; where it is the result, it is refined and faired as Liepa's fill is where that bends
  less against the surface, else refined alone where that is clean
  (``_loop_only_patch.faired_where_less_bent``; docs/notes/xie_zou2013_hpde.md: seeds 1-3 of the
  unseen groups 3.910 -> 3.854 per mille, 5 holes changed). Where the paper's layout failed and
  a fallback layout gave the patch, the loop-only patch is made too and kept if it bends less
  against the surface across the border
  (``core.border_bend``; ``_algorithm2._bends_more_than_loop_only``): the fallbacks run where
  the predictions stray (noisy borders, strips, loops round a part). Measured, before -> after,
  mean patch->GT per mille: ``scripts/unseen_holes.py`` groups through
  ``evaluation.comparison.run_comparison``, noisy cow seeds 1-8 2.297 -> 2.096 (28 holes,
  3 changed, none worse), closed shapes seeds 1-6 1.225 -> 1.211 (5 better, 3 worse), CAD
  tessellations seeds 1-6 12.401 -> 12.220, real-size seeds 1-6 1.999 -> 1.918, range scans
  seeds 1-2 0.063 -> 0.059, creased parts unchanged (4.653); ``scripts/strip_holes.py``
  0.729 -> 0.348; ``scripts/large_holes.py`` 3.714 -> 3.762; the benchmark suite and
  ``scripts/cad_tessellation_holes.py`` unchanged; 5-30 % more time on those groups. Made after
  every first clean patch instead, the coarse loop-only patch won on small holes by its
  coarseness alone (docs/notes/xie_zou2013_hpde.md, tried and not kept). A chord duplicating a mesh
  edge is split at its midpoint.
* Sec. 4.7. NumSmooth = 60 passes of Taubin's non-shrinking lambda|mu filter (ref. [26]: the
  paper names no operator for step 7, and Taubin's filter does not shrink the patch) on the new vertices, loop fixed,
  lambda = 0.33 (Taubin's example) and mu from the pass band k_PB = 1/lambda + 1/mu set to
  the patch's lowest Dirichlet frequency k_1 (``taubin_pass_band=0``), so the smoothest
  shape of the patch passes with gain 1 and no mode is amplified. Taubin's closed-surface
  value (mu = -0.34, k_PB ~ 0.09) lies below k_1 = 0.1-0.4 of a patch a few edges across
  and damps every mode; per mille of the diagonal on the benchmark's small / medium / large
  holes: k_PB = 0.09 0.308 / 1.796 / 1.647, k_PB = k_1 0.277 / 1.804 / 1.595, MeshLab 0.296 /
  5.85 / 21.4 (2026-12-01). Option ``smoothing='curvature'``: the second-order umbrella
  (Kobbelt 1998) on the patch glued to its surrounding rings, whose fixed points have the
  uniform turning angles of Sec. 5.2.2, anchored to the predictions (``smoothing_anchor``
  0.15; free passes converge on narrow holes to the thin-plate fill of the loop): closer to
  the removed surface (0.200 / 1.682 / 1.591), but a fit to the predictions over the patch and its
  rings rather than the smoothing filter of the patch that step 7 describes. Edges
  shorter than ``decimation_rate`` (0.6) * EdgeLen collapse to their midpoint, onto the loop
  vertex when one end is on the loop; min-angle swaps keep each new triangle within 60
  degrees of the old pair's normal. ``relax`` (beyond the paper, on by
  default for the quality target): obtuse-edge splits, collapse of slivers on the loop and
  tangential relaxation, then moves of the free vertices of triangles below quality 0.5
  (improve_worst_vertices), taken back if it folds. ``quality_floor`` (beyond the paper, 0.4 by
  default): the final guarded pass of quality_pass on the triangles below the floor, the
  paper's swaps and collapses plus vertex moves, each kept only if it raises the smallest
  quality of the triangles it changes, keeps them unfolded, and the patch does not cross the
  rings (benchmark, with the clearance above: the 14 natural / large holes below 0.3 and
  above their corner bound go to min 0.37-0.59; natural holes' mean quality 0.867 -> 0.884;
  patch->GT distance per size class unchanged but medium 1.66 -> 1.70 per mille, from cow
  hole 1, whose two sliver apexes on a 3-EdgeLen loop edge are left out).
  On the loop-only last resort the pass also splits edges (floors 0.4, then 0.6), and its
  swaps may not create loop triangles crossing the rings (bunny10k hole 1: min 0.084 ->
  0.54, mean 0.41 -> 0.68).
"""
from __future__ import annotations

import numpy as np

from ...core.parameters import ParamSpec
from ._algorithm2 import OptimisationOptions, PredictionOptions, SmoothingOptions, patch_hole
from .prediction import NUM_ITER
from .quality_pass import raise_min_quality

__all__ = ["fill", "PARAMS", "RINGS", "WARM_UP", "warm_up"]

RINGS = 2

PARAMS = [
    ParamSpec("population_factor", "float", 3.0,
              "DE population size per section plane N = factor * m (Sec. 4.8: N = 3 m).", minimum=1.0, maximum=50.0),
    ParamSpec("mutation", "float", 0.8, "DE mutation factor F of Eq. 2 (Sec. 4.8: 0.8).", minimum=0.0, maximum=2.0),
    ParamSpec("crossover", "float", 0.05, "DE crossover probability CR of Eq. 3 (Sec. 4.8: 0.05).",
              minimum=0.0, maximum=1.0),
    ParamSpec("generations", "int", NUM_ITER,
              "DE generations (NumIter of Sec. 4.8, which the paper calls a small constant without a value).",
              minimum=0, maximum=100000),
    ParamSpec("critical_dihedral", "float", 90.0,
              "A_c in degrees: the boundary is split in two planes when their dihedral angle is below it, "
              "or above it by at most 0.1 degree (fitted planes of a tessellated right-angled edge) "
              "(Sec. 4.2; pi/2 in the paper).", minimum=0.0, maximum=180.0),
    ParamSpec("critical_intersection", "float", 12.0,
              "I_c in degrees: base points whose linking line meets the boundary at a smaller angle are "
              "skipped (Sec. 4.3; pi/15 in the paper).", minimum=0.0, maximum=90.0),
    ParamSpec("num_smooth", "int", 60, "NumSmooth: smoothing passes of the patch (Sec. 4.7; 60).",
              minimum=0, maximum=10000),
    ParamSpec("smoothing", "enum", "taubin",
              "Smoothing operator of Sec. 4.7: 'taubin' = Taubin's non-shrinking lambda|mu filter (ref. [26]) on "
              "the new vertices, loop fixed, its pass band at the patch's lowest frequency (taubin_pass_band); "
              "'curvature' = second-order umbrella with the surrounding rings anchored to the prediction "
              "(smoothing_anchor), whose fixed points have uniform turning angles (Sec. 5.2.2); "
              "'curvature_scaled' = the same with scale-dependent weights.",
              choices=("curvature", "curvature_scaled", "taubin")),  # order kept: .mlx enums are indices
    ParamSpec("taubin_lambda", "float", 0.33,
              "lambda of the Taubin filter (the Gaussian step of each pass; Taubin's example 0.33).",
              minimum=0.01, maximum=0.9),
    ParamSpec("taubin_pass_band", "float", 0.0,
              "Pass-band frequency k_PB = 1/lambda + 1/mu of the Taubin filter (lambda 0.33); 0 = the patch's "
              "lowest Dirichlet frequency, so the smoothest shape of the patch passes unchanged (Taubin's "
              "closed-surface value 0.1 flattens small patches). At most 1, so it stays below 1/lambda "
              "(a patch's lowest frequency is at most 1 too).", minimum=0.0, maximum=1.0),
    ParamSpec("smoothing_anchor", "float", 0.15,
              "smoothing=curvature: weight w of the predicted positions in the smoothing of Sec. 4.7 (reading: "
              "the smoothing filters the prediction, it does not replace it): each pass solves towards "
              "(U^2 + w) x = w x_pred, which removes wavelengths below ~2 pi / (2 w^(1/4)) ~ 5 edges (the "
              "section-plane jitter) and keeps the DE shape; 0 = free smoothing, which converges to the "
              "thin-plate fill of the loop on narrow holes.",
              minimum=0.0, maximum=100.0),
    ParamSpec("arc_tangent", "enum", "secant",
              "Start angle of the arcs of Sec. 4.5: 'secant' = the direction TV = BP - AP as the tangent at BP "
              "(the paper's words); 'circle' = the tangent at BP of the circle through AP, BP and the other base "
              "point (exact on a sphere; the secant overshoots by half the angle the ring edge subtends).",
              choices=("secant", "circle")),
    ParamSpec("decimation_rate", "float", 0.6,
              "Edges shorter than this times EdgeLen are collapsed to their midpoints (Sec. 4.7-4.8; the "
              "paper gives no value).", minimum=0.0, maximum=2.0),
    ParamSpec("seed", "int", 0, "Random seed of the differential evolution.", minimum=0, maximum=2**31 - 1),
    ParamSpec("quality_floor", "float", 0.4,
              "Beyond the paper: triangles of 2r/R below this floor are improved at the end of Sec. 4.7 by "
              "guarded edge swaps, vertex moves in the tangent plane and edge collapses, each kept only if it "
              "raises the smallest quality of the triangles it changes without folding them; "
              "0 = off.", minimum=0.0, maximum=1.0),
    ParamSpec("relax", "int", 10,
              "Beyond the paper: passes of tangential relaxation (then min-angle swaps) after the mesh "
              "optimisation, evening out the triangles without changing the shape; on by default for triangle "
              "quality; 0 = the paper.",
              minimum=0, maximum=1000),
    ParamSpec("layouts", "enum", "first",
              "Which attempt's patch is kept: 'first' (the paper's choice, the other layouts only where it "
              "fails) or 'smoothest' (beyond the paper: every prediction and layout is tried and the patch that "
              "bends least against the surrounding surface across the hole's border is kept; about four times "
              "the time).", choices=("first", "smoothest")),
]

_WARM = []  # set once the kernels are loaded in this process


def warm_up():
    """Load (or compile) the filter's numba kernels now, by filling a small hole.

    The kernels are compiled on first use and cached on disk; loading them takes a few tenths
    of a second per process (0.3-0.4 s of the first hole's time otherwise). The pipeline calls
    this (``WARM_UP``) before filling holes, so that forked workers inherit the loaded kernels.
    """
    if _WARM:
        return
    from ...core import examples
    from ...core.holes import hole_context
    from ...geometry.segments import is_simple_polygon
    from ...geometry.topology import interior_edges

    V, F, loop = examples.bowl_with_hole()
    fill(hole_context(V, F, loop, rings=RINGS), seed=1)
    # The bowl's patch needs no quality pass: one on a square with an off-centre vertex, whose move
    # a fold test refuses, so the round runs again face by face and the move is taken back.
    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.9, 0.12, 0.0]])
    raise_min_quality(square, np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]), 4,
                      fold_test=lambda V, F: int(V[4, 0] != 0.9))
    is_simple_polygon(square[:4, :2], 1e-9)  # the development layout's simplicity test
    # The edge table as Python code reads it: the fold test's compiled call to it, loaded from the cache,
    # does not load it for the calls from Python.
    interior_edges(np.array([[0, 1, 4], [1, 2, 4]]), 5)
    _WARM.append(True)


def fill(ctx, population_factor=3.0, mutation=0.8, crossover=0.05, generations=NUM_ITER, critical_dihedral=90.0,
         critical_intersection=12.0, num_smooth=60, decimation_rate=0.6, seed=0, relax=10, smoothing="taubin",
         record=None, smoothing_anchor=0.15, arc_tangent="secant", quality_floor=0.4, taubin_pass_band=0.0,
         taubin_lambda=0.33, layouts="first"):
    """Fill one hole by HPDE, Algorithm 2 steps 2-7.

    Attempts (first clean one wins): the paper's choice (segmented prediction with two
    unfolded planes, or unsegmented with the PCA plane), the loop's development and the disc,
    and the other plane layout with the same prediction, then the layouts with the other
    prediction (:func:`._algorithm2.attempt_order`). An attempt is clean when no fold-over is
    left after smoothing, optimisation and repairs, its patch is a disc closing the loop once
    (:func:`meshlab_holefill.core.patch.validate_patch`) and it does not cross the surrounding
    rings; one that kept under half of the prediction points is used only if no other keeps
    more. The loop-only triangulation is the last resort, and replaces a fallback layout's patch
    that bends more against the surface across the border. The steps run in
    :func:`._algorithm2.patch_hole`; the keywords are grouped there into
    :class:`PredictionOptions` (steps 2-5), :class:`SmoothingOptions` and
    :class:`OptimisationOptions` (step 7).

    Parameters
    ----------
    ctx : HoleContext
        The hole and ``RINGS`` rings of faces around it (:func:`meshlab_holefill.core.holes.hole_context`).
    population_factor, mutation, crossover, generations, seed : float, float, float, int, int
        Differential evolution of Sec. 4.5 and 4.8 (N = factor * m, F, CR, NumIter, random seed).
    critical_dihedral, critical_intersection : float
        A_c (Sec. 4.2) and I_c (Sec. 4.3), in degrees.
    num_smooth, smoothing, smoothing_anchor, taubin_pass_band, taubin_lambda : int, str, float, float, float
        NumSmooth and the smoothing operator of Sec. 4.7 with its settings.
    decimation_rate : float
        Edges shorter than this times EdgeLen collapse (Sec. 4.7).
    relax, quality_floor : int, float
        Beyond the paper: tangential relaxation passes and the floor of the final quality pass.
    arc_tangent : {'secant', 'circle'}
        Start angle of the arcs of Sec. 4.5.
    layouts : {'first', 'smoothest'}
        'first' keeps the first clean attempt (above); 'smoothest' (beyond the paper) makes every
        attempt and keeps the patch with the smallest
        :func:`meshlab_holefill.core.border_bend.border_bend`.
    record : dict, optional
        Receives ``smoothed_points`` ((s, 3) float64, the SP_i of Sec. 4.7 of the returned
        patch; empty for the loop-only last resort), for the errors of Eq. 17.

    Returns
    -------
    Patch
        ``vertices`` (p, 3) float64 and ``faces`` (q, 3) int64 in loop-local indices (i < k:
        loop vertex i). ``info``: ``base_points`` (n), ``segmented`` (prediction), ``layout``,
        ``dihedral_deg``, ``pairs``, ``skipped_base_points``, ``M``, ``predicted``, ``kept``
        (prediction points triangulated), ``collapses``, ``rate`` (new vertices / prediction
        points, the paper's Rate), ``swaps``, ``fold_repairs``, ``outliers`` and per-step seconds.

    Raises
    ------
    HoleFillError
        A degenerate hole, or every attempt and the last resort failed (the message names
        each attempt's reason).

    References
    ----------
    W.-C. Xie and X.-F. Zou, "A triangulation-based hole patching method using differential
    evolution", Computer-Aided Design 45 (2013), Elsevier.

    Examples
    --------
    A round hole in a bowl-shaped grid, its new points predicted by differential evolution:

    >>> from meshlab_holefill.core import examples, hole_context
    >>> V, F, loop = examples.bowl_with_hole()
    >>> ctx = hole_context(V, F, loop, rings=RINGS)
    >>> patch = fill(ctx, seed=1)
    >>> examples.is_disc_patch(patch, ctx)  # closes the loop exactly once, as a disc
    True
    """
    return patch_hole(
        ctx,
        PredictionOptions(critical_dihedral=critical_dihedral, critical_intersection=critical_intersection,
                          population_factor=population_factor, mutation=mutation, crossover=crossover,
                          generations=generations, seed=seed, arc_tangent=arc_tangent),
        SmoothingOptions(operator=smoothing, passes=num_smooth, taubin_lambda=taubin_lambda,
                         taubin_pass_band=taubin_pass_band, anchor=smoothing_anchor),
        OptimisationOptions(decimation_rate=decimation_rate, relax=relax, quality_floor=quality_floor),
        record=record, layouts=layouts)


WARM_UP = warm_up
# Fill seconds per boundary edge with the defaults (the benchmark's holes, one core; the time grows
# about linearly with the edges): the estimate from which workers=0 judges whether forking pays.
SECONDS_PER_EDGE = 1.8e-3
