"""The meshes of a comparison (cases) and their holes with ground truth.

A :class:`MeshCase` is a mesh with the holes to fill given (faces removed from a closed surface,
so the removed faces are the ground truth) or natural; :func:`prepare_case` cuts holes where none
are given and measures what every run is compared against (:class:`PreparedCase`).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..core.holes import boundary_halfedges, boundary_loops
from ..core.outlines import outline_mask, pinch_vertices
from ..geometry.topology import face_adjacency
from ..meshlab.mesh_files import is_mesh, load_mesh, mesh_arrays
from .cut_holes import cut_holes, hole_plan
from .metrics import compact_mesh, corner_quality_bound

__all__ = ["Hole", "MeshCase", "PreparedCase", "as_case", "prepare_case"]


@dataclass
class MeshCase:
    """A mesh to compare fillers on.

    Attributes
    ----------
    name : str
    V : (n, 3) float64, F : (m, 3) int
    analytic : callable, optional
        (N, 3) points -> (N,) distance to the exact surface the mesh samples (sphere, torus).
    removed : (m,) bool, optional
        Faces to remove as holes with ground truth (instead of holes cut at random).
    surface_area : float, optional  area of the analytic surface (Xu et al.'s error normalisation)
    given_class : str  size class of the ``removed`` holes in the report ("given"; the creased cases
        of :mod:`.creased` use "crease" and "crossing")
    """

    name: str
    V: np.ndarray
    F: np.ndarray
    analytic: object = None
    removed: np.ndarray | None = None
    surface_area: float | None = None
    given_class: str = "given"


@dataclass
class Hole:
    """One evaluated hole of a prepared case."""

    index: int  # the hole's number: its boundary loop index, as in `meshlab-holefill holes` and fill results
    size_class: str
    shape: str
    boundary_edges: int
    loop: np.ndarray  # (k,) ordered boundary vertices (indices into the case's V0)
    loop_index: int  # position among boundary_loops(F0), as in our filters' result['holes'] (== index)
    border: tuple  # ((k, 2) int64 half-edges, (k,) int64 faces) in F0
    ground_truth: tuple | None = None  # ((n0 + g, 3), (r, 3)) indexed like a filled mesh
    quality_bound: float = 1.0  # metrics.corner_quality_bound: best reachable minimum quality


@dataclass
class PreparedCase:
    """A case ready to run: the mesh with its holes (V0, F0), the evaluated holes, notes.

    Attributes
    ----------
    name : str
    kind : str  "cut holes", "natural holes" or "given holes"
    V0 : (n0, 3) float64, F0 : (m0, 3) int64  the mesh the fillers get
    diag : float  bounding-box diagonal of the source mesh (per-mille figures)
    holes : list of Hole
    notes : list of str  holes that could not be cut or are not evaluated, and why
    analytic, surface_area : as in MeshCase
    source_faces : int  faces of the source mesh before holes were cut
    """

    name: str
    kind: str  # "cut holes" | "natural holes" | "given holes"
    V0: np.ndarray
    F0: np.ndarray
    diag: float
    holes: list
    notes: list = field(default_factory=list)
    analytic: object = None
    surface_area: float | None = None
    source_faces: int = 0

    def summary(self):
        return {"case": self.name, "kind": self.kind, "vertices": int(len(self.V0)), "faces": int(len(self.F0)),
                "source_faces": self.source_faces, "bbox_diagonal": self.diag, "notes": list(self.notes),
                "holes": [{"hole": h.index, "size_class": h.size_class, "shape": h.shape,
                           "boundary_edges": h.boundary_edges, "ground_truth": h.ground_truth is not None,
                           "quality_bound": h.quality_bound}
                          for h in self.holes]}


def as_case(mesh, index=0):
    """A MeshCase from a path, pymeshlab.Mesh (or MeshSet: its current mesh), (V, F) tuple or MeshCase.

    Parameters
    ----------
    mesh : str, os.PathLike, pymeshlab.Mesh, pymeshlab.MeshSet, ((n, 3) float, (m, 3) int) or MeshCase
    index : int  names an unnamed mesh ``mesh{index}``

    Returns
    -------
    MeshCase
    """
    if isinstance(mesh, MeshCase):
        return mesh
    if isinstance(mesh, (str, os.PathLike)):
        V, F = load_mesh(mesh)
        return MeshCase(os.path.basename(str(mesh)), V, F)
    if isinstance(mesh, tuple) and len(mesh) == 2:
        return MeshCase(f"mesh{index}", np.asarray(mesh[0], np.float64), np.asarray(mesh[1], np.int64))
    if is_mesh(mesh):
        return MeshCase(f"mesh{index}", *mesh_arrays(mesh))
    raise TypeError(f"cannot compare on {type(mesh).__name__}: give a path, (V, F), pymeshlab.Mesh or MeshCase")


def _with_ground_truth(V, F, removed_groups):
    """Mesh without the removed faces, and each removed group as ground truth indexed like a fill.

    Parameters
    ----------
    removed_groups : list of (r_i,) int  face indices into F, one group per hole

    Returns
    -------
    V0 (n0, 3), F0 (m0, 3), truths: list of ((n0 + g, 3) float64, (r, 3) int64)
    """
    keep = np.ones(len(F), bool)
    for group in removed_groups:
        keep[group] = False
    V0, F0 = compact_mesh(V, F[keep])
    used = np.unique(F[keep].ravel())
    truths = []
    for group in removed_groups:
        faces = F[group]
        remap = np.full(len(V), -1, np.int64)
        remap[used] = np.arange(len(used))
        interior = np.setdiff1d(np.unique(faces.ravel()), used)
        remap[interior] = len(V0) + np.arange(len(interior))
        truths.append((np.concatenate([V0, V[interior]]), remap[faces]))
    return V0, F0, truths


def _match_loops(F0, vertex_sets):
    """For each vertex set, the boundary loop of F0 lying in it (index, loop) or (-1, None)."""
    loops = boundary_loops(F0)
    out = []
    for verts in vertex_sets:
        found = (-1, None)
        for i, lp in enumerate(loops):
            if lp.closed and np.isin(lp.vertices, verts).all():
                found = (i, lp)
                break
        out.append(found)
    return out, loops


def _border(F0, he, hf, loop):
    mask = np.isin(he, loop).all(axis=1)
    return he[mask], hf[mask]


def prepare_case(case, holes=4, sizes=("small", "medium", "large"), seed=0, maxholesize=1000):
    """Holes with ground truth cut into a closed mesh, or the natural holes of an open one.

    Parameters
    ----------
    case : MeshCase
    holes : int  holes to cut into a closed mesh (sizes cycle, compact and irregular shapes alternate)
    sizes : sequence of str  keys of cut_holes.SIZE_CLASSES
    seed : int
    maxholesize : int  natural holes with more boundary edges are not evaluated

    Returns
    -------
    PreparedCase
    """
    V, F = np.asarray(case.V, np.float64), np.asarray(case.F, np.int64)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    notes = []
    if case.removed is not None or not len(boundary_loops(F)):
        if case.removed is not None:
            kind = "given holes"
            removed = np.flatnonzero(np.asarray(case.removed, bool))
            if not len(removed):
                raise ValueError(f"case '{case.name}': removed marks no face, so it has no hole to fill")
            _, label = connected_components(face_adjacency(F[removed]), directed=False)
            groups = [removed[label == c] for c in np.unique(label)]
            specs = [(case.given_class, "given", None) for _ in groups]
        else:
            kind = "cut holes"
            plan = hole_plan(holes, sizes)
            _, cut = cut_holes(V, F, sizes=[s for s, _ in plan], shapes=[sh for _, sh in plan], seed=seed,
                               strict=False)
            if len(cut) < len(plan):
                got, missing = [(h.size_class, h.shape) for h in cut], []
                for wanted in plan:
                    if wanted in got:
                        got.remove(wanted)
                    else:
                        missing.append(wanted)
                notes.append("could not cut " + ", ".join(f"{s} {sh}" for s, sh in missing)
                             + " hole(s) (no room for a simple hole of that size)")
            groups = [h.face_indices for h in cut]
            specs = [(h.size_class, h.shape, h.boundary_edges) for h in cut]
        V0, F0, truths = _with_ground_truth(V, F, groups)
        vertex_sets = [np.unique(t[1])[np.unique(t[1]) < len(V0)] for t in truths]
        matches, _ = _match_loops(F0, vertex_sets)
        he, hf = boundary_halfedges(F0)
        out = []
        for (size, shape, _), truth, (li, lp) in zip(specs, truths, matches):
            if lp is None:
                notes.append(f"a {size} hole did not leave a simple boundary loop; left out")
                continue
            out.append(Hole(li, size, shape, len(lp), lp.vertices, li, _border(F0, he, hf, lp.vertices),
                            truth, corner_quality_bound(V0, F0, lp.vertices)))
        out.sort(key=lambda h: h.index)  # numbered and listed as `meshlab-holefill holes` lists the loops
    else:
        kind = "natural holes"
        V0, F0 = V, F
        loops = boundary_loops(F0)
        he, hf = boundary_halfedges(F0)
        measurable = [i for i, lp in enumerate(loops) if lp.closed and len(lp) >= 3]
        outline = dict(zip(measurable, outline_mask(V0, F0, [loops[i] for i in measurable],
                                                     pinch_vertices(loops, len(V0)))))
        out = []
        for i, lp in enumerate(loops):
            if not lp.closed or lp.pinched or len(lp) < 3 or len(lp) > maxholesize:
                why = ("open chain" if not lp.closed else "pinched (non-manifold vertex)" if lp.pinched
                       else f"{len(lp)} edges > maxholesize {maxholesize}" if len(lp) > maxholesize else "degenerate")
                notes.append(f"boundary loop {i} ({len(lp)} edges) not evaluated: {why}")
                continue
            # An island's outline is listed apart: capping it folds over the island (outlines.outline_mask).
            kind_of = "outline" if outline[i] else "natural"
            out.append(Hole(i, kind_of, kind_of, len(lp), lp.vertices, i,
                            _border(F0, he, hf, lp.vertices), None, corner_quality_bound(V0, F0, lp.vertices)))
    return PreparedCase(case.name, kind, V0, F0, diag, out, notes, case.analytic, case.surface_area, len(F))
