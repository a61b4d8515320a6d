"""Open third-party hole fillers as anchors of the comparison: CGAL's Liepa fill and PyMeshFix.

Both are optional (the ``bench`` extra installs them) and imported only inside the worker that
runs them, so the evaluation layer works without them; a filler whose package is missing is
skipped with a note in the report (:func:`missing_package`).

- ``cgal_liepa``: CGAL's ``Polygon_mesh_processing::triangulate_refine_and_fair_hole``
  (Liepa 2003: minimum-dihedral/area triangulation of the hole, refinement to the surrounding
  density, fairing of the new vertices), from the PyPI package ``cgal`` (CGAL's SWIG bindings,
  ``CGAL.CGAL_Polygon_mesh_processing``). CGAL fills one hole per call: it is called once per
  boundary loop, holes with more than ``maxholesize`` edges left open, so every hole has its own
  time and status as with our filters. Parameters: ``density`` (CGAL's density control factor,
  default sqrt(2)) and ``continuity`` (fairing continuity 0, 1 or 2; default 1, CGAL's).
- ``pymeshfix``: MeshFix (Attene 2010) from the PyPI package ``pymeshfix``. Its hole filler,
  ``PyTMesh.fill_small_boundaries`` (triangulate each boundary loop, then refine and fair the
  new triangles), is called once on the whole mesh: MeshFix cannot be told which hole to fill,
  so the per-hole rows share one run time (seconds per hole = run time / holes) and have no
  per-hole status beyond open or closed; the patches themselves are made hole by hole, each from
  its own loop, so the per-hole distances and qualities mean the same as for the other fillers.
  ``mode="repair"`` runs MeshFix's whole repair instead (fill, keep the largest component,
  remove self-intersections and degenerate faces): it may delete or move original faces, which
  the report counts as ``originals_changed``.

MeshFix renumbers the mesh, so its output is mapped back (:func:`map_back`): vertices by their
exact coordinates (MeshFix keeps original coordinates bit for bit), original faces by their
vertex triples; what remains is new. The reply then has the originals first, as our filters
return them, and every per-hole metric is computed the same way for all fillers.
"""
from __future__ import annotations

import importlib.util
import time

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..core.holes import boundary_loops

__all__ = ["ANCHORS", "cgal_fill", "is_anchor", "map_back", "missing_package", "pymeshfix_fill", "run_anchor",
           "split_nonmanifold_vertices"]

# name -> (module to import, PyPI package, description)
ANCHORS = {
    "cgal_liepa": ("CGAL", "cgal", "CGAL triangulate_refine_and_fair_hole (Liepa), one call per hole"),
    "pymeshfix": ("pymeshfix", "pymeshfix", "MeshFix fill_small_boundaries, one call for the whole mesh"),
}


def is_anchor(name):
    """Is ``name`` one of the third-party fillers (:data:`ANCHORS`)?"""
    return name in ANCHORS


def missing_package(name):
    """Why anchor ``name`` cannot run here (its package is not installed), or None when it can.

    Returns
    -------
    str or None
    """
    module, package, _ = ANCHORS[name]
    if importlib.util.find_spec(module) is None:
        return (f"package '{package}' not installed: {name} skipped (pip install {package}, "
                "or the package's 'bench' extra)")
    return None


