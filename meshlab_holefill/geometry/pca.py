"""Least-squares plane fitting by principal component analysis."""
from __future__ import annotations

import numpy as np

from .quality import cross_rows

__all__ = ["fit_plane", "plane_frame", "project_to_plane"]


def fit_plane(P):
    """Best-fitting plane of a point set.

    Parameters
    ----------
    P : (k, 3) float64

    Returns
    -------
    centroid : (3,) float64
    normal : (3,) float64
        Unit eigenvector of the smallest covariance eigenvalue.
    eigenvalues : (3,) float64
        Covariance eigenvalues in ascending order (the first is the mean squared distance to the plane).
    axes : (3, 3) float64
        Rows are the eigenvectors in the same order; rows 1 and 2 span the plane.
    """
    P = np.asarray(P, dtype=np.float64)
    c = P.mean(axis=0)
    cov = (P - c).T @ (P - c) / max(len(P), 1)
    w, U = np.linalg.eigh(cov)
    return c, U[:, 0], w, U.T


def plane_frame(normal, hint=None):
    """Two unit vectors (u, v) so that (u, v, normal) is a right-handed orthonormal frame."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    if hint is None:
        hint = np.eye(3)[np.argmin(np.abs(n))]
    u = hint - np.dot(hint, n) * n
    u /= np.linalg.norm(u)
    return u, cross_rows(n, u)  # np.cross's arithmetic without its axis handling, the frame's main cost


def project_to_plane(P, centroid, normal):
    """2D coordinates of points in the frame of the plane, (k, 2), counter-clockwise seen from `normal`."""
    u, v = plane_frame(normal)
    D = np.asarray(P, dtype=np.float64) - centroid
    return np.stack([D @ u, D @ v], axis=1)
