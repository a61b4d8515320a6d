"""Hole filling by the modified minimum-angle triangulation, density refinement and bilateral filter.

Hu, Wang, Li and Liu, "Filling Holes in Triangular Meshes in Engineering" (Sec. III): the
hole is triangulated by repeatedly cutting the boundary vertex of smallest angle whose
neighbours' normals agree (III.B), refined to the density of the surrounding mesh (III.C),
and its interior vertices are moved along their normals by the bilateral filter (III.D).

Readings where the paper leaves room (each a parameter, measured on the benchmark's cut holes):

* Relaxation (III.C, Fig. 4) is the circumcircle test of Pfeifle and Seidel, who relax in a
  plane. In space the two circumsphere tests can both pass for the worse diagonal of a
  folded quad (the triangle joining three concave vertices between spikes of a jagged
  border keeps quality 0.28); the default tests the two triangles unfolded about their
  common edge, which is the same test on a planar quad (``relaxation``).
* The filter's neighbourhood (III.D): Eq. 4 after Fleishman et al. takes every point within
  rho = 2 sigma_c, the pseudo-code "the 1-ring neighborhood of v"; nothing restricts it to
  the patch, so the ``radius`` reading includes the surrounding mesh's fixed vertices. With
  sigma_c = 0.1 of the vertex density (Sec. IV, "density" read as the mean incident edge
  length) rho holds no neighbour; on the 1-ring the Gaussian is then so narrow that the
  nearest neighbour takes all the weight. Wider kernels (sigma_c 0.5-1 edge length, the
  reading under which rho covers the 1-ring) make the filter a plain smoother, which moves a
  piecewise-flat patch further from a curved removed surface, the more so with the
  surrounding vertices included; the default stays the paper's 1-ring with sigma_c = 0.1.
* The filter step is guarded (``filter_guard``): a move that would make a sliver or flip a
  triangle is undone.

Distance to the removed surface with the paper's steps (benchmark cut holes, mean per mille of
the bounding-box diagonal, small / medium holes; MeshLab's ear fill 0.29 / 5.85): the
minimum-angle triangulation alone 0.40 / 5.27, after refinement 0.42 / 5.76 (swaps between
interior vertices of a curved patch cut its corners: bone hole 0 1.04 -> 1.65), after the
filter 0.49 / 6.09. With sigma_c = 0.1 the nearest neighbour takes the filter's whole weight,
so each vertex moves to the height of its nearest neighbour's along its normal: a smoother,
which pulls a patch over a convex hole inward (sphere hole 0, mean signed offset of the new
vertices -0.39 -> -0.54 per mille); the sign the paper prints (v + n d, away from the
neighbours) overshoots instead (bone hole 0 1.65 -> 5.6). No reading of Sec. III.B-D found
meets MeshLab's small-hole distance; the ``fairing=thinplate`` option with ``iterations=0``
does (0.28 / 2.48), and ``smoothing`` (beyond the paper) lifts the triangle quality. Measured
with the options (benchmark suite, 2026-12-01; small / medium / large distance, natural holes'
mean quality, holes whose min is below min(0.3, corner bound)): paper's steps 0.50 / 6.12 /
16.8, 0.793, 9 holes; smoothing=10: 0.47 / 6.22 / 16.8, 0.843, 1 (bunny10k_textured 1);
fairing=thinplate, iterations=0, smoothing=10: 0.28 / 2.47 / 5.66, 0.851, 0 (every target of
the benchmark met); the same with alpha=1.55: 0.22 / 2.10 / 4.71, 0.862, 0; MeshLab 0.30 /
5.87 / 21.4.
"""
from __future__ import annotations

import itertools
import time

import numpy as np

from .bilateral_filter import bilateral_filter
from .fairing import fair_patch_in_context
from ...geometry.flips import relax_edges
from ...geometry.refine import refine_patch
from ...geometry.topology import boundary_edges_and_chords
from .hole_guards import LoopSectors, patch_guard, relax_in_sectors, swaps_crossing
from ...core.content_key import content_key
from ...core.crossings import context_crossings
from ...core.least_bend import least_bend_triangulations
from ...core.patch import Patch
from ...errors import HoleFillError
from ...core.parameters import ParamSpec
from .tangential_smoothing import tangential_smoothing
from .min_angle_triangulation import hole_plane_triangulation, min_angle_triangulation
from .crossing_test import crosses

__all__ = ["fill", "FAIRED_OPTIONS", "PARAMS", "RINGS", "WARM_UP", "warm_up", "relaxation_guard"]

