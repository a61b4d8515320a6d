"""Least-squares support vector machine regression (Suykens), as used by Xu et al. 2013, Sec. 2.2.

The regression function f(x) = sum_i a_i K(x, x_i) + b (Eq. 15) comes from the KKT system

    [ 0   1^T             ] [ b ]   [ 0 ]
    [ 1   Omega + I/gamma ] [ a ] = [ y ]          (Eq. 14, Omega_ij = K(x_i, x_j))

of the problem min 1/2 |w|^2 + gamma/2 sum e_i^2 subject to y_i = w^T phi(x_i) + b + e_i
(Eq. 10-13). With the RBF kernel K(x, z) = exp(-|x - z|^2 / (2 sigma^2)), H = Omega + I/gamma
is symmetric positive definite, so the system is solved by one Cholesky factorisation of H:
eta = H^-1 1, nu = H^-1 y, b = 1^T nu / 1^T eta, a = nu - b eta. Inputs may be scalars
(Xu et al. regress one coordinate component, Eq. 9) or vectors.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

__all__ = ["rbf_kernel", "LSSVMRegressor", "lssvm_fit", "kkt_matrix"]


def rbf_kernel(X, Z, width):
    """RBF kernel matrix K_ij = exp(-|X_i - Z_j|^2 / (2 width^2)).

    The squared distances are summed from the differences, not expanded as
    |X_i|^2 + |Z_j|^2 - 2 X_i . Z_j: far from the origin (a scan in georeferenced coordinates,
    1e6 away) the expansion cancels to noise, H of :func:`lssvm_fit` is then not positive
    definite and every hole failed; the kernel depends on X - Z only, as it should.

    Parameters
    ----------
    X : (l,) or (l, d) float64
    Z : (r,) or (r, d) float64
    width : float
        Kernel width sigma (> 0).

    Returns
    -------
    K : (l, r) float64
    """
    X = np.asarray(X, np.float64).reshape(len(X), -1)
    Z = np.asarray(Z, np.float64).reshape(len(Z), -1)
    if X.shape[1] == 1:
        # Scalar inputs (the filter's regressions): the squares einsum sums, without its (l, r, 1) pass.
        diff = X[:, 0, None] - Z[None, :, 0]  # (l, r)
        d2 = np.multiply(diff, diff, out=diff)
    else:
        diff = X[:, None, :] - Z[None, :, :]  # (l, r, d)
        d2 = np.einsum("lrd,lrd->lr", diff, diff)
    d2 /= -2.0 * width * width  # -(d2 / (2 width^2)): a sign changes no other bit
    return np.exp(d2, out=d2)


@dataclass
class LSSVMRegressor:
    """A fitted LS-SVM regression function f(x) = sum_i a_i K(x, x_i) + b (Eq. 15).

    Attributes
    ----------
    support : (l,) or (l, d) float64  training inputs x_i
    alpha : (l,) or (l, c) float64    Lagrange multipliers a_i (one column per output)
    bias : float or (c,) float64      b
    width : float                     RBF kernel width
    gamma : float                     regularisation parameter
    """

    support: np.ndarray
    alpha: np.ndarray
    bias: np.ndarray
    width: float
    gamma: float

    def __call__(self, x):
        """f(x) for (r,) or (r, d) inputs: (r,) or (r, c) values."""
        return rbf_kernel(x, self.support, self.width) @ self.alpha + self.bias


def lssvm_fit(x, y, gamma=10.0, width=1.0):
    """Solve the LS-SVM KKT system (Eq. 14) for the RBF kernel.

    Parameters
    ----------
    x : (l,) or (l, d) float64
        Training inputs.
    y : (l,) or (l, c) float64
        Training outputs (several output columns share the kernel matrix).
    gamma : float
        Regularisation parameter (> 0): larger fits the samples more closely.
    width : float
        RBF kernel width sigma (> 0), in the units of x.

    Returns
    -------
    LSSVMRegressor
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    if len(x) == 0:
        raise ValueError("LS-SVM needs at least one training sample")
    if len(y) != len(x):
        raise ValueError(f"LS-SVM: {len(x)} inputs but {len(y)} outputs")
    H = rbf_kernel(x, x, width)
    H[np.diag_indices_from(H)] += 1.0 / gamma
    factor = sla.cho_factor(H, lower=True, check_finite=False)
    ones = np.ones(len(x))
    eta = sla.cho_solve(factor, ones, check_finite=False)
    nu = sla.cho_solve(factor, y, check_finite=False)
    bias = (ones @ nu) / (ones @ eta)
    alpha = nu - np.multiply.outer(eta, bias) if np.ndim(bias) else nu - bias * eta
    return LSSVMRegressor(support=x, alpha=alpha, bias=bias, width=float(width), gamma=float(gamma))


def kkt_matrix(x, gamma, width):
    """The full (l + 1) x (l + 1) matrix of Eq. 14 (for checks; :func:`lssvm_fit` avoids forming it)."""
    x = np.asarray(x, np.float64)
    l = len(x)
    A = np.zeros((l + 1, l + 1))
    A[0, 1:] = 1.0
    A[1:, 0] = 1.0
    A[1:, 1:] = rbf_kernel(x, x, width) + np.eye(l) / gamma
    return A
