"""Four published hole-filling algorithms for triangle meshes, as pymeshlab MeshSet filters and on arrays.

Importing the package registers the filters as methods of ``pymeshlab.MeshSet``::

    import pymeshlab, meshlab_holefill
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh("scan.ply")
    ms.meshing_close_holes_min_angle_bilateral(maxholesize=500)

and :func:`fill_holes` runs the same pipeline on plain ``(V, F)`` arrays, also where pymeshlab
cannot be imported (the MeshSet entry points then raise ImportError saying why).

Layers, each importing only those before it (a test walks every import and fails on a cycle):

1. ``errors``: the exceptions.
2. ``geometry``: building blocks with two or more users (numpy/scipy).
3. ``core``: holes and their context, patches, parameters, attributes, the per-hole pipeline.
4. ``algorithms``: one subpackage per paper, and the table of filters.
5. ``meshlab``: the only package that imports pymeshlab (registration, MeshSet I/O,
   pymeshlab's doors, ``.mlx`` scripts).
6. ``evaluation``: holes with ground truth, isolated runs, metrics, reports.
7. ``cli``: the ``meshlab-holefill`` command.
"""
from ._version import __version__
from .array_api import algorithm_names, compile_kernels, fill_holes
from .core.holes import HoleContext, boundary_loops, hole_context
from .core.parameters import Percentage
from .core.patch import Patch
from .errors import FilterParameterError, HoleFillError, MeshTopologyError, MlxRunError, MlxScriptError

try:
    from . import meshlab as _meshlab
except ImportError as _exc:  # only a missing pymeshlab is expected here; anything else is a bug to see
    if _exc.name != "pymeshlab" and "pymeshlab" not in str(_exc):
        raise
    PYMESHLAB_ERROR = _exc
else:
    PYMESHLAB_ERROR = None

if PYMESHLAB_ERROR is None:
    from .meshlab import (FILTERS, apply_filter, clear_filter_history, filter_calls, filter_history, filter_list,
                          print_filter_parameter_list)
    from .meshlab.mlx.script import filter_script_xml, read_filter_script, run_filter_script, save_filter_script

    _meshlab.register_all()  # MeshSet methods; ms.apply_filter(name), filter scripts and parameter listing know ours
else:
    FILTERS = {}

    def _needs_pymeshlab(name):
        def unavailable(*args, **kwargs):
            raise ImportError(f"meshlab_holefill.{name} needs pymeshlab, which cannot be imported "
                              f"({PYMESHLAB_ERROR}); meshlab_holefill.fill_holes(V, F, algorithm=...) works without it")

        unavailable.__name__ = name
        return unavailable

    apply_filter, clear_filter_history, filter_calls, filter_history, filter_list, print_filter_parameter_list = (
        _needs_pymeshlab(name) for name in ("apply_filter", "clear_filter_history", "filter_calls",
                                            "filter_history", "filter_list", "print_filter_parameter_list"))
    filter_script_xml, read_filter_script, run_filter_script, save_filter_script = (
        _needs_pymeshlab(name) for name in ("filter_script_xml", "read_filter_script", "run_filter_script",
                                            "save_filter_script"))


def compare(meshes, report=None, **options):
    """Fill holes in meshes with every filler, measure them, and optionally write a report.

    See :func:`meshlab_holefill.evaluation.compare.compare` for the options.
    """
    if PYMESHLAB_ERROR is not None:
        raise ImportError(f"meshlab_holefill.compare needs pymeshlab, which cannot be imported ({PYMESHLAB_ERROR})")
    from .evaluation.compare import compare as run

    return run(meshes, report=report, **options)


def batch(inputs, out, **options):
    """Repair many mesh files on dask (a local cluster or yours): see :func:`meshlab_holefill.batching.batch`.

    Imported on first use, so ``import meshlab_holefill`` does not load dask.
    """
    from .batching import batch as run

    return run(inputs, out, **options)


__all__ = [
    "FILTERS", "FilterParameterError", "HoleContext", "HoleFillError", "MeshTopologyError", "MlxRunError",
    "MlxScriptError", "PYMESHLAB_ERROR", "Patch", "Percentage", "__version__", "algorithm_names", "apply_filter",
    "batch", "boundary_loops", "clear_filter_history", "compare", "compile_kernels", "fill_holes", "filter_calls", "filter_history",
    "filter_list", "filter_script_xml", "hole_context", "print_filter_parameter_list", "read_filter_script",
    "run_filter_script", "save_filter_script",
]