RINGS = 2
# The faired option set (filters/close_holes_min_angle_bilateral_faired.mlx), the fallback's patch.
FAIRED_OPTIONS = {"fairing": "thinplate", "iterations": 0, "smoothing": 10}

PARAMS = [
    ParamSpec("alpha", "float", float(np.sqrt(2.0)),
              "Density control factor of the refinement (Sec. III.C); larger gives a denser patch.",
              minimum=0.5, maximum=10.0),
    ParamSpec("sigma_c", "float", 0.1,
              "Bilateral closeness width as a fraction of the local vertex density (mean incident edge length), Sec. IV.",
              minimum=1e-3, maximum=10.0),
    ParamSpec("sigma_s", "float", 0.5,
              "Bilateral feature-preserving width as a fraction of the local vertex density, Sec. IV.",
              minimum=1e-3, maximum=10.0),
    ParamSpec("iterations", "int", 3, "Bilateral filter iterations (Sec. IV).", minimum=0, maximum=100),
    ParamSpec("fairing", "enum", "none",
              "Extra step beyond the paper, off by default: solve a membrane ('membrane') or thin-plate "
              "('thinplate') energy for the new vertices, with the surrounding rings fixed, after refinement "
              "(edges relaxed again afterwards) and before the bilateral filter. The filter is a smoother: after "
              "fairing it flattens the faired patch again, so combine fairing with iterations=0.",
              choices=("none", "membrane", "thinplate")),
    ParamSpec("smoothing", "int", 0,
              "Extra step beyond the paper, off by default: rounds of tangential smoothing of the new vertices "
              "after refinement (and fairing), before the bilateral filter. Each round collapses a new vertex "
              "stuck next to a long border edge, bisects the interior edge opposite the obtuse angle of poor "
              "triangles, moves every new vertex in its tangent plane toward the apexes of equilateral triangles "
              "on its opposite edges (a move that lowers the worst quality around it is undone) and relaxes the "
              "edges again. Best combined with fairing=thinplate and iterations=0.",
              minimum=0, maximum=100),
    ParamSpec("relaxation", "enum", "angles",
              "Edge relaxation test of the refinement (Sec. III.C, Fig. 4): 'angles' = the two triangles "
              "unfolded into one plane about their common edge (opposite angles adding up to more than pi: swap), "
              "the paper's circumcircle test of a planar quad; 'sphere' = the circumspheres in space, which on a "
              "folded quad can keep a sliver.",
              choices=("angles", "sphere")),
    ParamSpec("neighbourhood", "enum", "ring",
              "Bilateral filter neighbourhood (Sec. III.D): 'ring' = the pseudo-code's 1-ring; 'radius' = every "
              "point within rho = 2 sigma_c (Eq. 4, after Fleishman et al.), the surrounding mesh's vertices "
              "included (with sigma_c = 0.1 no point is that close: use sigma_c >= 0.5 with it).",
              choices=("ring", "radius")),
    ParamSpec("fallback", "bool", True,
              "Beyond the paper, used only where the paper's patch would be rejected: when it still crosses the "
              "mesh after the guarded refinement and fewer filter iterations, the patch of the faired option "
              "set (fairing=thinplate, iterations=0, smoothing=10) is taken instead if that one crosses nothing; "
              "where the initial triangulation itself crosses, the same steps are tried from a triangulation about "
              "the hole's own plane (first where fewer of its faces cross than of the initial one, else last); "
              "for jagged borders, the same steps (then the faired set) from the loop's least-bend "
              "triangulations; otherwise the hole is reported failed as before."),
    ParamSpec("filter_guard", "float", 0.3,
              "Guard on the bilateral step: a move that would leave a new triangle with quality 2r/R below "
              "min(filter_guard, its quality before), or flip it, is undone; 0 turns the guard off.",
              minimum=0.0, maximum=1.0),
]


_WARM = []  # set once the kernels are loaded in this process


def warm_up():
    """Load (or compile) the filter's numba kernels now, by filling a small hole with both option sets.

    The kernels are compiled on first use and cached on disk; loading them takes a few tenths
    of a second per process. The pipeline calls this (``WARM_UP``) before filling holes, so
    that forked workers inherit the loaded kernels instead of each loading them within its
    first hole's time.
    """
    if _WARM:
        return
    from ...core import examples
    from ...core.holes import hole_context

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=RINGS)
    fill(ctx)
    fill(ctx, fairing="thinplate", iterations=0, smoothing=1)
    _WARM.append(True)