def split_nonmanifold_vertices(F, n):
    """Give each fan of faces around a vertex its own vertex (pinched and bow-tie vertices split).

    Two corners of a vertex are in one fan when their faces share an edge at that vertex.

    Parameters
    ----------
    F : (m, 3) int  faces over vertices 0..n-1
    n : int  number of vertices

    Returns
    -------
    F_split : (m, 3) int64  the same faces; a vertex's second and later fans use new indices n, n+1, ...
    origin : (n + s,) int64  the original vertex of every vertex of F_split
    """
    F = np.asarray(F, np.int64)
    m = len(F)
    corner = np.arange(3 * m).reshape(m, 3)
    # Half-edge (a -> b) of face f is corners (f, i) -> (f, i+1); its twin (b -> a) of face g.
    a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
    ca, cb = corner.ravel(), np.roll(corner, -1, axis=1).ravel()
    key = a * n + b
    twin_key = b * n + a
    order = np.argsort(key)
    pos = np.clip(np.searchsorted(key[order], twin_key), 0, len(key) - 1)
    has = key[order][pos] == twin_key
    j = order[pos][has]
    i = np.flatnonzero(has)
    # corner of a in face i ~ corner of a in the twin's face (where the twin ends), likewise for b
    rows = np.concatenate([ca[i], cb[i]])
    cols = np.concatenate([cb[j], ca[j]])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(3 * m, 3 * m))
    _, label = connected_components(graph, directed=False)
    vertex = F.ravel()
    # one index per (vertex, fan); the first fan of each vertex keeps the vertex's own index
    pairs, inverse = np.unique(np.stack([vertex, label], axis=1), axis=0, return_inverse=True)
    first = np.ones(len(pairs), bool)
    first[1:] = pairs[1:, 0] != pairs[:-1, 0]
    new_index = np.where(first, pairs[:, 0], n + np.cumsum(~first) - 1)
    origin = np.concatenate([np.arange(n), pairs[~first, 0]]).astype(np.int64)
    return new_index[inverse.ravel()].reshape(m, 3).astype(np.int64), origin


def map_back(V0, F0, V_out, F_out):
    """Renumber a repaired mesh so that the original vertices and faces come first, as they were.

    Parameters
    ----------
    V0 : (n, 3) float64, F0 : (m, 3) int  the mesh given to the third-party filler
    V_out : (p, 3) float, F_out : (q, 3) int  what it returned, in its own numbering

    Returns
    -------
    V1 : (n + g, 3) float64  V0, then the g output vertices at coordinates no original vertex has
    F1 : (m + h, 3) int64  F0, then the h output faces that are not original faces (same orientation)
    info : dict  ``originals_removed`` (original faces missing from the output, with either
        orientation) and ``vertices_dropped`` (original vertices missing from the output)
    """
    V0, F0 = np.asarray(V0, np.float64), np.asarray(F0, np.int64)
    V_out, F_out = np.asarray(V_out, np.float64), np.asarray(F_out, np.int64)
    if len(V_out):
        d, idx = cKDTree(V0).query(V_out) if len(V0) else (np.full(len(V_out), np.inf), np.zeros(len(V_out), int))
    else:
        d, idx = np.zeros(0), np.zeros(0, np.int64)
    original = d == 0.0
    new = np.flatnonzero(~original)
    index = np.where(original, idx, -1)
    index[new] = len(V0) + np.arange(len(new))
    F_mapped = index[F_out] if len(F_out) else np.zeros((0, 3), np.int64)

    def canonical(F):  # rotate each face so its smallest index comes first (keeps orientation)
        F = np.asarray(F, np.int64).reshape(-1, 3)
        k = np.argmin(F, axis=1)
        return np.stack([F[np.arange(len(F)), (k + s) % 3] for s in range(3)], axis=1)

    width = max(len(V0) + len(new), 1)

    def keys(F):
        C = canonical(F)
        return (C[:, 0] * width + C[:, 1]) * width + C[:, 2]

    k0, k_out = keys(F0), keys(F_mapped)
    is_original = np.isin(k_out, k0)
    kept = np.isin(k0, k_out) | np.isin(keys(F0[:, ::-1]), k_out)
    used = np.zeros(len(V0), bool)
    used[F_mapped[F_mapped < len(V0)]] = True
    info = {"originals_removed": int(np.count_nonzero(~kept)),
            "vertices_dropped": int(np.count_nonzero(~np.isin(np.arange(len(V0)), idx[original])))}
    return (np.concatenate([V0, V_out[new]]), np.concatenate([F0, F_mapped[~is_original]]), info)


