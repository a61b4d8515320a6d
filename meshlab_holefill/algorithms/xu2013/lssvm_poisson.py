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
faces, see :mod:`meshlab_holefill.algorithms.xu2013.border_split`); the initial patch, the Laplacian and
the safeguards beyond the paper are in :mod:`.poisson_patch`, the regression in
:mod:`.lssvm`, the advancing front in :mod:`meshlab_holefill.algorithms.xu2013.advancing_front`.

Parameter choices the paper leaves open, as measured on the benchmark's 42 holes with ground
truth (mean patch-to-ground-truth distance, per mille of the bounding-box diagonal; the
boundary's Laplacian rows in the Poisson system): ``layers`` 1 / 2 / 3 gives 2.02 / 2.13 /
2.15 over all holes (medium 1.98 / 2.43 / 2.59, large 2.02 / 2.19 / 2.20, creased 3.88 /
3.96 / 3.95, small 0.137 / 0.139 / 0.142), so k = 1 (lower or equal in every class).
``poisson_iterations`` 2 gives 2.17 (creased 3.88 -> 4.25), so one solve, except on a curved
development (:func:`poisson_solves`).
"""
from __future__ import annotations

import functools
import time

import numpy as np
import scipy.sparse.linalg as spla

from .advancing_front import warm_up as warm_up_front
from .border_split import split_long_boundary_edges
from ...geometry.laplacian import cotangent_weights, tangential_umbrella_smoothing
from ...core.blas_threads import single_blas_thread
from ...core.holes import boundary_halfedges
from ...core.patch import Patch
from ...errors import HoleFillError
from ...core.parameters import ParamSpec
from .lssvm import lssvm_fit
from ...geometry.flips import relax_edges
from .poisson_patch import (context_hits, initial_patches, normalized_cotangent_laplacian, relax_patch, repair_slivers,
                            solve_folds)

__all__ = ["fill", "PARAMS", "RINGS", "PREPARE", "prepare_boundary", "training_set", "fit_laplacian_regressors",
           "predict_laplacians", "poisson_reposition", "poisson_solves", "reposition"]

MAX_LAYERS = 5
RINGS = MAX_LAYERS + 1  # vertices of depth <= RINGS - 1 have complete 1-rings in the HoleContext
# Tangential smoothing steps after the Poisson solve (with relax): 3 raised the benchmark's
# minimum triangle quality from 0.11 to 0.48 without changing the distance to the ground truth.
TANGENTIAL_ITERATIONS = 3
# Beyond the paper: triangles still below this quality after the smoothing get local tangential
# steps (repair_slivers); 0.3 is the minimum quality below which a triangle counts as poor (README,
# "How each paper is implemented").
SLIVER_QUALITY = 0.3
# The development keeps the loop's perimeter and spreads the curvature it encloses evenly along it.
# A round cap of angular radius t (curvature K = 2 pi (1 - cos t)) then comes out with radius
# sin t for its geodesic t, 2 % short at K = 0.37 rad; beyond it the layout's metric is not the
# surface's, the less so the less round the hole, and a second solve is made (poisson_solves).
CURVED_DEVELOPMENT = 0.37

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
              f"where the 3D front leaves the hole) whose loop encloses more than {CURVED_DEVELOPMENT} rad of "
              "Gaussian curvature gets at least 2: its first solve's weights are the development's.",
              minimum=1, maximum=50),
    ParamSpec("poisson_boundary", "enum", "laplacian",
              "Boundary condition of the Poisson equation (Sec. 2.3): 'laplacian' (the hole boundary is fixed and "
              "its vertices' Laplacians, Eq. 1 over the mesh and the patch, are asked to equal their prediction "
              "too; the system, then overdetermined, is solved in the least-squares sense, as Sec. 2.3 and 3.4 "
              "describe) or 'dirichlet' (the boundary fixed, one equation per inner vertex: the patch meets the "
              "mesh at an angle).", choices=("laplacian", "dirichlet")),
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
    before holes are filled in forked workers, it lets them inherit the loaded kernels.
    """
    warm_up_front()
    rhombus = np.array([[-1.0, 0.0, 0.0], [0.0, -0.3, 0.0], [1.0, 0.0, 0.0], [0.0, 0.3, 0.0]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    relax_edges(rhombus, faces)  # the long diagonal is swapped
    normalized_cotangent_laplacian(rhombus, faces)


WARM_UP = warm_up


def training_set(ctx, layers):
    """Training samples: coordinates and Laplacians of k layers of vertices around the hole (Sec. 3.3).

    SV_1 are the vertices sharing a triangle with a boundary vertex, SV_{j+1} those sharing a
    triangle with SV_j and in no earlier layer (Steps 1-4): exactly the HoleContext's ring
    depths 1..k. Vertices on any mesh boundary (another hole, the mesh border) are left out:
    their Laplacian (Eq. 1) is not defined there.

    Parameters
    ----------
    ctx : HoleContext  with ``rings >= layers + 1``
    layers : int       k

    Returns
    -------
    X : (l, 3) float64  coordinates V_i
    delta : (l, 3) float64  Laplacians delta_i (Eq. 1-3)
    """
    V, F = ctx.vertices, ctx.faces
    rows = training_rows(ctx, layers)
    if len(rows) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3))
    L = normalized_cotangent_laplacian(V, F)
    return V[rows].copy(), np.asarray(L[rows] @ V)


def training_rows(ctx, layers):
    """Context vertices of the training set (:func:`training_set`): depths 1..k, off every border."""
    layer = (ctx.depth >= 1) & (ctx.depth <= layers)
    he, _ = boundary_halfedges(ctx.faces)
    on_border = np.zeros(len(ctx.vertices), bool)
    on_border[he.ravel()] = True
    # The outermost ring of the context is an artificial border; it lies deeper than any layer.
    return np.flatnonzero(layer & ~on_border)


def fit_laplacian_regressors(X, delta, gamma, kernel_width, model_selection="fixed"):
    """LS-SVM regression functions f_x, f_y, f_z of Sec. 3.4 (Eq. 9, 14, 15).

    f_d maps a coordinate component V_id to the same component of the Laplacian delta_id.

    Parameters
    ----------
    X : (l, 3) float64, delta : (l, 3) float64  training set (Sec. 3.3)
    gamma : float  regularisation (Eq. 11)
    kernel_width : float  RBF width as a fraction of the training set's RMS radius

    Returns
    -------
    list of 3 LSSVMRegressor, one per axis
    """
    radius = float(np.sqrt(((X - X.mean(axis=0)) ** 2).sum(axis=1).mean()))
    scale = radius if radius > 0 else 1.0
    out = []
    for d in range(3):
        g, width = select_model(X[:, d], delta[:, d], scale, gamma, kernel_width, model_selection)
        out.append(lssvm_fit(X[:, d], delta[:, d], gamma=g, width=width))
    return out


def predict_laplacians(regressors, X):
    """Delta'_d = [f_d(v'_1d), ..., f_d(v'_nd)] for patch vertices X (Eq. 19), (n, 3)."""
    return np.stack([regressors[d](X[:, d]) for d in range(3)], axis=1)


LOO_WIDTHS = (0.25, 0.5, 1.0, 2.0)
LOO_GAMMAS = (1.0, 10.0, 100.0, 1000.0)


def loo_error(x, y, gamma, width):
    """Mean squared leave-one-out residual of an LS-SVM fit, in closed form (Cawley & Talbot 2004).

    With C the KKT matrix of Eq. 14 and (b, a) = C^-1 (0, y), the residual at sample i of the
    fit without sample i is a_i / (C^-1)_ii.
    """
    from .lssvm import kkt_matrix
    C = kkt_matrix(x, gamma, width)
    Ci = np.linalg.inv(C)
    sol = Ci @ np.concatenate([[0.0], y])
    r = sol[1:] / np.diag(Ci)[1:]
    return float(np.mean(r * r))


def select_model(x, y, scale, gamma, kernel_width, model_selection):
    """(gamma, width) for one regression: the given ones, or the leave-one-out best of the grid."""
    if model_selection != "loo" or len(x) < 8:
        return gamma, kernel_width * scale
    best = min(((loo_error(x, y, g, w * scale), g, w) for w in LOO_WIDTHS for g in LOO_GAMMAS))
    return best[1], best[2] * scale


def vertex_edge_scale(X, F, n=None):
    """Mean squared length of the edges at each vertex, (n,) (0 where a vertex has none)."""
    n = len(X) if n is None else n
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    l2 = ((X[E[:, 0]] - X[E[:, 1]]) ** 2).sum(axis=1)
    total = np.bincount(E.ravel(), weights=np.repeat(l2, 2), minlength=n)
    count = np.bincount(E.ravel(), minlength=n)
    return np.where(count > 0, total / np.maximum(count, 1), 0.0)


class NormalFrameRegressor:
    """LS-SVM of the scale-free normal Laplacian t = (delta . n) / l^2 over positions (laplacian_frame='normal').

    Positions are taken relative to the training set's centroid and divided by its RMS radius;
    the patch's Laplacian at a vertex is t(x) l'^2 n', with l'^2 the mean squared edge length
    at the vertex and n' its normal in the patch being repositioned (Eq. 19 in a local frame).
    """

    def __init__(self, X, delta, normals, edge_scale, gamma, kernel_width, model_selection="fixed"):
        self.centre = X.mean(axis=0)
        radius = float(np.sqrt(((X - self.centre) ** 2).sum(axis=1).mean())) or 1.0
        self.radius = radius
        t = (delta * normals).sum(axis=1) / np.maximum(edge_scale, 1e-300)
        x = (X - self.centre) / radius
        self.gamma, width = select_model(x, t, 1.0, gamma, kernel_width, model_selection)
        self.model = lssvm_fit(x, t, gamma=self.gamma, width=width)

    def laplacians(self, X, F, rows):
        """Predicted Laplacians (len(rows), 3) at patch vertices ``rows`` of the patch (X, F)."""
        from ...geometry.quality import vertex_normals
        N = vertex_normals(X, F, len(X))[rows]
        t = self.model((X[rows] - self.centre) / self.radius)
        return (t * vertex_edge_scale(X, F)[rows])[:, None] * N


def patch_laplacians(regressors, X, F, rows):
    """Right-hand side of Eq. 18 at patch vertices ``rows`` (indices or a mask; zero without regressors)."""
    rows = np.flatnonzero(rows) if np.asarray(rows).dtype == bool else np.asarray(rows)
    if regressors is None:
        return np.zeros((len(rows), 3))
    if isinstance(regressors, NormalFrameRegressor):
        return regressors.laplacians(X, F, rows)
    return predict_laplacians(regressors, X[rows])


def with_context(X, F, ctx):
    """The patch joined to the HoleContext's surrounding faces: patch vertices first, then the context's others."""
    k, p = ctx.size, len(X) - ctx.size
    allX = np.concatenate([X, ctx.vertices[k:]])
    context = np.where(ctx.faces >= k, ctx.faces + p, ctx.faces)
    return allX, np.concatenate([np.asarray(F, np.int64), context])


def boundary_rows(X, F, ctx):
    """Hole-boundary vertices whose Laplacian row (Eq. 1) is complete once the patch closes the hole.

    Left out: those also on another border of the surrounding mesh (another hole, the mesh
    border), where Eq. 1 is not defined.
    """
    allX, allF = with_context(X, F, ctx)
    he, _ = boundary_halfedges(allF)
    on_border = np.zeros(len(allX), bool)
    on_border[he.ravel()] = True
    return np.flatnonzero(~on_border[:ctx.size]), allX, allF


def solve_poisson(X, F, free, rhs, boundary=None, cotangents=None):
    """Positions of the free vertices solving Eq. 18, the three coordinates with one factorisation.

    Without ``boundary``: the square system L_ff x_f = rhs - L_fb x_b (Dirichlet boundary).
    With ``boundary = (rows, allX, allF, rhs_rows)``: the hole-boundary vertices' rows of the
    Laplacian of the patch joined to the surrounding mesh are added, each asking that vertex's
    Laplacian to equal its prediction too, and the system is solved in the least-squares
    sense (normal equations), the boundary still fixed. ``cotangents`` ((len(F), 3)) are the
    patch faces' corner cotangents when they are not those of X (:func:`poisson_reposition`'s
    ``layout``); the surrounding faces always have their own.
    """
    free_idx = np.flatnonzero(free)
    if boundary is None:
        L = normalized_cotangent_laplacian(X, F, cotangents=cotangents)
        B = rhs - L[free][:, ~free] @ X[~free]
        return spla.splu(L[free][:, free].tocsc()).solve(B)
    rows, allX, allF, rhs_rows = boundary
    if cotangents is not None:
        cotangents = np.concatenate([cotangents, cotangent_weights(allX, allF[len(F):])])
    L = normalized_cotangent_laplacian(allX, allF, cotangents=cotangents)
    known = np.ones(len(allX), bool)
    known[free_idx] = False
    R = np.concatenate([free_idx, rows])
    A = L[R][:, free_idx].tocsc()
    B = np.concatenate([rhs, rhs_rows]) - L[R][:, known] @ allX[known]
    return spla.splu((A.T @ A).tocsc()).solve(A.T @ B)


def poisson_reposition(X, F, fixed, regressors=None, iterations=1, update_rhs=False, relax_ctx=None, boundary_ctx=None,
                       layout=None):
    """Poisson reconstruction of the patch (Sec. 2.3, 3.4, Eq. 16-19).

    Solves L_Vn V'_d = Delta'_d (Eq. 18) for the inner vertices, d = x, y, z, with L_Vn the
    normalised cotangent Laplacian of the patch (Eq. 5-6), Delta' the predicted Laplacians
    (Eq. 19; zero without regressors) and the boundary vertices as Dirichlet conditions; one
    sparse LU factorisation per solve serves the three coordinates (:func:`solve_poisson`).

    The boundary condition. Sec. 2.3 takes as known "the collection of divergence values at
    all boundary vertices formulated by Eq. (1) ... as the boundary condition", and Sec. 3.4
    computes the patch "in the least squares sense". With ``boundary_ctx`` (the default of
    :func:`fill`, ``poisson_boundary='laplacian'``) that is the reading: the boundary stays
    fixed, and each boundary vertex's Laplacian (Eq. 1 over its whole 1-ring, mesh and patch)
    is one more equation, asked to equal the prediction at that vertex; the overdetermined
    system is solved by least squares. Those rows tie the first ring of the patch to the
    surface around the hole, so the patch continues the surface's slope instead of meeting it
    at an angle. Measured on the benchmark's 42 holes with ground truth (mean patch-to-ground-
    truth distance, per mille of the bounding-box diagonal; ``scripts/benchmark.py`` cases
    without the natural-hole scans): 3.80 with the square Dirichlet system, 2.13 with the
    boundary rows (small holes 0.203 -> 0.139, medium 3.27 -> 2.43, large 5.63 -> 2.19,
    creased 7.00 -> 3.96, crossing 0.74 -> 0.32; cow.obj's 68-edge hole 8.80 -> 8.32,
    creased_box's 93-edge 23.1 -> 14.8, airplane.obj's 165-edge 9.29 -> 3.20).

    L_Vn of the first solve is the Laplacian of the triangles the advancing front made. Where
    it made them in a plane (the developed or projected fallback of
    :func:`.poisson_patch.initial_patches`, ``layout``), their weights are taken there, not
    from the harmonic lift that places them in 3D: the lift is a membrane spanning the loop,
    its triangles shrunk and sheared towards the middle of a curved hole, while the planar
    triangles are the front's well-shaped ones and, on a developable surface, congruent to
    the surface's own. Measured on the benchmark's 45 holes with ground truth (6 of them on
    the developed fallback; command in README, "How each paper is implemented"): mean
    patch-to-ground-truth distance 1.967 -> 1.849 per mille of the bounding-box diagonal
    (creased 3.883 -> 3.507; the real-size bunny's 3 holes 1.164 -> 0.914, CGAL's Liepa
    fill 0.877; large 2.017 -> 2.211; medium 1.982 -> 2.096): creased_box's 93-edge hole
    14.7 -> 9.3, the real-size 151-edge hole 1.68 -> 1.01, union's 69-edge 6.8 -> 6.2;
    worse on airplane.obj's 165-edge hole (3.3 -> 4.1) and bone.ply's 60-edge hole (4.5 ->
    5.2), both strongly doubly curved, where the development distorts the metric most. The
    lowest triangle quality over the holes went from 0.356 to 0.290 (bone.ply's hole: a
    triangle of three border vertices that the swaps after the solve leave).

    Delta' is predicted once, at the initial patch's vertices (and the boundary's): predicting
    it again at each solve's result made the iteration diverge on several benchmark holes (the
    bulge raises the prediction, which raises the bulge). L_Vn depends on the positions, so
    ``iterations`` > 1 solves again with the weights of the previous result (after Delaunay
    swaps when ``relax_ctx`` is given). One solve is the default: weights from the
    well-shaped initial patch gave the lower distance to the ground truth on the benchmark's
    medium holes (Dirichlet system: mean 3.1 per mille of the bounding-box diagonal with 1
    solve, 3.7 with 2, 3.6 with 3) and better triangles. A solve that folds the patch where it
    moves it (:func:`.poisson_patch.solve_folds`: a degenerate triangle, or neighbours at a
    dihedral angle over 120 degrees) and that :func:`unfold` cannot unfold (with
    ``relax_ctx``; folds the patch had before the solve excepted) is discarded and the
    iteration stops.

    Parameters
    ----------
    X : (n, 3) float64  patch vertices (boundary ones included)
    F : (m, 3) int64    patch faces
    fixed : (n,) bool   Dirichlet vertices (the hole boundary)
    regressors : list of 3 callables, NormalFrameRegressor or None
    iterations : int
    update_rhs : bool   predict Delta' again before each solve (diverges, see above)
    relax_ctx : HoleContext, optional  swap edges between solves and where a solve folds
        (:func:`relax_patch`)
    boundary_ctx : HoleContext, optional  add the boundary vertices' Laplacian rows
        (:func:`boundary_rows`) and solve by least squares
    layout : (n, 3) float64, optional  the patch's planar layout: the first solve's weights

    Returns
    -------
    X : (n, 3) float64
    F : (m, 3) int64  (changed only by swaps between solves)
    info : dict  ``poisson_solves``, ``poisson_last_change`` (max displacement of the last
        accepted solve relative to the first), ``poisson_rejected`` (a solve was discarded)
    """
    X = np.array(X, np.float64)
    free = ~np.asarray(fixed, bool)
    info = {"poisson_solves": 0, "poisson_last_change": 0.0, "poisson_rejected": False}
    if not free.any():
        return X, F, info
    first_change = None
    rhs = patch_laplacians(regressors, X, F, free)
    rhs_rows = None
    for _ in range(iterations):
        if update_rhs and regressors is not None:
            rhs = patch_laplacians(regressors, X, F, free)
        boundary = None
        if boundary_ctx is not None:
            rows, allX, allF = boundary_rows(X, F, boundary_ctx)
            if rhs_rows is None:
                rhs_rows = patch_laplacians(regressors, allX, allF, rows)
            boundary = (rows, allX, allF, rhs_rows)
        layouts = [layout, None] if layout is not None and not info["poisson_solves"] else [None]
        for weights_from in layouts:
            Y, G = _unfolded_solve(X, F, free, rhs, boundary, weights_from, relax_ctx)
            if Y is not None:
                info["poisson_layout_weights"] = weights_from is not None
                break
        if Y is None:
            info["poisson_rejected"] = True
            break
        F = G
        change = float(np.abs(Y - X).max())
        first_change = change if first_change is None else first_change
        info["poisson_last_change"] = change / first_change if first_change > 0 else 0.0
        info["poisson_solves"] += 1
        X = Y
        if relax_ctx is not None and iterations > 1:
            F, _ = relax_patch(X, F, relax_ctx)
    return X, F, info


def _unfolded_solve(X, F, free, rhs, boundary, layout, relax_ctx):
    """One solve (:func:`solve_poisson`, the patch faces' weights from ``layout`` if given), unfolded; (None, F) if it fails."""
    Y = X.copy()
    Y[free] = solve_poisson(X, F, free, rhs, boundary, None if layout is None else cotangent_weights(layout, F))
    if not np.all(np.isfinite(Y)):
        return None, F
    if solve_folds(Y, F, ~free):
        return unfold(Y, F, ~free, relax_ctx, X)
    return Y, F


def unfold(Y, F, fixed, relax_ctx=None, before=None):
    """A folded Poisson solution unfolded by the relaxation that follows every solve, or (None, F).

    A fold across one edge is often a quad the solve turned over: its other diagonal (the
    Delaunay swap, :func:`.poisson_patch.relax_patch`) unfolds it, and discarding the whole
    solve for it lost the predicted shape (airplane's large hole: 10.2 per mille from the
    ground truth without the solve, 8.7 with it). Where swaps are not enough, the solve has
    pressed free vertices against a spike of the boundary; the tangential smoothing that
    follows the solve anyway (``TANGENTIAL_ITERATIONS`` steps, then swaps) spreads them again.
    On bone.ply's 66-edge irregular hole (holes cut with ``scripts/benchmark.py --seed 1
    --holes 6``) the solve was discarded for such a fold, leaving the patch 3.9 per mille of
    the bounding-box diagonal from the ground truth; unfolded, 0.39 (CGAL's Liepa fill 0.26).
    When the solve with the planar layout's weights cannot be unfolded, the lift's own weights
    are tried before the solve is discarded. Without ``relax_ctx`` (``relax`` off) a fold
    discards the solve. Where neither unfolds it, the folds left may be those the patch had
    ``before`` the solve (its positions then): they are not the solve's
    (:func:`.poisson_patch.solve_folds`), and the solve is kept, swapped, then smoothed if
    the swaps alone leave a fold of its own.

    Returns
    -------
    Y : (n, 3) float64 or None, F : (m, 3) int64
    """
    if relax_ctx is None:
        return None, F
    G = relax_patch(Y, F, relax_ctx)[0]
    if not solve_folds(Y, G, fixed):
        return Y, G
    Z = tangential_umbrella_smoothing(Y, G, fixed, TANGENTIAL_ITERATIONS)
    H = relax_patch(Z, G, relax_ctx)[0]
    if not solve_folds(Z, H, fixed):
        return Z, H
    if before is not None:
        if not solve_folds(Y, G, fixed, before):
            return Y, G
        if not solve_folds(Z, H, fixed, before):
            return Z, H
    return None, F


def poisson_solves(stats, poisson_iterations):
    """How many Poisson solves (Sec. 3.4) an initial patch gets: at least two on a curved development.

    The first solve of a patch the front built on the loop's development takes the layout's
    weights (:func:`poisson_reposition`), which are the surface's own on a developable surface,
    creases included, and not where the loop encloses Gaussian curvature: the development spreads
    it evenly along the loop, right for a round cap only. Beyond ``CURVED_DEVELOPMENT`` radians
    (:func:`geometry.development.enclosed_curvature`) a second solve takes the first result's own
    weights. On holes of a unit sphere, mean distance of the patch from the sphere with one and
    two solves: a round cap 0.0060 and 0.0061, an ellipse of half-axes 1.2 and 0.4 0.0074 and 0.0040,
    a three-lobed hole 0.0107 and 0.0072 (``tests/algorithms/xu2013/test_planar_layout_weights.py``). Measured (mean patch-to-ground-truth distance, per mille of the bounding-box
    diagonal; 21 developed holes): ``scripts/large_holes.py --filters meshing_close_holes_lssvm_poisson``
    3.451 -> 3.290 (CGAL's Liepa fill 3.001; bone2_s1's 271-edge hole 1.44 -> 0.58, bunny1_s1's
    265-edge 2.40 -> 1.56); the benchmark suite
    (``scripts/benchmark.py --filters meshing_close_holes_lssvm_poisson --no-pictures``) 1.893 -> 1.872: medium
    1.960 -> 1.863 (bone.ply's 60-edge hole 4.41 -> 3.83), large 2.211 -> 2.094 (airplane.obj's 165-edge 4.10 ->
    3.63), real-size 0.914 -> 0.950 (bunny_212k's 274-edge 0.41 -> 0.27, its 151-edge 1.01 -> 1.26; CGAL 0.877);
    the lowest triangle quality 0.356 -> 0.309 (bone.ply's hole). Two solves on every developed
    patch lost on the flat-sided ones (creased_box's 93-edge hole, enclosing none: 9.33 -> 11.98).

    Parameters
    ----------
    stats : dict  the initial patch's, from :func:`.poisson_patch.initial_patches`
    poisson_iterations : int  the filter's parameter

    Returns
    -------
    int
    """
    if stats.get("domain") == "developed" and abs(stats["enclosed_curvature"]) > CURVED_DEVELOPMENT:
        return max(poisson_iterations, 2)
    return poisson_iterations


def reposition(ctx, X, F, regressors, iterations, relax, poisson_boundary="laplacian", layout=None):
    """Relax, Poisson reconstruction (Sec. 3.4), relax; checked against the surrounding mesh.

    With ``relax`` (beyond the paper) the solve is followed by swaps, :func:`geometry.laplacian.tangential_umbrella_smoothing`,
    swaps again and :func:`repair_slivers` around triangles still below ``SLIVER_QUALITY``
    (dropped again if only the repaired patch touches the surrounding mesh).

    The initial patch is (nearly always) clear of the surrounding mesh; the swaps and the
    Poisson solve may not be (a bulge into a fold of the surface next to the hole). Then the
    swaps are undone and the displacement damped (beyond the paper) until the patch is clear,
    down to the initial patch itself.

    Returns
    -------
    X : (n, 3) float64 or None (not even the initial patch is clear of the mesh)
    F : (q, 3) int64
    info : dict  Poisson counts, ``swaps``, ``poisson_damping`` (1 = the full solve)
    """
    k = ctx.size
    X_front, F_front = X, F
    swaps = 0
    if relax:
        F, swaps = relax_patch(X, F, ctx)
    fixed = np.arange(len(X)) < k
    X, F, info = poisson_reposition(X, F, fixed, regressors, iterations, relax_ctx=ctx if relax else None,
                                    boundary_ctx=ctx if poisson_boundary == "laplacian" else None, layout=layout)
    if not np.all(np.isfinite(X)):
        X, F = X_front, F_front
    repaired = 0
    if relax:
        F, more = relax_patch(X, F, ctx)
        X = tangential_umbrella_smoothing(X, F, fixed, TANGENTIAL_ITERATIONS)
        F, again = relax_patch(X, F, ctx)
        swaps += more + again
        X_smooth, F_smooth = X, F
        X, F, repaired = repair_slivers(X, F, fixed, ctx, SLIVER_QUALITY)
    info.update(swaps=swaps, poisson_damping=1.0, sliver_repairs=repaired)
    if not len(context_hits(X, F, ctx)):
        return X, F, info
    if repaired and not len(context_hits(X_smooth, F_smooth, ctx)):
        info["sliver_repairs"] = 0
        return X_smooth, F_smooth, info
    info["swaps"] = 0
    for t in (1.0, 0.5, 0.25, 0.0):
        Y = X_front + t * (X - X_front)
        if not len(context_hits(Y, F_front, ctx)):
            info["poisson_damping"] = t
            return Y, F_front, info
    return None, F_front, info


def _one_blas_thread(fill_function):
    """Fill with one BLAS thread (:mod:`..core.blas_threads`: a hole's dense systems are too small to share)."""
    @functools.wraps(fill_function)
    def wrapped(*args, **kwargs):
        with single_blas_thread():
            return fill_function(*args, **kwargs)
    return wrapped


@_one_blas_thread
def fill(ctx, split_boundary=True, split_factor=1.5, merge_factor=0.75, layers=1, gamma=10.0,
         kernel_width=0.5, poisson_iterations=1, laplacian_prediction="lssvm", relax=True,
         laplacian_frame="global", model_selection="fixed", poisson_boundary="laplacian"):
    """Fill one hole by Xu et al.'s steps (Sec. 3.2-3.4); Sec. 3.1 ran before as ``PREPARE``.

    The training set and regression (Sec. 3.3, 2.2) come first; then the initial patches of
    :func:`.poisson_patch.initial_patches` are tried in turn (the paper's 3D advancing front
    first) until one is repositioned (:func:`reposition`) clear of the surrounding mesh.

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
        The Poisson system's boundary condition (:func:`poisson_reposition`): the boundary's
        Laplacian rows by least squares (Sec. 2.3), or the square Dirichlet system.

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
    failures = []
    for X0, F0, stats, layout in initial_patches(ctx, merge_factor, failures):
        t2 = time.perf_counter()
        solves = poisson_solves(stats, poisson_iterations)
        X, F, pinfo = reposition(ctx, X0, F0, regressors, solves, relax, poisson_boundary, layout)
        t3 = time.perf_counter()
        if X is None:
            failures.append(f"{stats['domain']} patch: intersects the surrounding mesh")
            continue
        info = {f"afm_{key}": value for key, value in stats.items()}
        info.update(training_samples=samples, **pinfo, lssvm_seconds=t1 - t0,
                    initial_patch_seconds=t2 - t1, poisson_seconds=t3 - t2, fallbacks=len(failures))
        if failures:
            info["fallback_reasons"] = "; ".join(failures)
        return Patch(vertices=X[k:], faces=F, info=info)
    raise HoleFillError("; ".join(failures) or "no initial patch")
