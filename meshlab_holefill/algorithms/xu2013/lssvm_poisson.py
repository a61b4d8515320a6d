"""Hole filling by an advancing-front patch repositioned by a Poisson equation on LS-SVM-predicted Laplacians.

Xu, Li and Tan, "Feature Based Hole Filling Algorithm on Triangular Mesh", CCTA 2013: long
boundary edges are split at their midpoints (Sec. 3.1); the hole is covered by the advancing
front method (Sec. 3.2); least-squares support vector machines learn, on k layers of mesh
vertices around the hole, each component of the normalised cotangent Laplacian as a function
of the same coordinate component (Sec. 2.1-2.2, 3.3); the patch's inner vertices are then
placed by the discrete Poisson equation L x = f(x) with the boundary as Dirichlet condition
(Sec. 2.3, 3.4, Eq. 16-19), the boundary vertices' Laplacians joining the system as Sec. 2.3's
boundary condition (``poisson_boundary``). With ``laplacian_prediction='zero'`` and
``poisson_boundary='dirichlet'`` the right-hand side is 0 and the boundary only fixed, the
membrane fill of Zhao et al. 2007 the paper compares with (its Table 1).

Sec. 3.1 runs for all holes at once before any is filled (``PREPARE``: it changes original
faces, see :mod:`.border_split`); the initial patch, the Laplacian and the safeguards beyond the
paper are in :mod:`.poisson_patch`, the training set and the regression in
:mod:`.laplacian_regression` (the LS-SVM itself in :mod:`.lssvm`), the Poisson reconstruction in
:mod:`.poisson_reconstruction`, the advancing front in :mod:`.advancing_front`. This module is
the filter: its parameters and :func:`fill`, which runs those steps in order.

Parameter choices the paper leaves open, as measured on the benchmark's 42 holes with ground
truth (mean patch-to-ground-truth distance, per mille of the bounding-box diagonal; the
boundary's Laplacian rows in the Poisson system): ``layers`` 1 / 2 / 3 gives 2.02 / 2.13 /
2.15 over all holes (medium 1.98 / 2.43 / 2.59, large 2.02 / 2.19 / 2.20, creased 3.88 /
3.96 / 3.95, small 0.137 / 0.139 / 0.142), so k = 1 (lower or equal in every class).
``poisson_iterations`` 2 gives 2.17 (creased 3.88 -> 4.25), so one solve, except on the loop's
development (:func:`.poisson_reconstruction.poisson_solves`).
"""
from __future__ import annotations

import functools
import time

import numpy as np

from ...core import examples
from ...core.blas_threads import single_blas_thread
from ...core.border_bend import border_bend
from ...core.holes import hole_context
from ...core.parameters import ParamSpec
from ...core.patch import Patch
from ...errors import HoleFillError
from ...geometry.flips import relax_edges
from ...geometry.quality import triangle_quality
from ...geometry.refine import refine_patch
from ...geometry.segments import is_simple_polygon, polygon_edges_touch
from .advancing_front import warm_up as warm_up_front
from .border_split import split_long_boundary_edges
from .laplacian_regression import (NormalFrameRegressor, fit_laplacian_regressors, training_rows, training_set,
                                   vertex_edge_scale)
from .poisson_patch import initial_patches, normalized_cotangent_laplacian
from .poisson_reconstruction import SLIVER_QUALITY, poisson_solves, reposition

__all__ = ["fill", "PARAMS", "RINGS", "PREPARE", "prepare_boundary", "WARM_UP", "warm_up"]