def _polyhedron(V, F):
    """A CGAL Polyhedron_3 of the mesh, vertex ids set to the row indices of V."""
    from CGAL.CGAL_Kernel import Point_3
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3, Polyhedron_modifier

    modifier = Polyhedron_modifier()
    modifier.begin_surface(len(V), len(F))
    for p in V.tolist():
        modifier.add_vertex(Point_3(*p))
    for f in F.tolist():
        modifier.begin_facet()
        for i in f:
            modifier.add_vertex_to_facet(i)
        modifier.end_facet()
    modifier.end_surface()
    P = Polyhedron_3()
    P.delegate(modifier)
    if P.size_of_facets() != len(F) or P.size_of_vertices() != len(V):
        raise RuntimeError(f"CGAL's polyhedron builder refused the mesh ({P.size_of_facets()} of {len(F)} faces "
                           "built): non-manifold or inconsistently oriented faces")
    for i, v in enumerate(P.vertices()):
        v.set_id(i)
    return P


def _cycle_length(h, limit):
    """Half-edges in the border cycle of ``h`` (counting stops past ``limit``)."""
    count, g = 1, h.next()
    while g != h and count <= limit:
        g = g.next()
        count += 1
    return count


def cgal_fill(V, F, maxholesize=1000, density=2 ** 0.5, continuity=1):
    """Fill every boundary loop with CGAL's ``triangulate_refine_and_fair_hole``, one call per loop.

    Pinched vertices are split first (CGAL's polyhedron holds only manifold meshes: one vertex per
    fan of faces) and mapped back afterwards; the loops are those of
    :func:`core.holes.boundary_loops`. A loop pinched at a vertex with another one fails: with the
    vertex split by fans, CGAL's border cycle there runs through both loops (the two pairings of
    border edges at a pinched vertex are equally valid; ours keeps each loop simple).

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    maxholesize : int  loops with at least this many edges are left open (as MeshLab's parameter)
    density : float  CGAL's density_control_factor (sqrt(2) by default, CGAL's own)
    continuity : int  CGAL's fairing_continuity: 0, 1 (default) or 2

    Returns
    -------
    V1 : (n + g, 3) float64  originals first
    F1 : (m + h, 3) int64  originals first
    result : dict  ``holes``: one dict per loop (``hole`` its index among boundary_loops(F),
        ``boundary_edges``, ``status`` closed/skipped/failed, ``reason``, ``seconds``,
        ``new_vertices``, ``new_faces``), ``closed_holes``, ``failed_holes``
    """
    from CGAL import CGAL_Polygon_mesh_processing as PMP

    if int(continuity) not in (0, 1, 2):
        raise ValueError(f"continuity must be 0, 1 or 2, got {continuity}")
    if not float(density) > 0:
        raise ValueError(f"density must be positive, got {density}")
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    n = len(V)
    F_split, origin = split_nonmanifold_vertices(F, n)
    P = _polyhedron(V[origin], F_split)
    border = {}
    for h in P.halfedges():
        if h.is_border():
            border[(int(origin[h.opposite().vertex().id()]), int(origin[h.vertex().id()]))] = h
    loops = boundary_loops(F)
    holes, new_V, new_F = [], [], []
    next_id = len(origin)
    for index, lp in enumerate(loops):
        entry = {"hole": index, "boundary_edges": len(lp)}
        holes.append(entry)
        if not lp.closed or len(lp) < 3:
            entry.update(status="failed", reason="not a closed loop")
            continue
        if len(lp) >= maxholesize:
            entry.update(status="skipped", reason=f"{len(lp)} edges >= maxholesize {maxholesize}")
            continue
        # the loop's first edge (loops run in patch orientation, as CGAL's border half-edges)
        a, b = int(lp.vertices[0]), int(lp.vertices[1])
        start = border.get((a, b), border.get((b, a)))
        if start is None or not start.is_border():
            entry.update(status="failed", reason="loop not found in CGAL's polyhedron")
            continue
        if _cycle_length(start, len(lp)) != len(lp):
            # At a pinched vertex CGAL's halfedge mesh pairs the border edges by fans, which joins this
            # loop with the one it touches into a single border cycle: not the hole this row is about.
            entry.update(status="failed", reason="pinched loop: CGAL's halfedge mesh joins it with the loop it "
                                                 "touches")
            continue
        faces_out, vertices_out = [], []
        t0 = time.perf_counter()
        PMP.triangulate_refine_and_fair_hole(P, start, faces_out, vertices_out, float(density), int(continuity))
        entry["seconds"] = time.perf_counter() - t0
        if not faces_out:
            entry.update(status="failed", reason="CGAL returned no triangle")
            continue
        for v in vertices_out:
            v.set_id(next_id)
            new_V.append([v.point().x(), v.point().y(), v.point().z()])
            next_id += 1
        for f in faces_out:
            h = f.halfedge()
            tri = [h.vertex().id(), h.next().vertex().id(), h.next().next().vertex().id()]
            new_F.append(tri)
        entry.update(status="closed", new_vertices=len(vertices_out), new_faces=len(faces_out))
    # split vertices map back to their originals; new vertices follow the originals
    to_final = np.concatenate([origin, n + np.arange(len(new_V))]).astype(np.int64)
    F_new = to_final[np.asarray(new_F, np.int64).reshape(-1, 3)]
    V1 = np.concatenate([V, np.asarray(new_V, np.float64).reshape(-1, 3)])
    result = {"holes": holes, "closed_holes": sum(e.get("status") == "closed" for e in holes),
              "failed_holes": sum(e.get("status") == "failed" for e in holes)}
    return V1, np.concatenate([F, F_new]), result