WARM_UP = warm_up
# Fill seconds per boundary edge with the defaults (the benchmark's holes, one core; the time grows
# about linearly with the edges): the estimate from which workers=0 judges whether forking pays.
SECONDS_PER_EDGE = 8e-5


def relaxation_guard(ctx, sector=None):
    """Veto for relaxation swaps: the hole-sector test, with an exact second opinion.

    The sector test (:func:`hole_guards.patch_guard`) refuses a swap whose new edge leaves a
    boundary vertex outside its hole sector, measured in the tangent plane of the mesh
    normal there. Where the patch meets the surrounding surface at a large angle (a nearly
    flat patch in a strongly curved hole, up to 100 degrees on the bunny's largest cut
    hole) that projection misjudges edges that run almost along the border, and the
    refused swaps leave fans of slivers between nearly collinear boundary vertices that
    the circumsphere test of Sec. III.C would remove. A swap the sector test refuses is
    therefore allowed when its two new triangles intersect neither the surrounding faces
    nor the rest of the patch, which is what the sector test stands in for.

    Parameters
    ----------
    ctx : HoleContext
    sector : callable, optional
        ``patch_guard(ctx)``, when the caller has it already (it is built from the loop's
        hole sectors, about 0.3 ms per hole).

    Returns
    -------
    callable ``allowed(V, F, A, B, replaced) -> (s,) bool`` for :func:`geometry.flips.relax_edges`
    """
    if sector is None:
        sector = patch_guard(ctx)

    def allowed(V, F, A, B, replaced):
        ok = sector(V, F, A, B, replaced)
        idx = np.flatnonzero(~ok)
        if len(idx) == 0:
            return ok
        ok[idx] = ~swaps_crossing(ctx, V, F, A[idx], B[idx], replaced[idx])
        return ok

    return allowed


_REFINED = []  # the last few (ctx, key, refinement) of _refined


def _refined(ctx, F0, alpha, fixed, criterion):
    """:func:`_refine` of ``F0``, the same refinement handed out again (as copies) for the same triangulation.

    A fallback starts from the triangulation an earlier attempt refined (the faired option set
    from the paper's, the least-bend one with the faired set after the filter's own options);
    the refinement depends on the triangulation and these options only.
    """
    key = (content_key(np.asarray(F0), np.asarray(fixed), np.array([alpha], float)), criterion)
    for c, k, (V, F, scale, info) in _REFINED:
        if c is ctx and k == key:
            return V.copy(), F.copy(), scale.copy(), dict(info)
    V, F, scale, info = _refine(ctx, F0, alpha, fixed, criterion=criterion)
    _REFINED.insert(0, (ctx, key, (V.copy(), F.copy(), scale.copy(), dict(info))))
    del _REFINED[4:]
    return V, F, scale, info


def _refine(ctx, F0, alpha, fixed, max_passes=4, criterion="sphere"):
    """Refinement of Sec. III.C run until neither a split nor a relaxation swap is left.

    The rounds of :func:`refine_patch` use the fast sector test; the swaps it refuses are then
    reconsidered with :func:`relaxation_guard` (an exact intersection check, too slow to run
    in every round), and when any of them is made, refinement resumes from the relaxed patch,
    since the new triangles may need splitting. Both relax by :func:`.hole_guards.relax_in_sectors`.
    A refinement whose last relaxation ended with the sector test refusing nothing has no swap
    to reconsider (the patch refine_patch returns is the one it last relaxed).
    """
    sectors = LoopSectors(ctx.points, ctx.loop_normals)
    exact = relaxation_guard(ctx, patch_guard(ctx, sectors=sectors))
    settled = [False]  # of the last relaxation refine_patch ran

    def relax(V, F):
        F, swaps, settled[0] = relax_in_sectors(sectors, V, F, fixed, criterion)
        return F, swaps

    V, F, scale, info = refine_patch(ctx.points, F0, ctx.edge_scale, alpha=alpha, relax=relax)
    for _ in range(max_passes):
        if settled[0]:
            break
        F, swaps, _ = relax_in_sectors(sectors, V, F, fixed, criterion, refused=exact)
        info["swaps"] += swaps
        if swaps == 0:
            break
        V, F, scale, more = refine_patch(V, F, scale, alpha=alpha, relax=relax)
        info["split_rounds"] += more["split_rounds"]
        info["swaps"] += more["swaps"]
    return V, F, scale, info


