"""Four published hole-filling algorithms as pymeshlab MeshSet filters.

Importing the package registers the filters as methods of ``pymeshlab.MeshSet``::

    import pymeshlab, meshlab_holefill
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh("scan.ply")
    ms.meshing_close_holes_min_angle_bilateral(maxholesize=500)
"""
from .core.holes import HoleContext, MeshTopologyError, boundary_loops, hole_context
from .core.patch import HoleFillError, Patch
from .meshlab.registration import FILTERS, FilterParameterError, apply_filter, clear_filter_history, filter_calls, filter_history, filter_list, print_filter_parameter_list
from .meshlab.mlx.script import MlxRunError, MlxScriptError, filter_script_xml, read_filter_script, run_filter_script, save_filter_script

from .evaluation import cut_holes as compare  # a callable module: meshlab_holefill.evaluation.cut_holes(meshes, report="dir")
from .meshlab import register_all as _register_all

__version__ = "0.1.0"


def batch(inputs, out, **options):
    """Repair many mesh files on dask (a local cluster or yours): see :func:`meshlab_holefill.batch.batch`.

    Imported on first use, so ``import meshlab_holefill`` does not load dask.
    """
    from .batch import batch as run

    return run(inputs, out, **options)


_register_all()  # MeshSet methods; ms.apply_filter(name), filter scripts and the parameter listing know ours

__all__ = [
    "FILTERS", "FilterParameterError", "HoleContext", "HoleFillError", "MeshTopologyError", "Patch",
    "apply_filter", "batch", "boundary_loops", "compare", "filter_history", "filter_list", "hole_context",
    "print_filter_parameter_list",
    "MlxRunError", "MlxScriptError", "clear_filter_history", "filter_calls", "filter_script_xml",
    "read_filter_script", "run_filter_script", "save_filter_script",
]
