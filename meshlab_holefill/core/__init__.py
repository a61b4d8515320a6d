"""The filter contract on arrays: holes and their context, patches, parameters, attributes, the pipeline.

Imports ``errors`` and ``geometry`` only (no pymeshlab). Modules:

- ``holes``: boundary loops (vectorised), :class:`HoleContext`, island outlines, per-hole measures.
- ``patch``: :class:`Patch` (new vertices and faces in loop-local numbering), validation, merge.
- ``parameters``: :class:`ParamSpec`, :func:`resolve_params`, :class:`Percentage`.
- ``attributes``: :class:`MeshArrays`, attributes of new elements and of refined borders.
- ``crossings``: patches against the mesh near them, against each other, at shared vertices.
- ``failure_reasons``: what a failed hole's reason adds about the mesh (an island's outline, folds beside it).
- ``least_bend``: the loop's least-bend triangulations, the filters' shared fallback for jagged borders.
- ``blas_threads``: one OpenBLAS thread inside a block (LS-SVM's fills, the processes ``parallel`` forks).
- ``parallel``: holes filled by this process and forked children at once, with a time limit per hole.
- ``content_key``: a digest of arrays' contents, the key of work kept for the same input.
- ``kernel_cache``: numba's on-disk kernels dropped when the package's kernel sources change.
- ``pipeline``: :func:`fill_mesh_holes`, what every filter does around its algorithm.
"""
from .attributes import MeshArrays
from .holes import BoundaryLoop, HoleContext, boundary_loops, hole_context
from .outlines import hole_measures
from .parameters import ParamSpec, Percentage, resolve_params
from .patch import Patch, merge_patches, validate_patch
from .pipeline import COMMON_PARAMS, FilledMesh, fill_mesh_holes

__all__ = ["BoundaryLoop", "COMMON_PARAMS", "FilledMesh", "HoleContext", "MeshArrays", "ParamSpec", "Patch",
           "Percentage", "boundary_loops", "fill_mesh_holes", "hole_context", "hole_measures", "merge_patches",
           "resolve_params", "validate_patch"]