def _optimise(ctx, V, F, interior, scale, fairing, sigma_c, sigma_s, iterations, neighbourhood="ring",
              min_quality=None, fixed=None, criterion="angles", smoothing=0):
    """Optional fairing (beyond the paper) then the bilateral filter of Sec. III.D on the new vertices.

    Fairing moves the new vertices a long way off the refined, nearly flat patch; the edges
    are then relaxed again (Sec. III.C's test, ``criterion``, with ``fixed`` edges kept), as
    the paper's refinement leaves a patch whose every interior edge passes it, unless the
    relaxed patch intersects itself or the surrounding faces and the faired one does not.
    With ``neighbourhood="radius"`` the surrounding rings of the hole (``ctx.vertices[k:]``)
    are the filter's neighbours too, fixed (Eq. 4's N(u) is every point within rho = 2 sigma_c).

    Returns
    -------
    V : (n, 3) float64, F : (m, 3) int64
    """
    V = V.copy()
    k = ctx.size
    if fairing != "none" and interior.any():
        V[k:] = fair_patch_in_context(ctx.vertices, ctx.faces, k, V[k:], F,
                                      order=1 if fairing == "membrane" else 2)
        relaxed, swaps = relax_edges(V, F, fixed, allowed=relaxation_guard(ctx), criterion=criterion)
        # The guard checks intersections only where the sector test refuses: a faired patch
        # close to the surrounding surface can be pushed through it by an allowed swap.
        if swaps and not (crosses(ctx, V, relaxed) and not crosses(ctx, V, F)):
            F = relaxed
    if smoothing > 0 and interior.any():
        Vs, Fs, ss = tangential_smoothing(V, F, interior, smoothing, fixed=fixed, allowed=relaxation_guard(ctx),
                                          criterion=criterion, attr=scale)
        if not (crosses(ctx, Vs, Fs) and not crosses(ctx, V, F)):
            V, F, scale = Vs, Fs, ss
            interior = np.arange(len(V)) >= k
    if iterations > 0 and interior.any():
        V = bilateral_filter(V, F, interior, sigma_c * scale, sigma_s * scale, iterations,
                             neighbourhood=neighbourhood, fixed_points=ctx.vertices[k:], min_quality=min_quality)
    return V, F


def fill(ctx, alpha=np.sqrt(2.0), sigma_c=0.1, sigma_s=0.5, iterations=3, fairing="none", relaxation="angles",
         neighbourhood="ring", filter_guard=0.3, smoothing=0, fallback=True):
    """Fill one hole by Hu et al.'s three steps (Sec. III.B-III.D).

    The modified minimum-angle triangulation (:func:`.min_angle_triangulation.min_angle_triangulation`),
    the Pfeifle-Seidel refinement with edge relaxation (:func:`meshlab_holefill.geometry.refine.refine_patch`),
    then the bilateral filter (:func:`.bilateral_filter.bilateral_filter`); ``fairing`` and
    ``smoothing`` are steps beyond the paper, off by default.

    Parameters
    ----------
    ctx : HoleContext
        The hole and ``RINGS`` rings of faces around it (:func:`meshlab_holefill.core.holes.hole_context`).
    alpha : float
        Density control factor of the refinement (Sec. III.C).
    sigma_c, sigma_s : float
        Bilateral closeness and feature widths, as fractions of the local vertex density.
    iterations : int
        Bilateral filter iterations (Sec. III.D).
    fairing : {'none', 'membrane', 'thinplate'}
        Beyond the paper: an energy solved for the new vertices before the filter.
    relaxation : {'angles', 'sphere'}
        Edge relaxation test of the refinement.
    neighbourhood : {'ring', 'radius'}
        Bilateral filter neighbourhood.
    filter_guard : float
        Quality below which a bilateral move is undone (0: off).
    smoothing : int
        Beyond the paper: rounds of tangential smoothing of the new vertices.
    fallback : bool
        Beyond the paper: a patch that still crosses the mesh is replaced by the
        :data:`FAIRED_OPTIONS` patch when that one crosses nothing, and, where the initial
        triangulation itself crosses the mesh or itself, by the patches grown from
        :func:`.min_angle_triangulation.hole_plane_triangulation` (paper's steps, then faired) when one of them crosses nothing;
        then by the paper's steps grown from the loop's least-bend triangulations
        (:func:`meshlab_holefill.core.least_bend.least_bend_triangulations`), for jagged borders
        whose faces tilt every way (noisy scans), then by the faired option set grown from them.
        Where the hole plane's triangulation crosses as much as the initial one, its patches come last.

    Returns
    -------
    Patch
        ``vertices`` (p, 3) float64 and ``faces`` (q, 3) int64 in loop-local indices (i < k:
        loop vertex i); ``info`` has ``initial_faces``, ``split_rounds``, ``swaps`` and
        per-step seconds.

    Raises
    ------
    HoleFillError
        When the minimum-angle triangulation cannot close the hole (fewer than 3 boundary
        vertices, no valid ear left, or a last triangle duplicating a mesh edge).

    References
    ----------
    P. Hu, C. Wang, B. Li and M. Liu, "Filling Holes in Triangular Meshes in Engineering",
    Journal of Software (JSW) 7(1), 2012.

    Examples
    --------
    A round hole in a bowl-shaped grid, triangulated, refined and smoothed by the bilateral filter:

    >>> from meshlab_holefill.core import examples, hole_context
    >>> V, F, loop = examples.bowl_with_hole()
    >>> ctx = hole_context(V, F, loop, rings=RINGS)
    >>> patch = fill(ctx, iterations=3)
    >>> examples.is_disc_patch(patch, ctx)  # closes the loop exactly once, as a disc
    True
    """
    return _patch_from(ctx, None, alpha=alpha, sigma_c=sigma_c, sigma_s=sigma_s, iterations=iterations, fairing=fairing,
                       relaxation=relaxation, neighbourhood=neighbourhood, filter_guard=filter_guard,
                       smoothing=smoothing, fallback=fallback)


