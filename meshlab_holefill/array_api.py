"""The array API: fill the holes of a mesh given as (V, F) with one algorithm, without pymeshlab."""
from __future__ import annotations

import numpy as np

from .algorithms import ALGORITHMS, find_algorithm
from .core._attribute_kernels import idw_interpolated
from .core.attributes import MeshArrays
from .core.face_grid import load_face_grid_kernels
from .core.kernel_cache import refresh_kernel_cache
from .core.parameters import resolve_params
from .core.pipeline import COMMON_PARAMS, fill_mesh_holes
from .errors import FilterParameterError
from .geometry.dihedral_triangulation import dihedral_triangulation

__all__ = ["algorithm_names", "compile_kernels", "fill_holes", "refresh_kernel_cache"]

#: The option sets :func:`compile_kernels` runs beyond each algorithm's defaults (their own kernels).
COMPILE_OPTION_SETS = (("min_angle_bilateral", (("fairing", "thinplate"), ("iterations", 0), ("smoothing", 10))),)


def algorithm_names():
    """Short names of the algorithms :func:`fill_holes` takes, in the table's order."""
    return [row.key for row in ALGORITHMS]


def _checked_arrays(V, F, face_dtype=np.int64):
    """(V, F) as float64 / ``face_dtype`` arrays, or a ValueError naming what is wrong with them."""
    V = np.asarray(V)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3 or not np.issubdtype(V.dtype, np.number):
        raise ValueError(f"V must be an (n, 3) array of coordinates, got shape {V.shape} of {V.dtype}")
    if F.ndim != 2 or F.shape[1] != 3 or (F.size and not np.issubdtype(F.dtype, np.integer)):
        raise ValueError(f"F must be an (m, 3) array of vertex indices, got shape {F.shape} of {F.dtype}")
    if len(F) == 0:
        raise ValueError("the mesh has no faces (a point cloud): there are no holes to fill")
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=face_dtype)
    if F.min() < 0 or F.max() >= len(V):
        raise ValueError(f"F refers to vertex {int(F.min() if F.min() < 0 else F.max())}, outside 0..{len(V) - 1}")
    if not np.all(np.isfinite(V)):
        bad = int(np.count_nonzero(~np.isfinite(V).all(axis=1)))
        raise ValueError(f"the mesh has {bad} vertices with NaN or infinite coordinates")
    return V, F


def fill_holes(V, F, algorithm="min_angle_bilateral", *, selected_faces=None, **params):
    """Fill the holes of a triangle mesh with one of the four algorithms.

    The same pipeline as the MeshSet filters, on plain arrays (for trimesh, libigl, Open3D
    users, and where pymeshlab is not installed): every boundary loop within ``maxholesize``
    is filled completely or not at all, original vertices and faces are kept bit for bit
    (first, in their order), new vertices and faces follow.

    Parameters
    ----------
    V : (n, 3) float
        Vertex coordinates.
    F : (m, 3) int
        Triangles, consistently oriented.
    algorithm : str
        ``"min_angle_bilateral"`` (Hu et al.), ``"curve_unfolding"`` (Brunton et al.),
        ``"differential_evolution"`` (Xie & Zou, HPDE) or ``"lssvm_poisson"`` (Xu et al.), or the
        filter's python name (``"meshing_close_holes_curve_unfolding"``).
    selected_faces : (m,) bool, optional
        Face selection, used by ``selected=True`` (only holes with a selected border face).
    **params
        The filter's parameters (``maxholesize``, ``selfintersection``, the paper's own...;
        ``meshlab-holefill filters`` lists them), validated as for the MeshSet filter. Lengths
        relative to the mesh are given as :class:`meshlab_holefill.Percentage`.

    Returns
    -------
    V2 : (n2, 3) float64
        ``V`` followed by the new vertices.
    F2 : (m2, 3) int64
        ``F`` followed by the new faces (or, for ``lssvm_poisson``, whose Sec. 3.1 splits long
        border edges, the refined original faces: ``result['split_boundary_edges']`` rows
        after the m originals).
    result : dict
        ``closed_holes``, ``new_faces``, ``new_vertices``, ``skipped_holes``, ``failed_holes``,
        ``seconds`` and ``holes``: one dict per boundary loop with its status (closed,
        skipped, failed) and reason.

    Raises
    ------
    ValueError
        Unknown algorithm; V or F of the wrong shape or type, indices out of range, NaN/inf
        coordinates, no faces; :class:`meshlab_holefill.MeshTopologyError` for non-manifold
        edges; :class:`meshlab_holefill.FilterParameterError` for a bad parameter.

    Examples
    --------
    >>> import numpy as np
    >>> import meshlab_holefill
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 1.0]])
    >>> F = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])   # a pyramid without its base
    >>> V2, F2, result = meshlab_holefill.fill_holes(V, F, "min_angle_bilateral")
    >>> result["closed_holes"], len(F2) > len(F), bool((F2[:4] == F).all())
    (1, True, True)
    """
    return _fill_holes(V, F, algorithm, selected_faces, params, np.int64)