MAX_LAYERS = 5
BOUNDARY_WEIGHT = 2.0  # poisson_reconstruction.poisson_reposition says how it was chosen
RINGS = MAX_LAYERS + 1  # vertices of depth <= RINGS - 1 have complete 1-rings in the HoleContext
PARAMS = [
    ParamSpec("split_boundary", "bool", True,
              "Boundary pre-treatment (Sec. 3.1): split boundary edges longer than split_factor times the "
              "hole's mean boundary edge length, with their border triangle, at their midpoints. The only "
              "change to original faces; the surface stays geometrically identical."),
    ParamSpec("split_factor", "float", 1.5,
              "k of Sec. 3.1 (the paper leaves it open): an edge is split when longer than k * L_ave. "
              "1.5 leaves evenly sampled boundaries untouched.", minimum=1.0, maximum=100.0),
    ParamSpec("merge_factor", "float", 0.75,
              "Advancing front (Sec. 3.2, Step 4): a new vertex closer than merge_factor times the target "
              "edge length to a front vertex is merged with it.", minimum=0.1, maximum=0.95),
    ParamSpec("layers", "int", 1,
              "Layers of mesh vertices around the hole in the LS-SVM training set (Sec. 3.3; the paper leaves "
              "k open): the one ring sharing a triangle with the boundary fitted the patches closest.",
              minimum=1, maximum=MAX_LAYERS),
    ParamSpec("gamma", "float", 10.0,
              "LS-SVM regularisation parameter gamma (Sec. 2.2, Eq. 11, 14; not given in the paper). 1 to 10 "
              "fit about equally; 100 follows the noise of the samples' Laplacians.", minimum=1e-6, maximum=1e9),
    ParamSpec("kernel_width", "float", 0.5,
              "RBF kernel width sigma as a fraction of the training set's RMS radius (Sec. 2.2; not given in "
              "the paper). 0.25 overfits on irregular meshes, 1.0 smooths curvature away.",
              minimum=1e-3, maximum=100.0),
    ParamSpec("laplacian_frame", "enum", "global",
              "What the LS-SVM learns (Sec. 2.2, 3.3): 'global' (the paper as printed: each global coordinate "
              "component of the Laplacian as a function of the same coordinate component, Eq. 9) or 'normal' "
              "(a reading: the Laplacian's normal component divided by the squared local edge length, a "
              "scale-free mean curvature, as a function of the position; rotation-invariant and independent "
              "of the patch's resolution; the patch's Laplacian is that curvature times its own squared edge "
              "length along its normal).", choices=("global", "normal")),
    ParamSpec("model_selection", "enum", "fixed",
              "LS-SVM kernel width and gamma: 'fixed' (kernel_width, gamma) or 'loo' (chosen from the data by "
              "the closed-form leave-one-out error of the LS-SVM over widths 0.25-2 of the RMS radius and "
              "gamma 1-1000).", choices=("fixed", "loo")),
    ParamSpec("poisson_iterations", "int", 1,
              "Poisson solves (Sec. 3.4): the patch's cotangent Laplacian depends on the positions, so further "
              "solves use the previous result's weights. A patch built on the loop's development (the fallback "
              "where the 3D front leaves the hole) also gets a second, kept if its patch meets the surrounding "
              "surface with the smaller bend: its first solve's weights are the development's.",
              minimum=1, maximum=50),
    ParamSpec("poisson_boundary", "enum", "laplacian",
              "Boundary condition of the Poisson equation (Sec. 2.3): 'laplacian' (the hole boundary is fixed and "
              "its vertices' Laplacians, Eq. 1 over the mesh and the patch, are asked to equal their prediction "
              "too; the system, then overdetermined, is solved in the least-squares sense, as Sec. 2.3 and 3.4 "
              "describe) or 'dirichlet' (the boundary fixed, one equation per inner vertex: the patch meets the "
              "mesh at an angle).", choices=("laplacian", "dirichlet")),
    ParamSpec("boundary_weight", "float", BOUNDARY_WEIGHT,
              "With poisson_boundary='laplacian': the weight of each boundary vertex's Laplacian equation "
              "against an inner vertex's in the least-squares solve (Sec. 3.4; the paper leaves it open). Larger "
              "values make the patch continue the surrounding surface's slope more closely.",
              minimum=0.01, maximum=100.0),
    ParamSpec("laplacian_prediction", "enum", "lssvm",
              "Right-hand side of the Poisson equation: 'lssvm' (the paper) or 'zero' (with "
              "poisson_boundary='dirichlet' the membrane fill of Zhao et al. 2007, the paper's Table 1 "
              "comparison).", choices=("lssvm", "zero")),
    ParamSpec("relax", "bool", True,
              "Beyond the paper, for triangle quality: Delaunay edge swaps on the advancing-front "
              "patch (thin triangles where fronts meet) and, after the Poisson solve, swaps and tangential "
              "smoothing (the solve also moves vertices along the surface), then local smoothing around "
              "triangles still below quality 0.3."),
]


