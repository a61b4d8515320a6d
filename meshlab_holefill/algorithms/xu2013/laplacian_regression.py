"""The training set and the regression of the Laplacian (Xu, Li and Tan 2013, Sec. 3.3, 2.2).

The LS-SVM filter learns, on k layers of mesh vertices around the hole, each component of the
normalised cotangent Laplacian as a function of the same coordinate component (Eq. 9, 14, 15),
and predicts it at the patch's vertices (Eq. 19), the right-hand side of the Poisson system
(:mod:`.poisson_reconstruction`). The ``laplacian_frame='normal'`` reading
(:class:`NormalFrameRegressor`) and the leave-one-out model selection are here too.
"""
from __future__ import annotations

import numpy as np

from ...core.holes import boundary_halfedges
from .lssvm import lssvm_fit
from .poisson_patch import normalized_cotangent_laplacian

__all__ = ["training_set", "training_rows", "fit_laplacian_regressors", "predict_laplacians", "loo_error",
           "select_model", "vertex_edge_scale", "NormalFrameRegressor", "patch_laplacians", "LOO_WIDTHS", "LOO_GAMMAS"]


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
