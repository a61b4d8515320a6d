"""The array API: fill the holes of a mesh given as (V, F) with one algorithm, without pymeshlab."""
from __future__ import annotations

import numpy as np

from .algorithms import ALGORITHMS, find_algorithm
from .core.attributes import MeshArrays
from .core.parameters import resolve_params
from .core.pipeline import COMMON_PARAMS, fill_mesh_holes
from .errors import FilterParameterError

__all__ = ["algorithm_names", "fill_holes"]


def algorithm_names():
    """Short names of the algorithms :func:`fill_holes` takes, in the table's order."""
    return [row.key for row in ALGORITHMS]


def _checked_arrays(V, F):
    """(V, F) as float64 / int64 arrays, or a ValueError naming what is wrong with them."""
    V = np.asarray(V)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3 or not np.issubdtype(V.dtype, np.number):
        raise ValueError(f"V must be an (n, 3) array of coordinates, got shape {V.shape} of {V.dtype}")
    if F.ndim != 2 or F.shape[1] != 3 or (F.size and not np.issubdtype(F.dtype, np.integer)):
        raise ValueError(f"F must be an (m, 3) array of vertex indices, got shape {F.shape} of {F.dtype}")
    if len(F) == 0:
        raise ValueError("the mesh has no faces (a point cloud): there are no holes to fill")
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
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
    try:
        row = find_algorithm(algorithm)
    except ValueError as exc:
        raise FilterParameterError(str(exc)) from None
    V, F = _checked_arrays(V, F)
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
                                     warm_up=getattr(module, "WARM_UP", None))
    return filled.V, filled.F, result