def _fill_holes(V, F, algorithm, selected_faces, params, face_dtype):
    """:func:`fill_holes` with the faces held as ``face_dtype`` (int32: as a pymeshlab MeshSet holds them)."""
    try:
        row = find_algorithm(algorithm)
    except ValueError as exc:
        raise FilterParameterError(str(exc)) from None
    V, F = _checked_arrays(V, F, face_dtype)
    module = row.load()
    own = list(module.PARAMS)
    diagonal = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    resolved = resolve_params(COMMON_PARAMS + own, params, row.filter_name, diagonal)
    selected = np.zeros(len(F), bool) if selected_faces is None else np.asarray(selected_faces, bool).ravel()
    if len(selected) != len(F):
        raise ValueError(f"selected_faces has {len(selected)} entries for {len(F)} faces")
    arrays = MeshArrays(V=V, F=F, face_attrs={"selected": selected.astype(np.float64)[:, None]}, label="mesh")
    filled, result = fill_mesh_holes(arrays, module.fill, resolved, algorithm_params=[p.name for p in own],
                                     rings=module.RINGS, prepare=getattr(module, "PREPARE", None),
                                     warm_up=getattr(module, "WARM_UP", None),
                                     seconds_per_edge=getattr(module, "SECONDS_PER_EDGE", None))
    return filled.V, filled.F, result


def _kernel_example():
    """A wavy 25 x 25 grid with two holes (about 40 and 20 boundary edges): every filter's common paths."""
    from .core.examples import bowl_with_hole

    V, F, _ = bowl_with_hole(n=25, radius=0.45)
    V[:, 2] += 0.05 * np.sin(4.0 * V[:, 0]) * np.cos(3.0 * V[:, 1])
    corner = np.linalg.norm(V[F].mean(axis=1)[:, :2] - [0.7, 0.7], axis=1) > 0.15
    return V, F[corner]


def _compile_one(algorithm, params):
    """Fill the example with one algorithm and option set; the process seconds it took (compiling included).

    The faces go in as int64 (:func:`fill_holes`) and as int32 (a pymeshlab MeshSet's): a
    kernel compiles once per argument type.
    """
    import time

    start = time.process_time()
    V, F = _kernel_example()
    for face_dtype in (np.int64, np.int32):
        _, _, result = _fill_holes(V, F, algorithm, None, dict(params, workers=1), face_dtype)
        if result["closed_holes"] == 0:
            raise RuntimeError(f"{algorithm}: the kernel example closed no hole ({result['holes']})")
        load_face_grid_kernels(face_dtype)  # built before workers fork, which the example does not
    # The jagged-border fallback's programme, which the example's smooth holes never reach, and the
    # interpolation of new vertices' attributes, which the example (no attributes) does not need.
    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    dihedral_triangulation(square, np.tile([0.0, 0.0, 1.0], (4, 1)))
    idw_interpolated(square, square.mean(axis=0, keepdims=True), np.ones((4, 1)))
    return time.process_time() - start


def compile_kernels(processes=None):
    """Compile (or load from numba's on-disk cache) every filter's kernels ahead of first use.

    The filters' compiled kernels (numba, ``cache=True``) are compiled the first time they run
    after an install or an update, which makes that first fill slow; later processes load them
    from the cache. This first drops a cache made from other kernel sources
    (:func:`refresh_kernel_cache`), then runs each algorithm, and the option sets in ``COMPILE_OPTION_SETS``,
    once on a small example mesh, in parallel processes, so that cost is paid here.

    Parameters
    ----------
    processes : int, optional
        Processes compiling at once (default: one per core, at most one per option set).

    Returns
    -------
    dict
        ``"algorithm"`` or ``"algorithm (option=value, ...)"`` -> process seconds it took.

    Examples
    --------
    >>> import meshlab_holefill
    >>> seconds = meshlab_holefill.compile_kernels(processes=1)  # doctest: +SKIP
    >>> sorted(seconds)[0]  # doctest: +SKIP
    'curve_unfolding'
    """
    import multiprocessing
    import os
    from concurrent.futures import ProcessPoolExecutor

    refresh_kernel_cache()
    jobs = [(name, ()) for name in algorithm_names()] + list(COMPILE_OPTION_SETS)
    processes = max(1, min(int(processes or os.cpu_count() or 1), len(jobs)))
    labels = [name + (f" ({', '.join(f'{k}={v}' for k, v in params)})" if params else "") for name, params in jobs]
    if processes == 1:
        return {label: _compile_one(*job) for label, job in zip(labels, jobs)}
    with ProcessPoolExecutor(processes, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(_compile_one, *job) for job in jobs]
        return {label: future.result() for label, future in zip(labels, futures)}
