"""Each row of the table of algorithms as a FilterSpec whose ``run`` fills holes on a MeshSet."""
from __future__ import annotations

from ..algorithms import ALGORITHMS
from ..core.pipeline import COMMON_PARAMS
from .close_holes import close_holes
from .registration import FilterSpec, register

__all__ = ["filter_spec", "register_all"]


def filter_spec(algorithm):
    """The FilterSpec of one :class:`~meshlab_holefill.algorithms.Algorithm`."""
    module = algorithm.load()
    own = list(module.PARAMS)

    def run(ms, **params_in):
        return close_holes(ms, module.fill, params_in, algorithm_params=[p.name for p in own],
                           rings=module.RINGS, prepare=getattr(module, "PREPARE", None),
                           warm_up=getattr(module, "WARM_UP", None),
                           seconds_per_edge=getattr(module, "SECONDS_PER_EDGE", None))

    doc = (module.__doc__ or "").strip().split("\n\n")[0]
    return FilterSpec(name=algorithm.filter_name, display_name=algorithm.display_name, description=doc,
                      params=COMMON_PARAMS + own, run=run, paper=algorithm.paper, extra={"module": module.__name__})


def register_all():
    """Register every algorithm's filter on pymeshlab.MeshSet (idempotent)."""
    for algorithm in ALGORITHMS:
        register(filter_spec(algorithm))