def prepare_boundary(V, F, loops, params):
    """Boundary edge pre-treatment for the filter pipeline (Sec. 3.1), the module's ``PREPARE`` hook.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int  the whole mesh
    loops : list of BoundaryLoop  the holes about to be filled
    params : dict  the filter's parameters (``split_boundary``, ``split_factor``)

    Returns
    -------
    BorderRefinement or None (nothing to split, or splitting switched off)
    """
    if not params.get("split_boundary", True):
        return None
    refinement = split_long_boundary_edges(V, F, loops, params.get("split_factor", 1.5))
    return refinement if refinement.split_edges else None


PREPARE = prepare_boundary


def warm_up():
    """Load the compiled kernels a fill calls: the 3D front's, the edge relaxation's rounds and the Laplacian's rows.

    Loading them from the disk cache takes a few tenths of a second per process; called
    before holes are filled in forked workers, it lets them inherit the loaded kernels. A small
    hole is filled too, so that every kernel a fill calls is loaded with the argument types a
    real hole gives it.
    """
    if _WARM:
        return
    warm_up_front()
    rhombus = np.array([[-1.0, 0.0, 0.0], [0.0, -0.3, 0.0], [1.0, 0.0, 0.0], [0.0, 0.3, 0.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    relax_edges(rhombus, faces)  # the long diagonal is swapped
    normalized_cotangent_laplacian(rhombus, faces)
    V, F, loop = examples.bowl_with_hole()
    fill(hole_context(V, F, loop, rings=RINGS))
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    polygon_edges_touch(square)  # the developed loop's tests, which the bowl's hole does not reach
    is_simple_polygon(square, 1e-9)
    refine_patch(rhombus, faces, np.full(4, 0.5))  # the initial patches' refinement (split faces)
    _WARM.append(True)


_WARM = []  # set once the compiled kernels are loaded in this process


WARM_UP = warm_up
# Fill seconds per boundary edge with the defaults (the benchmark's holes, one core; the time grows
# about linearly with the edges): the estimate from which workers=0 judges whether forking pays.
SECONDS_PER_EDGE = 3.8e-4


def _one_blas_thread(fill_function):
    """Fill with one BLAS thread (:mod:`..core.blas_threads`: a hole's dense systems are too small to share)."""
    @functools.wraps(fill_function)
    def wrapped(*args, **kwargs):
        with single_blas_thread():
            return fill_function(*args, **kwargs)
    return wrapped


def _less_bent(ctx, added, asked):
    """The repositioned patch, of two, that bends less against the surrounding surface at the border.

    ``added`` has the solves :func:`.poisson_reconstruction.poisson_solves` added, ``asked`` those
    the filter was asked for; each is (X, F, info), X None when the patch was not clear of the mesh.
    The smaller :func:`core.border_bend.border_bend` wins, a tie going to ``added``;
    ``info["added_solve_kept"]`` says which was kept.
    """
    k = ctx.size
    kept = added
    if added[0] is not None and asked[0] is not None:
        if border_bend(ctx, asked[0][k:], asked[1]) < border_bend(ctx, added[0][k:], added[1]):
            kept = asked
    elif added[0] is None:
        kept = asked
    kept[2]["added_solve_kept"] = kept is added
    return kept


def _poorer(X, F, X_unshaped, F_unshaped):
    """Does the patch (X, F) have a triangle below ``SLIVER_QUALITY`` and below every one of the unshaped patch?

    On small holes of noisy scans the 3D front's patch, where its solves fail, is already close
    to the surface (0-0.1 per mille from it), and the later patch the solve shapes can be worse
    and hold a sliver (a 13-edge hole: quality 0.37 -> 0.03); where the shaped patch has no poor
    triangle, or none poorer than the unshaped one, it is the better patch on the measured cases.
    """
    worst = triangle_quality(X, F).min()
    return worst < min(SLIVER_QUALITY, triangle_quality(X_unshaped, F_unshaped).min())


@_one_blas_thread
def fill(ctx, split_boundary=True, split_factor=1.5, merge_factor=0.75, layers=1, gamma=10.0,
         kernel_width=0.5, poisson_iterations=1, laplacian_prediction="lssvm", relax=True,
         laplacian_frame="global", model_selection="fixed", poisson_boundary="laplacian",
         boundary_weight=BOUNDARY_WEIGHT):
    """Fill one hole by Xu et al.'s steps (Sec. 3.2-3.4); Sec. 3.1 ran before as ``PREPARE``.

    The training set and regression (Sec. 3.3, 2.2) come first; then the initial patches of
    :func:`.poisson_patch.initial_patches` are tried in turn (the paper's 3D advancing front
    first) until one is repositioned (:func:`.poisson_reconstruction.reposition`) clear of the surrounding mesh.
    A patch no Poisson solve could be kept for (each folded it beyond repair, or gave no finite
    positions) is the initial triangulation alone, without the Sec. 3.4 step that gives the
    patch its shape: the later initial patches are tried for one the solve does shape, and it
    is kept only when none is, or when the shaped one has a poor triangle it has not
    (:func:`_poorer`; measured in docs/notes/xu2013_lssvm_poisson.md).

    Parameters
    ----------
    ctx : HoleContext
        The hole and ``RINGS`` rings of faces around it (:func:`meshlab_holefill.core.holes.hole_context`),
        its loop already refined by :func:`prepare_boundary` when the pipeline runs it.
    split_boundary, split_factor : bool, float
        Used by :func:`prepare_boundary` only (Sec. 3.1).
    merge_factor : float
        Advancing-front merge distance, in target edge lengths (Sec. 3.2, Step 4).
    layers : int
        Rings of mesh vertices in the LS-SVM training set (Sec. 3.3).
    gamma, kernel_width : float
        LS-SVM regularisation and RBF width (fraction of the training set's RMS radius).
    poisson_iterations : int
        Poisson solves (Sec. 3.4).
    laplacian_prediction : {'lssvm', 'zero'}
        Right-hand side of the Poisson equation.
    relax : bool
        Beyond the paper: swaps and smoothing for triangle quality.
    laplacian_frame, model_selection : str
        What the LS-SVM learns, and how its width and gamma are chosen (readings; see ``PARAMS``).
    poisson_boundary : {'laplacian', 'dirichlet'}
        The Poisson system's boundary condition (:func:`.poisson_reconstruction.poisson_reposition`): the boundary's
        Laplacian rows by least squares (Sec. 2.3), or the square Dirichlet system.
    boundary_weight : float
        The weight of those boundary rows against the inner rows (:func:`.poisson_reconstruction.solve_poisson`).

    Returns
    -------
    Patch
        ``vertices`` (p, 3) float64 and ``faces`` (q, 3) int64 in loop-local indices (i < k:
        loop vertex i). ``info`` has the initial patch's counts (``afm_*``, ``afm_domain`` says which
        triangulation), ``fallbacks`` (and ``fallback_reasons``), ``swaps``,
        ``training_samples``, the Poisson counts, ``poisson_damping`` and per-step seconds.

    Raises
    ------
    HoleFillError
        When no initial patch can be made or kept clear of the surrounding mesh.

    References
    ----------
    B. Xu, Z. Li and Y. Tan, "Feature Based Hole Filling Algorithm on Triangular Mesh", 7th
    International Conference on Computer and Computing Technologies in Agriculture (CCTA 2013),
    IFIP AICT 420, Springer, pp. 90-101.

    Examples
    --------
    A round hole in a bowl-shaped grid, its Laplacian predicted by LS-SVM and the patch solved by Poisson:

    >>> from meshlab_holefill.core import examples, hole_context
    >>> V, F, loop = examples.bowl_with_hole()
    >>> ctx = hole_context(V, F, loop, rings=RINGS)
    >>> patch = fill(ctx)
    >>> examples.is_disc_patch(patch, ctx)  # closes the loop exactly once, as a disc
    True
    """
    k = ctx.size
    t0 = time.perf_counter()
    regressors, samples = None, 0
    if laplacian_prediction == "lssvm":
        samples_X, samples_delta = training_set(ctx, min(layers, RINGS - 1))
        samples = len(samples_X)
        if samples and laplacian_frame == "normal":
            rows = training_rows(ctx, min(layers, RINGS - 1))
            scale = vertex_edge_scale(ctx.vertices, ctx.faces)[rows]
            regressors = NormalFrameRegressor(samples_X, samples_delta, ctx.normals[rows], scale, gamma,
                                              kernel_width, model_selection)
        elif samples:
            regressors = fit_laplacian_regressors(samples_X, samples_delta, gamma, kernel_width, model_selection)
    t1 = time.perf_counter()
    failures, crossing, unshaped = [], None, None
    for X0, F0, stats, layout in initial_patches(ctx, merge_factor, failures):
        t2 = time.perf_counter()
        solves = poisson_solves(stats, poisson_iterations)
        X, F, pinfo = reposition(ctx, X0, F0, regressors, solves, relax, poisson_boundary, layout, boundary_weight)
        if solves > poisson_iterations:
            X, F, pinfo = _less_bent(ctx, (X, F, pinfo),
                                     reposition(ctx, X0, F0, regressors, poisson_iterations, relax, poisson_boundary,
                                                layout, boundary_weight))
        seconds = (t1 - t0, t2 - t1, time.perf_counter() - t2)
        if X is None:
            failures.append(f"{stats['domain']} patch: intersects the surrounding mesh")
            if crossing is None and "crossing_patch" in pinfo:  # crossings allowed: the first such patch
                crossing = (*pinfo.pop("crossing_patch"), stats, pinfo, seconds)
            continue
        if pinfo["poisson_solves"] == 0:  # no solve kept: the initial patch only, which a later one may improve on
            if unshaped is None:
                unshaped = (X, F, stats, pinfo, seconds, list(failures))
            failures.append(f"{stats['domain']} patch: no Poisson solve could be kept")
            continue
        if unshaped is not None and _poorer(X, F, unshaped[0], unshaped[1]):
            break  # the shaped patch has a poor triangle the unshaped one does not
        return _patch(k, X, F, stats, pinfo, samples, seconds, failures)
    if unshaped is not None:
        X, F, stats, pinfo, seconds, failed = unshaped
        return _patch(k, X, F, stats, pinfo, samples, seconds, failed)
    if crossing is not None:
        X, F, stats, pinfo, seconds = crossing
        patch = _patch(k, X, F, stats, pinfo, samples, seconds, failures)
        patch.info["crossing_surroundings"] = True
        return patch
    raise HoleFillError("; ".join(failures) or "no initial patch")


def _patch(k, X, F, stats, pinfo, samples, seconds, failures):
    """The filled hole's Patch with :func:`fill`'s info: the initial patch's counts, the solve's, the seconds."""
    info = {f"afm_{key}": value for key, value in stats.items()}
    info.update(training_samples=samples, **pinfo, lssvm_seconds=seconds[0], initial_patch_seconds=seconds[1],
                poisson_seconds=seconds[2], fallbacks=len(failures))
    if failures:
        info["fallback_reasons"] = "; ".join(failures)
    return Patch(vertices=X[k:], faces=F, info=info)
