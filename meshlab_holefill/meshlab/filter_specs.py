"""The table of this package's filters: one FilterSpec per paper, built from each algorithm module.

An algorithm module provides ``fill(ctx, **params) -> Patch``, ``PARAMS`` (its own
ParamSpecs, after the common ones) and ``RINGS`` (how many rings of surrounding mesh its
HoleContext needs). Adding a filter is adding one row to ``ALGORITHMS``.
"""
from __future__ import annotations

import importlib

from ..core.pipeline import COMMON_PARAMS, close_holes
from .registration import FilterSpec, register

# (module in meshlab_holefill.algorithms, python name, .mlx display name, paper)
ALGORITHMS = [
    ("hu2012.min_angle_bilateral", "meshing_close_holes_min_angle_bilateral", "Close Holes: Minimum Angle + Bilateral",
     "P. Hu, C. Wang, B. Li, M. Liu, Filling Holes in Triangular Meshes in Engineering, JSW 2012"),
    ("brunton2009.curve_unfolding", "meshing_close_holes_curve_unfolding", "Close Holes: Curve Unfolding",
     "A. Brunton, S. Wuhrer, C. Shu, P. Bose, E. D. Demaine, Filling Holes in Triangular Meshes by Curve "
     "Unfolding, IEEE SMI 2009"),
    ("xie_zou2013.differential_evolution", "meshing_close_holes_differential_evolution", "Close Holes: Differential Evolution (HPDE)",
     "W.-C. Xie, X.-F. Zou, A triangulation-based hole patching method using differential evolution, CAD 45 (2013)"),
    ("xu2013.lssvm_poisson", "meshing_close_holes_lssvm_poisson", "Close Holes: LS-SVM Laplacian + Poisson",
     "B. Xu, Z. Li, Y. Tan, Feature Based Hole Filling Algorithm on Triangular Mesh, CCTA 2013, IFIP AICT 420, "
     "pp. 90-101"),
]


def _make_spec(module_name, name, display_name, paper):
    module = importlib.import_module(f"meshlab_holefill.algorithms.{module_name}")
    own = list(module.PARAMS)
    params = COMMON_PARAMS + own

    def run(ms, **params_in):
        return close_holes(ms, module.fill, params_in, algorithm_params=[p.name for p in own],
                           rings=module.RINGS, prepare=getattr(module, "PREPARE", None))

    doc = (module.__doc__ or "").strip().split("\n\n")[0]
    return FilterSpec(name=name, display_name=display_name, description=doc, params=params, run=run,
                      paper=paper, extra={"module": module.__name__})


def register_all():
    """Register every filter of ALGORITHMS on pymeshlab.MeshSet (idempotent)."""
    for row in ALGORITHMS:
        register(_make_spec(*row))