def pymeshfix_fill(V, F, maxholesize=1000, refine=True, mode="fill"):
    """Fill the holes with MeshFix (``pymeshfix``) and map its output back to the original numbering.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    maxholesize : int  loops with at least this many edges are left open (MeshFix's ``nbe`` = maxholesize - 1)
    refine : bool  MeshFix's refinement (and fairing) of the new triangles
    mode : "fill" or "repair"
        ``fill``: ``fill_small_boundaries`` only; ``repair``: MeshFix's whole repair
        (``MeshFix.repair``: fill, keep the largest component, remove intersections and degeneracies).

    Returns
    -------
    V1, F1 : as :func:`map_back` (originals first)
    result : dict  ``closed_holes`` (MeshFix's count), ``originals_removed``, ``vertices_dropped``,
        ``mode``; no per-hole entries (MeshFix fills all holes in one call)
    """
    import pymeshfix

    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    if mode not in ("fill", "repair"):
        raise ValueError(f"mode must be 'fill' or 'repair', got {mode!r}")
    nbe = max(int(maxholesize) - 1, 1)
    if mode == "fill":
        mesh = pymeshfix.PyTMesh()
        mesh.set_quiet(True)
        mesh.load_array(V, F.astype(np.int32))
        closed = int(mesh.fill_small_boundaries(nbe, bool(refine)))
        V_out, F_out = mesh.return_arrays()
    else:
        fix = pymeshfix.MeshFix(V, F.astype(np.int32))
        fix.repair()
        V_out, F_out = fix.points, fix.faces
        closed = None
    V1, F1, info = map_back(V, F, V_out, F_out)
    return V1, F1, {"closed_holes": closed, "mode": mode, **info}


_FILLERS = {"cgal_liepa": cgal_fill, "pymeshfix": pymeshfix_fill}


def run_anchor(name, V, F, params):
    """Run anchor ``name`` on arrays (in the worker).

    Parameters
    ----------
    name : str  a key of :data:`ANCHORS`
    V : (n, 3) float64, F : (m, 3) int
    params : dict  the filler's keyword parameters (``maxholesize`` and its own)

    Returns
    -------
    V1 : (n + g, 3) float64, F1 : (m + h, 3) int64  originals first
    result : dict
    """
    if name not in _FILLERS:
        raise ValueError(f"unknown third-party filler '{name}' (known: {', '.join(_FILLERS)})")
    return _FILLERS[name](V, F, **params)
