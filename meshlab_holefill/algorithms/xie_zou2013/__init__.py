"""Xie and Zou, "A triangulation-based hole patching method using differential evolution", CAD 2013 (HPDE).

Where each step of Algorithm 2 lives (step 1, smoothing noisy input, is not used):

* Algorithm 1, DE/rand/1/bin: :mod:`.de_rand_1_bin` (:func:`de_rand_1_bin`).
* Step 2, Sec. 4.2: EdgeLen, base points, the Eq. 8 PCA segmentation: :mod:`.sections`
  (:func:`ring_edge_length`, :func:`base_points`, :func:`pca_segmentation`, :func:`segment_boundary`).
* Step 3, Sec. 4.3: correspondences (Eq. 9/10, the I_c rule): :mod:`.sections`
  (:func:`correspondences`).
* Step 4, Sec. 4.4: section planes (Eq. 11) and their intersection with the border ring:
  :mod:`.sections` (:func:`section_normals`, :func:`ring_intersections`).
* Step 5, Sec. 4.5: arcs and the DE prediction of the points (Eq. 12-16): :mod:`.prediction`
  (:func:`predict_points`, :func:`predict_y`).
* Step 6, Sec. 4.6: projection and constrained triangulation on the PCA plane or two unfolded
  planes (and the disc layout beyond the paper): :mod:`.triangulation`
  (:func:`triangulate_layout`); fold-over detection and repair: :mod:`.folds`.
* Step 7, Sec. 4.7: NumSmooth smoothing passes: :mod:`.smoothing` (:func:`taubin_smooth`,
  :func:`curvature_smooth`); decimation of short edges and min-angle swaps: :mod:`.optimisation`
  (:func:`decimate_short_edges`, :func:`swap_edges_min_angle`); the final guarded quality pass
  beyond the paper: :mod:`.quality_pass` (:func:`raise_min_quality`).
* The steps in order and the layouts tried: the private ``_algorithm2`` module; step 7 on one
  layout: ``_smooth_and_optimise``; the loop-only last resort: ``_loop_only_patch``. The filter (``fill``, ``PARAMS``, ``RINGS``, the readings of the
  paper): :mod:`.differential_evolution`. The paper's sphere experiment is in
  :mod:`meshlab_holefill.evaluation.papers.hpde_sphere`.
"""
from .de_rand_1_bin import de_rand_1_bin
from .differential_evolution import PARAMS, RINGS, fill
from .optimisation import decimate_short_edges, swap_edges_min_angle
from .prediction import predict_points, predict_y
from .quality_pass import raise_min_quality
from .sections import (base_points, correspondences, pca_segmentation, ring_edge_length, ring_intersections,
                       section_normals, segment_boundary)
from .smoothing import curvature_smooth, taubin_smooth
from .triangulation import triangulate_layout

__all__ = ["fill", "PARAMS", "RINGS", "de_rand_1_bin", "ring_edge_length", "base_points", "pca_segmentation",
           "segment_boundary", "correspondences", "section_normals", "ring_intersections", "predict_points",
           "predict_y", "triangulate_layout", "taubin_smooth", "curvature_smooth", "decimate_short_edges",
           "swap_edges_min_angle", "raise_min_quality"]
