"""Brunton, Wuhrer, Shu, Bose and Demaine, "Filling Holes in Triangular Meshes by Curve Unfolding", SMI 2009.

Where each step lives:

* Sec. 3.1, unfolding the boundary loop into a simple planar polygon (E_PE, simulated
  annealing under the clearance d_MD, projection to the best plane, restarts):
  :mod:`.annealing` (E_PE, :func:`anneal_loop`), :mod:`.linear_motion` (the projection reached by
  linear motion), :mod:`.unfolding` (runs and restarts, :func:`unfold_loop`).
* Sec. 3.2, constrained Delaunay triangulation of the unfolded polygon without Steiner points,
  and Sec. 3.3's planar refinement: :mod:`.unfolded_triangulation`
  (:func:`constrained_delaunay`, :func:`refine_planar`, :func:`triangulate_and_embed`).
* Sec. 3.3, the embedding energies E_AREA and E_DF, each one sparse solve: :mod:`.embedding`
  (:func:`embedding_energy`, :func:`minimise_embedding_energy`, :func:`embed_patch`), built on
  the umbrella operator U of :mod:`.umbrella`.
* Beyond the paper: the development fallback
  (:mod:`meshlab_holefill.geometry.development`, shared with Xu et al.) and the planar domains the
  filter tries (:mod:`.planar_domains`), the crossing repair (:mod:`.crossing_repair`:
  :func:`repair_crossings`), the quality swaps (:mod:`.quality_swaps`: :func:`improve_by_swaps`);
  the tangential relaxation of the embedded patch (:mod:`.tangential_relaxation`, option ``tangential``);
  the resampling of the energy's patch at the surrounding density
  (:func:`.unfolded_triangulation.resample_patch`, option ``density``) and the sliver repair
  (:mod:`.slivers`, option ``slivers``).
* The filter (``fill``, ``PARAMS``, ``RINGS``): :mod:`.curve_unfolding`.
"""
from .crossing_repair import repair_crossings
from .curve_unfolding import PARAMS, RINGS, fill
from .quality_swaps import improve_by_swaps
from .embedding import embed_patch, embedding_energy, minimise_embedding_energy
from .slivers import repair_slivers
from .unfolded_triangulation import constrained_delaunay, refine_planar, resample_patch, triangulate_and_embed
from .annealing import anneal_loop
from .unfolding import unfold_loop

__all__ = ["fill", "PARAMS", "RINGS", "anneal_loop", "unfold_loop", "constrained_delaunay", "refine_planar",
           "triangulate_and_embed", "embedding_energy", "minimise_embedding_energy", "embed_patch",
           "repair_crossings", "improve_by_swaps", "resample_patch", "repair_slivers"]
