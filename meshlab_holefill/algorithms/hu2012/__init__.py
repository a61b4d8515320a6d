"""Hu, Wang, Li and Liu, "Filling Holes in Triangular Meshes in Engineering", JSW 2012: the filter of Sec. III.

Where each step lives:

* Sec. III.B, the modified principle of minimum angle (convex/concave boundary vertices,
  Eq. 2, the normal-angle threshold): :mod:`.min_angle_triangulation`
  (:func:`boundary_angles`, :func:`normal_angle_threshold`, :func:`min_angle_triangulation`, and
  beyond the paper :func:`.min_angle_triangulation.hole_plane_triangulation`, the same about the loop's normal);
  the ear condition and the hole-sector checks that keep ears and swaps inside the hole:
  :mod:`.hole_guards`.
* Sec. III.C, Pfeifle-Seidel density refinement with circumsphere edge relaxation: shared
  with Xu et al., :func:`meshlab_holefill.geometry.refine.refine_patch` and
  :func:`meshlab_holefill.geometry.flips.relax_edges`.
* Sec. III.D, the bilateral filter (Fleishman et al.): :mod:`.bilateral_filter`
  (:func:`bilateral_filter`).
* Options beyond the paper, off by default: ``fairing`` (:mod:`.fairing`,
  :func:`fair_patch_in_context`) and ``smoothing`` (:mod:`.tangential_smoothing`,
  :func:`tangential_smoothing`).
* The filter (``fill``, ``PARAMS``, ``RINGS``, the fallbacks when a step would make the patch
  cross the mesh): :mod:`.min_angle_bilateral`; its test of whether a patch crosses itself or the
  surroundings: :mod:`.crossing_test`.
"""
from .bilateral_filter import bilateral_filter
from .fairing import fair_patch_in_context
from .hole_guards import inside_hole_sector
from .min_angle_bilateral import PARAMS, RINGS, fill
from .min_angle_triangulation import boundary_angles, min_angle_triangulation, normal_angle_threshold
from .tangential_smoothing import tangential_smoothing

__all__ = ["fill", "PARAMS", "RINGS", "boundary_angles", "normal_angle_threshold", "min_angle_triangulation",
           "inside_hole_sector", "bilateral_filter", "fair_patch_in_context", "tangential_smoothing"]
