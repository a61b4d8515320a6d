"""Xu, Li and Tan, "Feature Based Hole Filling Algorithm on Triangular Mesh", CCTA 2013.

Where each step lives:

* Sec. 2.1, the normalised cotangent Laplacian: :mod:`.poisson_patch`
  (:func:`normalized_cotangent_laplacian`).
* Sec. 2.2, LS-SVM regression (the KKT system of Eq. 14, RBF kernel): :mod:`.lssvm`
  (:func:`lssvm_fit`).
* Sec. 3.1, boundary pre-treatment (long border edges split at their midpoints, the filter's
  ``PREPARE``): :mod:`.border_split` (:func:`split_long_boundary_edges`).
* Sec. 3.2, the advancing front mesh of the hole: :mod:`.advancing_front`
  (:func:`advancing_front_triangulation`; its state, predicates and obstacle tests are the
  private ``_front_*`` modules); the initial patch with its fallbacks (development, plane
  projection) and the safeguards beyond the paper: :mod:`.poisson_patch`
  (:func:`initial_patches`, :func:`relax_patch`, :func:`repair_slivers`).
* Sec. 3.3, the training set and the predicted Laplacians: :mod:`.laplacian_regression`
  (:func:`training_set`, :func:`fit_laplacian_regressors`, :func:`predict_laplacians`).
* Sec. 2.3 and 3.4, the Poisson reconstruction with the boundary's Laplacian rows, and its
  safeguards: :mod:`.poisson_reconstruction` (:func:`poisson_reposition`, :func:`reposition`).
* The filter (``fill``, ``PARAMS``, ``RINGS``, ``PREPARE``): :mod:`.lssvm_poisson`.
"""
from .advancing_front import advancing_front_triangulation
from .border_split import split_long_boundary_edges
from .lssvm import lssvm_fit
from .laplacian_regression import fit_laplacian_regressors, predict_laplacians, training_set
from .lssvm_poisson import PARAMS, PREPARE, RINGS, fill
from .poisson_reconstruction import poisson_reposition, reposition
from .poisson_patch import initial_patches, normalized_cotangent_laplacian, relax_patch, repair_slivers

__all__ = ["fill", "PARAMS", "RINGS", "PREPARE", "normalized_cotangent_laplacian", "lssvm_fit",
           "split_long_boundary_edges", "advancing_front_triangulation", "initial_patches", "relax_patch",
           "repair_slivers", "training_set", "fit_laplacian_regressors", "predict_laplacians", "poisson_reposition",
           "reposition"]