def _patch_from(ctx, initial, alpha, sigma_c, sigma_s, iterations, fairing, relaxation, neighbourhood, filter_guard,
                smoothing, fallback):
    """:func:`fill`'s steps from the initial triangulation ``initial`` ((k - 2, 3) int; None: Sec. III.B's)."""
    k = ctx.size
    t0 = time.perf_counter()
    F0 = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges) if initial is None else initial
    t1 = time.perf_counter()
    fixed = boundary_edges_and_chords(k, ctx.forbidden_edges)
    V, F, scale, info = _refined(ctx, F0, alpha, fixed, relaxation)
    t2 = time.perf_counter()

    def optimise(V, F, scale, n_iter):
        interior = np.arange(len(V)) >= k
        return _optimise(ctx, V, F, interior, scale, fairing, sigma_c, sigma_s, n_iter, neighbourhood=neighbourhood,
                         min_quality=filter_guard if filter_guard > 0 else None, fixed=fixed, criterion=relaxation,
                         smoothing=smoothing)

    V, F = _optimised_clear_of_mesh(ctx, F0, V, F, scale, info, optimise, alpha, fixed, relaxation, iterations)
    t3 = time.perf_counter()
    info.update(initial_faces=len(F0), triangulation_seconds=t1 - t0, refinement_seconds=t2 - t1,
                filter_seconds=t3 - t2, fallback=None)
    if not fallback or not crosses(ctx, V, F):
        return Patch(vertices=V[k:], faces=F, info=info)
    same = dict(alpha=alpha, sigma_c=sigma_c, sigma_s=sigma_s, relaxation=relaxation, neighbourhood=neighbourhood,
                filter_guard=filter_guard, fallback=False)
    options = dict(fairing=fairing, iterations=iterations, smoothing=smoothing)
    patch = _fallback_patch(ctx, F0, same, options)
    return Patch(vertices=V[k:], faces=F, info=info) if patch is None else patch


