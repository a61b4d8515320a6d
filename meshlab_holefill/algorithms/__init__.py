"""The hole-filling algorithms, one subpackage per paper, and the table of filters made from them.

Each subpackage holds every step of its paper, its options beyond the paper, and provides
``fill(ctx, **params) -> Patch`` on one :class:`~meshlab_holefill.core.holes.HoleContext`,
``PARAMS`` (its own ParamSpecs, after :data:`~meshlab_holefill.core.pipeline.COMMON_PARAMS`),
``RINGS`` (rings of surrounding mesh its HoleContext needs) and optionally ``PREPARE`` (a
border refinement run before any hole is filled) and ``WARM_UP`` (loads its compiled kernels
before holes are filled in forked workers, and drops what it kept from an earlier run). Algorithms are pure numpy/scipy: they may
import ``errors``, ``geometry`` and ``core``, never ``meshlab`` or ``evaluation``.

========================  =====================================  ===================================
subpackage                filter                                 paper
========================  =====================================  ===================================
``hu2012``                meshing_close_holes_min_angle_bilateral  Hu, Wang, Li, Liu, JSW 2012
``brunton2009``           meshing_close_holes_curve_unfolding      Brunton et al., SMI 2009
``xie_zou2013``           meshing_close_holes_differential_evolution  Xie and Zou, CAD 2013
``xu2013``                meshing_close_holes_lssvm_poisson        Xu, Li, Tan, CCTA 2013
========================  =====================================  ===================================
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass

__all__ = ["ALGORITHMS", "Algorithm", "find_algorithm"]


@dataclass(frozen=True)
class Algorithm:
    """One row of the table of filters.

    Attributes
    ----------
    key : str
        Short name, as given to :func:`meshlab_holefill.fill_holes` (``"min_angle_bilateral"``).
    module : str
        Module providing ``fill``, ``PARAMS``, ``RINGS``, below this package.
    filter_name : str
        Python name of the MeshSet filter.
    display_name : str
        MeshLab display name (in .mlx scripts).
    paper : str
        Full citation.
    """

    key: str
    module: str
    filter_name: str
    display_name: str
    paper: str

    def load(self):
        """The algorithm's module (``fill``, ``PARAMS``, ``RINGS``, optional ``PREPARE``)."""
        return importlib.import_module(f"{__name__}.{self.module}")


ALGORITHMS = (
    Algorithm("min_angle_bilateral", "hu2012.min_angle_bilateral", "meshing_close_holes_min_angle_bilateral",
              "Close Holes: Minimum Angle + Bilateral",
              "P. Hu, C. Wang, B. Li, M. Liu, Filling Holes in Triangular Meshes in Engineering, JSW 2012"),
    Algorithm("curve_unfolding", "brunton2009.curve_unfolding", "meshing_close_holes_curve_unfolding",
              "Close Holes: Curve Unfolding",
              "A. Brunton, S. Wuhrer, C. Shu, P. Bose, E. D. Demaine, Filling Holes in Triangular Meshes by Curve "
              "Unfolding, IEEE SMI 2009"),
    Algorithm("differential_evolution", "xie_zou2013.differential_evolution",
              "meshing_close_holes_differential_evolution", "Close Holes: Differential Evolution (HPDE)",
              "W.-C. Xie, X.-F. Zou, A triangulation-based hole patching method using differential evolution, "
              "CAD 45 (2013)"),
    Algorithm("lssvm_poisson", "xu2013.lssvm_poisson", "meshing_close_holes_lssvm_poisson",
              "Close Holes: LS-SVM Laplacian + Poisson",
              "B. Xu, Z. Li, Y. Tan, Feature Based Hole Filling Algorithm on Triangular Mesh, CCTA 2013, IFIP AICT 420, "
              "pp. 90-101"),
)


def find_algorithm(name):
    """The table row of an algorithm, by its short name or its filter name.

    Raises
    ------
    ValueError
        Unknown name (the message lists the valid ones).
    """
    for row in ALGORITHMS:
        if name in (row.key, row.filter_name):
            return row
    raise ValueError(f"unknown algorithm {name!r}; valid: {', '.join(row.key for row in ALGORITHMS)} "
                     "(or their filter names)")
