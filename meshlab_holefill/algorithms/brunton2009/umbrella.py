"""The umbrella operator U of Brunton et al. 2009, Sec. 3.3.

:mod:`.embedding` builds the energies E_AREA and E_DF from U; :mod:`.tangential_relaxation` moves
the interior vertices where U has no tangential part. Both factorise with
:func:`meshlab_holefill.geometry.sparse_lu.symmetric_lu`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...geometry.laplacian import uniform_laplacian
from ...geometry.quality import unique_edges

__all__ = ["umbrella_operator"]


def umbrella_operator(F, n):
    """U of Sec. 3.3 as a sparse matrix: (W @ X)[p] = mean of p's 1-ring - p.

    Parameters
    ----------
    F : (t, 3) int
    n : int  number of vertices

    Returns
    -------
    W : (n, n) CSR float64  (rows of isolated vertices are zero)
    """
    F = np.asarray(F, np.int64)
    E = unique_edges(F)
    if len(E) == 0 or np.any(E[:, 0] == E[:, 1]):  # degenerate faces: the general sparse algebra
        L = uniform_laplacian(F, n)
        degree = -L.diagonal()
        inverse = np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)
        return (sp.diags(inverse) @ L).tocsr()
    return _umbrella_from_edges(E, n)


def _umbrella_from_edges(E, n):
    """diags(1 / degree) @ (A - diags(degree)) built directly, entry for entry as scipy builds it.

    Same values (1 / d and -d / d), same stored entries and the same order within each row
    (scipy's sparse product leaves the columns of a row in decreasing order), so every later
    sparse product and factorisation sees the identical matrix; scipy's construction (a COO
    to CSR conversion, a sparse difference and a sparse product) took most of the operator's
    time on a patch.
    """
    rows = np.concatenate([E[:, 0], E[:, 1]])
    cols = np.concatenate([E[:, 1], E[:, 0]])
    degree = np.bincount(rows, minlength=n).astype(np.float64)
    inverse = np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)
    has = np.flatnonzero(degree > 0)
    rows = np.concatenate([rows, has])
    cols = np.concatenate([cols, has])
    values = np.concatenate([inverse[rows[: 2 * len(E)]], inverse[has] * -degree[has]])
    order = np.argsort(rows * n + (n - 1 - cols), kind="stable")
    indptr = np.zeros(n + 1, np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    W = sp.csr_matrix((values[order], cols[order].astype(np.int32), indptr.astype(np.int32)), shape=(n, n))
    W.has_sorted_indices = False
    return W