def _optimised_clear_of_mesh(ctx, F0, V, F, scale, info, optimise, alpha, fixed, relaxation, iterations):
    """Sec. III.D on the refined patch (V, F), then, if that crosses the mesh, the steps that avoid it.

    Swaps can fold a patch through a strongly curved border or onto itself: the refinement is
    redone with every swap checked for intersections, and as a last resort without swaps
    (centroid splits alone never create an intersection). The filter moves vertices along their
    normals, which can fold a large, nearly flat patch: as many iterations are used as keep it
    free of intersections. ``optimise(V, F, scale, iterations)`` is :func:`_optimise` with the
    filter's options; ``info`` gets the refinement used and the filter's iterations.

    Returns
    -------
    V : (n, 3) float64, F : (m, 3) int64  the patch, which may still cross the mesh
    """
    Vb, Fb = optimise(V, F, scale, iterations)
    info["refinement"], info["bilateral_iterations"] = "plain", iterations
    if not crosses(ctx, Vb, Fb):
        return Vb, Fb
    refined = False
    for mode, guard in (("guarded", patch_guard(ctx, check_intersections=True)),
                        ("splits only", lambda V, F, A, B, r: np.zeros(len(A), bool))):
        if not crosses(ctx, V, F) or crosses(ctx, ctx.points, F0):
            break
        V, F, scale, info2 = refine_patch(ctx.points, F0, ctx.edge_scale, alpha=alpha, fixed_edges=fixed,
                                          allowed=guard, criterion=relaxation)
        refined = True
        info.update(info2, refinement=mode)
    for n_iter in range(iterations, -1, -1):
        if n_iter == iterations and not refined:
            continue  # the same refinement and iterations: (Vb, Fb), which crosses
        Vb, Fb = optimise(V, F, scale, n_iter)
        if n_iter == 0 or not crosses(ctx, Vb, Fb):
            break
    info["bilateral_iterations"] = n_iter
    return Vb, Fb


def _fallback_patch(ctx, F0, same, options):
    """The first fallback patch that crosses nothing (``fallback`` of :func:`fill`), or None.

    A large, strongly curved hole: the flat minimum-angle surface and the filter's moves along
    the normals keep crossing the mesh, where a faired patch bends away from it; so the faired
    option set is tried first from ``F0``. Where ``F0`` folds already (a cut across walls standing
    on the hole's plane), the steps are tried from the hole plane's triangulation, if it crosses
    less than ``F0`` (:func:`_hole_plane_start`). Then a jagged
    border, whose faces tilt every way so that the ears fold onto them: the loop's least-bend
    triangulations; after them, the hole plane's attempts where they were not tried first.
    ``same`` are the options every attempt keeps, ``options`` the filter's own (fairing,
    iterations, smoothing).
    """
    faired = options == FAIRED_OPTIONS
    tries = [] if faired else [("faired", lambda: F0, FAIRED_OPTIONS)]
    last = []
    if crosses(ctx, ctx.points, F0):
        plane, first = _hole_plane_start(ctx, F0)
        if plane is not None:
            plane_tries = [("hole plane", lambda: plane, options)]
            plane_tries += [] if faired else [("hole plane, faired", lambda: plane, FAIRED_OPTIONS)]
            if first:
                tries += plane_tries
            else:
                last = plane_tries
    for name, initial, chosen in itertools.chain(tries, _least_bend_tries(ctx, options, faired), last):
        try:
            patch = _patch_from(ctx, initial(), **same, **chosen)
        except HoleFillError:  # the hole fails for the paper's patch, not for a fallback's
            continue
        if not crosses(ctx, patch.all_points(ctx.points), patch.faces):
            patch.info["fallback"] = name
            return patch
    return None


def _hole_plane_start(ctx, F0):
    """The hole plane's triangulation ((k - 2, 3) int64, None where there is none) as a fallback's start, and
    whether it is tried before the least-bend triangulations.

    It replaces a triangulation that folds through the walls of a cut across; where it has at
    least as many faces crossing the mesh or each other as ``F0`` (a jagged loop, whose faces
    tilt every way, is no cut across), the patches grown from it mostly cross too, and it is
    tried after the least-bend ones only. Measured on the noisy cow's 307-edge hole: ``F0`` has
    6 faces crossing the mesh, the hole plane's 62, and its two attempts took 0.12 of the
    hole's 0.26 s before the least-bend one closed it. A 12-edge hole of a noisy range scan,
    whose three least-bend triangulations each cross the mesh, is closed by the hole plane's.
    """
    try:
        plane = hole_plane_triangulation(ctx.points, ctx.forbidden_edges)
    except HoleFillError:
        return None, False
    crossing = len(context_crossings(ctx, ctx.points, plane)), len(context_crossings(ctx, ctx.points, F0))
    return plane, crossing[0] < crossing[1]


def _least_bend_tries(ctx, options, faired):
    """The least-bend fallback's attempts (name, initial triangulation, options): each triangulation of
    :func:`.least_bend.least_bend_triangulations` with the options asked for, then each with the faired
    option set (where the filter's own patch bends onto the jagged border's teeth, the faired one bends away).
    """
    seen = []
    for T in least_bend_triangulations(ctx):
        seen.append(T)
        yield "least bend", (lambda T=T: T), options
    if not faired:
        for T in seen:
            yield "least bend, faired", (lambda T=T: T), FAIRED_OPTIONS
