"""What a boundary loop is and how large: an island's outline or a hole, and its measures.

A loop that outlines its whole connected component (an island of a range scan, a lone
triangle, a scan's own rim) is not a hole: capping it would fold a second sheet over the
island, so the filters refuse it (:func:`loop_class`). The per-hole entries of a filter's
result (:func:`hole_measures`) are here too.

Components are the faces joined through shared vertices, except at a vertex where two
boundary loops meet (:func:`pinch_vertices`: two fans touching at a point, as a range scan's
fragments touch its sheet), where only faces sharing an edge are joined: a fragment held to the
rest by such a point is a component of its own.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit

from ..geometry.quality import cross_rows

__all__ = ["loop_measures", "SHEET_RATIO", "FACING_AWAY", "outline_ratios", "outline_mask", "loop_facings",
           "outline_budgets", "pinch_vertices", "vector_area", "outlines_one_face", "loop_class", "loop_classes",
           "loops_measured", "is_outline", "outline_ratio", "hole_measures", "holes_measures"]


def loop_measures(points):
    """Perimeter, diameter and planarity of a closed polyline.

    Parameters
    ----------
    points : (k, 3) float64

    Returns
    -------
    dict with ``perimeter``, ``diameter`` (largest vertex distance, O(k^2) only up to
    2000 vertices, else the bounding-box diagonal) and ``planarity`` (RMS distance to the
    best-fitting plane divided by the diameter; 0 for a planar loop).
    """
    from ..geometry.pca import fit_plane
    from ..geometry.triangulate import polygon_perimeter

    P = np.asarray(points, dtype=np.float64)
    perimeter = polygon_perimeter(P)
    diameter = _diameter(P)
    _, _, w, _ = fit_plane(P)
    planarity = float(np.sqrt(max(w[0], 0.0)) / diameter) if diameter > 0 else 0.0
    return {"edges": len(P), "perimeter": perimeter, "diameter": diameter, "planarity": planarity}


SHEET_RATIO = 0.5  # the share of its component's area an outline encloses at least
FACING_AWAY = -0.5  # the facing (:func:`loop_facings`) of an outline at most


def pinch_vertices(loops, n):
    """Vertices where two or more boundary loops meet, (n,) bool: fans that touch at a point.

    Parameters
    ----------
    loops : sequence of BoundaryLoop or (k,) int arrays  every boundary loop of the mesh
    n : int  number of vertices
    """
    if not len(loops):
        return np.zeros(n, bool)
    every = np.concatenate([np.asarray(getattr(loop, "vertices", loop), np.int64) for loop in loops])
    return np.bincount(every, minlength=n) > 1


def loop_facings(V, F, loops):
    """How each loop's border faces face against a patch closing it: a cosine, (len(loops),) float.

    The cosine of the angle between the loop's vector area, taken in the orientation a patch
    would have, and the sum of its border faces' area vectors (a face once per border edge it
    holds). Round a hole the surface goes on the way the patch would (near 1). A loop with the
    surface inside it, the rim of a sheet or of a fragment, has its border faces turned against
    the patch (near -1): the patch would fold back over them. 0 for a loop of no vector area.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    loops : sequence of BoundaryLoop  closed

    Returns
    -------
    (len(loops),) float
    """
    if not len(loops):
        return np.zeros(0)
    V = np.asarray(V, np.float64)
    k = np.array([len(loop.vertices) for loop in loops])
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    owner = np.repeat(np.arange(len(loops)), k)
    P = V[np.concatenate([np.asarray(loop.vertices, np.int64) for loop in loops])]  # (K, 3) loop after loop
    following = np.arange(len(P)) + 1
    following[first + k - 1] = first
    R = P - P[first][owner]  # relative to each loop's first point, as vector_area takes them
    area = np.add.reduceat(cross_rows(R, R[following]), first)  # (L, 3)
    border = np.asarray(F)[np.concatenate([np.asarray(loop.border_faces, np.int64) for loop in loops])]  # (K, 3)
    normals = cross_rows(V[border[:, 1]] - V[border[:, 0]], V[border[:, 2]] - V[border[:, 0]])
    faces = np.add.reduceat(normals, first)
    dot = np.einsum("ij,ij->i", area, faces)
    norms = np.linalg.norm(area, axis=1) * np.linalg.norm(faces, axis=1)
    return np.where(norms > 0, dot / np.where(norms > 0, norms, 1.0), 0.0)


def outline_budgets(enclosed, facings):
    """The largest component area each loop outlines: its vector area over :data:`SHEET_RATIO`; -1 for a hole.

    A loop outlines its component when the surface lies inside it, so that a patch would fold back
    over the faces along it (facing at most :data:`FACING_AWAY`, :func:`loop_facings`), and it
    encloses at least half of the component's area: an island's outline encloses about all of it
    (face000.ply's 78-125 %), the rim of a curved sheet less (a range scan's outer rim: face000.ply's
    74 %, the virtual scans' 62-73 %). A hole has the surface going on beyond it, the way its
    patch would face; where its border faces turn away (a hole round the end of a bone, whose
    loop twists) it encloses a small share of its surface (at most 24 % in the measured cases).
    Over the holes and outlines of the benchmark's cases and ``scripts/unseen_holes.py``'s groups
    (seeds 1-6; range scans 1-4: 658 loops), every island outline faces at most -0.95 and every
    loop facing away in the range scans encloses 60 % or more. A loop facing the patch's way is
    a hole however much it encloses: a small fragment round a hole (a ring of seen faces round an
    unseen patch of a range scan) holds less area than the hole it surrounds.

    Parameters
    ----------
    enclosed : (L,) float  the loops' vector areas
    facings : (L,) float  :func:`loop_facings`

    Returns
    -------
    (L,) float
    """
    enclosed = np.asarray(enclosed, np.float64)
    return np.where(np.asarray(facings) <= FACING_AWAY, enclosed / SHEET_RATIO, -1.0)


def outline_ratios(V, F, loops, pinch=None):
    """How much of its connected component each loop encloses: |vector area| / component area.

    A loop that outlines a whole fragment (an island of a range scan, a lone triangle) encloses
    about as much area as the fragment has (ratio ~1, more for a fragment with holes of its
    own); capping it would fold a second sheet over the fragment, so it is not a hole. Real
    holes enclose a small share of their component (a hemisphere's rim, the worst case of a
    fillable hole, gives 0.5). On face000.ply the island outlines enclose 0.78-1.25 and the holes
    at most 0.46; :func:`outline_budgets` says which loops are outlines. The component of a loop is
    that of its border faces (all of them, where the loop runs through a pinch vertex between two).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    loops : sequence of BoundaryLoop or (k,) int arrays (with ``border_faces``)
    pinch : (n,) bool, optional  :func:`pinch_vertices` (default: of ``loops``)

    Returns
    -------
    (len(loops),) float
    """
    from scipy.sparse.csgraph import connected_components

    from ..geometry.quality import face_areas
    from ..geometry.topology import face_adjacency

    n, m = len(V), len(F)
    F = np.asarray(F, np.int64)
    if pinch is None:
        pinch = pinch_vertices(loops, n)
    # Nodes: the vertices, then the faces; a face joins its corners but pinch vertices, and the
    # faces it shares an edge with.
    corners = ~pinch[F].ravel()
    adjacent = face_adjacency(F).tocoo()
    rows = np.concatenate([np.repeat(n + np.arange(m), 3)[corners], n + adjacent.row])
    cols = np.concatenate([F.ravel()[corners], n + adjacent.col])
    graph = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n + m, n + m))
    _, label = connected_components(graph, directed=False)
    face_label = label[n:]
    component_area = np.bincount(face_label, weights=face_areas(V, F), minlength=label.max() + 1)
    ratios = np.zeros(len(loops))
    for i, loop in enumerate(loops):
        ids = np.asarray(getattr(loop, "vertices", loop), np.int64)
        area = component_area[np.unique(face_label[np.asarray(loop.border_faces, np.int64)])].sum()
        ratios[i] = vector_area(V[ids]) / area if area > 0 else np.inf
    return ratios


def outline_mask(V, F, loops, pinch=None):
    """Which loops outline their component, (len(loops),) bool: :func:`outline_budgets` on :func:`outline_ratios`,
    labelling the whole mesh; :func:`loop_classes` grows from the loops instead.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    loops : sequence of BoundaryLoop  closed, of at least 3 vertices
    pinch : (n,) bool, optional  :func:`pinch_vertices` of every loop of the mesh (default: of ``loops``)
    """
    return (loop_facings(V, F, loops) <= FACING_AWAY) & (outline_ratios(V, F, loops, pinch) >= SHEET_RATIO)


def vector_area(points):
    """Area enclosed by a closed polyline: the norm of its vector area (exact for a planar loop).

    Parameters
    ----------
    points : (k, 3) float

    Returns
    -------
    float
    """
    P = np.asarray(points, np.float64)
    # Relative to a vertex of the loop (the vector area of a closed loop does not depend on the
    # origin): far from the origin the products of raw coordinates cancel to noise (at 1e8 from
    # it a 1-unit mesh had every hole taken for an island outline).
    P = P - P[:1]
    # cross_rows: np.cross's arithmetic (the same bits) without its axis handling, 0.3 ms a call here
    return float(0.5 * np.linalg.norm(cross_rows(P, np.roll(P, -1, axis=0)).sum(axis=0)))


def outlines_one_face(loop):
    """Whether a 3-edge loop runs round one face (a triangle attached by its corners only, or alone).

    Its one triangulation is that face again, reversed: a duplicate face that no crossing test
    sees (it crosses nothing, it coincides). The filters refuse such a loop, and report it as an
    outline: it outlines its whole edge-connected component, the face.
    """
    return len(loop) == 3 and loop.closed and len(np.unique(loop.border_faces)) == 1


def loop_class(V, F, loop, incidence, pinch=None):
    """'outline' for a loop round one face (:func:`outlines_one_face`) or its whole component
    (:func:`is_outline`), else 'hole'."""
    return "outline" if outlines_one_face(loop) or is_outline(V, F, loop, incidence, pinch) else "hole"


# A growth of :func:`loop_classes` that has seen more than this share of the mesh's faces stops: the
# mesh's components are then labelled at once (:func:`_component_areas`, a union-find over the faces and
# their corners), where the growth's reads of the incidence rows cost about ten times as much a face.
GROWTH_SHARE = 1 / 64


def loop_classes(V, F, loops, incidence, enclosed=None, growth_cap=None, pinch=None):
    """:func:`loop_class` of many loops at once: the components grown in one compiled call.

    A loop that outlines a large component (a range scan's outer rim) would have its growth read
    the whole component's incidence rows: such a growth stops after ``growth_cap`` faces and the
    loop is decided on the area of its component in a labelling of the whole mesh. The answer is
    the growth's, but for the order in which the component's face areas are added up (a loop
    whose component area equals its budget to the last bits could go either way). On
    face000.ply (166k faces, 45 loops, its outer rim among them) 31 -> 8 ms; the same scan
    midpoint-subdivided to 2.66M faces 625 -> 105 ms.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    loops : sequence of BoundaryLoop  closed, of at least 3 vertices
    incidence : (n, m) sparse  :func:`.holes.vertex_face_incidence` of (F, n)
    enclosed : (len(loops),) float, optional  their vector areas (:func:`hole_measures`' ``area``)
    growth_cap : int, optional  faces a growth may see (default :data:`GROWTH_SHARE` of the mesh's)
    pinch : (n,) bool, optional  :func:`pinch_vertices` of every loop of the mesh (default: of ``loops``)

    Returns
    -------
    list of str  'outline' or 'hole', per loop
    """
    if not len(loops):
        return []
    if enclosed is None:
        enclosed = [vector_area(V[np.asarray(loop.vertices, np.int64)]) for loop in loops]
    if growth_cap is None:
        growth_cap = int(GROWTH_SHARE * len(F))
    V = np.asarray(V, np.float64)
    F = np.asarray(F)
    if pinch is None:
        pinch = pinch_vertices(loops, len(V))
    budgets = outline_budgets(enclosed, loop_facings(V, F, loops))
    starts = [np.unique(np.asarray(loop.border_faces, np.int64)) for loop in loops]
    offsets = np.cumsum([0] + [len(start) for start in starts])
    every_start = np.concatenate(starts) if starts else np.zeros(0, np.int64)
    areas = _grown_areas(incidence.indptr, incidence.indices, V, F, pinch, every_start, offsets, budgets, growth_cap)
    undecided = np.flatnonzero(areas == _UNDECIDED)
    if len(undecided):
        roots, component_area = _component_areas(incidence.indptr, incidence.indices, V, F, pinch, every_start)
        for i in undecided:
            area = component_area[np.unique(roots[offsets[i]:offsets[i + 1]])].sum()
            areas[i] = area if area <= budgets[i] else -1.0
    return ["outline" if outlines_one_face(loop) or area >= 0 else "hole" for loop, area in zip(loops, areas)]


def loops_measured(V, F, loops, incidence):
    """Each measurable loop's :func:`hole_measures` entries and its class, all at once (a scan's debris can
    give tens of thousands of loops).

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int
    loops : sequence of BoundaryLoop  every boundary loop of the mesh
    incidence : (n, m) sparse  :func:`.holes.vertex_face_incidence` of (F, n)

    Returns
    -------
    dict  loop index -> (measures dict, 'outline' or 'hole'), for the closed loops of at least 3 vertices
    """
    measured = [i for i, loop in enumerate(loops) if loop.closed and len(loop) >= 3]
    measures = holes_measures(V, [loops[i] for i in measured])
    classes = loop_classes(V, F, [loops[i] for i in measured], incidence, [m["area"] for m in measures],
                           pinch=pinch_vertices(loops, len(V)))
    return dict(zip(measured, zip(measures, classes)))


def is_outline(V, F, loop, incidence, pinch=None):
    """Whether a loop outlines its whole connected component (:func:`outline_budgets` on :func:`outline_ratios`).

    The same answer as the ratio, without labelling the whole mesh: the component is grown
    from the loop's border faces one ring of faces at a time (the connectivity of
    :func:`outline_ratios`), until either it is exhausted (then the ratio is exact) or its area
    exceeds the loop's budget (then the loop is a hole). The work is bounded by about 1.3 times
    the hole's own area of surrounding faces, so a hole in a 4M-face mesh costs what it costs in
    a small one. The growth and its areas run in one compiled call (:func:`_grown_area`): on
    face000.ply (45 loops) the per-ring gathers and area arrays took 0.12 s of the filter's serial time.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    loop : BoundaryLoop
    incidence : (n, m) sparse
        :func:`.holes.vertex_face_incidence` of (F, n).
    pinch : (n,) bool, optional
        :func:`pinch_vertices` of every loop of the mesh (default: the loop's own vertices meet no other loop).

    Returns
    -------
    bool
    """
    return outline_ratio(V, F, loop, incidence, pinch) is not None


def outline_ratio(V, F, loop, incidence, pinch=None):
    """The :func:`outline_ratios` entry of a loop that outlines its component, else None.

    Grown as in :func:`is_outline`, so it costs what the hole's surroundings cost, not the
    mesh: the ratio of a loop whose component stays within the budget is exact (the whole
    component's area), and a loop whose growth exceeds it is a hole.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    loop : BoundaryLoop
    incidence : (n, m) sparse
        :func:`.holes.vertex_face_incidence` of (F, n).
    pinch : (n,) bool, optional  as for :func:`is_outline`

    Returns
    -------
    float or None
        |vector area| / component area (inf for a component of zero area), or None for a hole.
    """
    V = np.asarray(V, np.float64)
    ids = np.asarray(loop.vertices, np.int64)
    enclosed = vector_area(V[ids])
    if pinch is None:
        pinch = np.zeros(len(V), np.bool_)
    budget = outline_budgets([enclosed], loop_facings(V, F, [loop]))[0]
    start = np.unique(np.asarray(loop.border_faces, np.int64))
    area = _grown_area(incidence.indptr, incidence.indices, V, np.asarray(F), pinch, start, budget)
    if area < 0:
        return None
    return enclosed / area if area > 0 else np.inf


@njit(cache=True)
def _triangle_area(V, F, f):
    """Area of face f: half the norm of (b - a) x (c - a), as :func:`..geometry.quality.face_areas`."""
    a, b, c = F[f, 0], F[f, 1], F[f, 2]
    ux, uy, uz = V[b, 0] - V[a, 0], V[b, 1] - V[a, 1], V[b, 2] - V[a, 2]
    wx, wy, wz = V[c, 0] - V[a, 0], V[c, 1] - V[a, 1], V[c, 2] - V[a, 2]
    nx, ny, nz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    return 0.5 * np.sqrt(nx * nx + ny * ny + nz * nz)


@njit(cache=True)
def _share_an_edge(F, f, g):
    """Whether faces f and g (distinct, sharing a corner) share a second corner: an edge."""
    shared = 0
    for i in range(3):
        for j in range(3):
            if F[f, i] == F[g, j]:
                shared += 1
    return shared >= 2


@njit(cache=True)
def _grown_area(indptr, indices, V, F, pinch, start, budget):
    """Area of the component of faces ``start`` (sorted, unique), or -1 once it exceeds ``budget``.

    The growth of :func:`is_outline` in one call: the same rings as gathering the incidence rows of a ring's vertices
    (the unseen faces sharing a vertex with the last ring; at a ``pinch`` vertex, sharing an edge
    with the ring face that reached it), their areas added ring by ring,
    stopping as soon as the area is over the budget. Each vertex's incidence row is read
    once, when a ring first reaches it (a vertex reached before had all its faces seen
    then), but a pinch vertex's, read by each ring face at it: on face000.ply's 166k-face outer
    outline about a sixth of the reads of gathering every ring face's three rows. Only the ``seen``
    flags (one byte per face and vertex) are sized by the mesh.
    """
    seen = np.zeros(F.shape[0], np.bool_)
    reached = np.zeros(V.shape[0], np.bool_)
    return _grow_tracked(indptr, indices, V, F, pinch, start, budget, seen, reached, np.empty(16, np.int64),
                         np.empty(0, np.int64), False, F.shape[0])[0]


_UNDECIDED = -2.0  # a growth of _grown_areas stopped at its cap


@njit(cache=True)
def _grown_areas(indptr, indices, V, F, pinch, starts, offsets, budgets, cap):
    """:func:`_grown_area` of many loops (loop i's faces ``starts[offsets[i]:offsets[i + 1]]``), (L,) float64;
    ``_UNDECIDED`` for a loop whose growth saw more than ``cap`` faces.

    The flags are allocated once and only the entries a loop's growth set are cleared after
    it: a mesh with many small islands (a range scan's debris) costs what their growths cost,
    not one pass over the mesh per island.
    """
    seen = np.zeros(F.shape[0], np.bool_)
    reached = np.zeros(V.shape[0], np.bool_)
    grown = np.empty(16, np.int64)
    areas = np.empty(len(offsets) - 1)
    touched = np.empty(16, np.int64)  # the faces seen by one growth, to clear
    for i in range(len(offsets) - 1):
        areas[i], grown, touched, count = _grow_tracked(indptr, indices, V, F, pinch,
                                                         starts[offsets[i]:offsets[i + 1]], budgets[i], seen,
                                                         reached, grown, touched, True, cap)
        for t in range(count):
            f = touched[t]
            seen[f] = False
            for c in range(3):
                reached[F[f, c]] = False
    return areas


@njit(cache=True)
def _grow_tracked(indptr, indices, V, F, pinch, start, budget, seen, reached, grown, touched, track, cap):
    """The growth of :func:`_grown_area`; with ``track`` the faces it sees are listed in the ``touched`` buffer.

    Every vertex it reaches belongs to a face it has seen (it reads only seen faces' corners),
    so clearing the listed faces' flags and their corners' clears every flag it set. With
    ``track``, a growth that has seen more than ``cap`` faces stops.

    Returns
    -------
    area : float  or -1 once over the budget, ``_UNDECIDED`` once over the cap
    grown, touched : the buffers (enlarged as needed)
    count : int  faces listed in ``touched`` (0 without ``track``)
    """
    count = 0
    ring = start.copy()
    area = 0.0
    for f in ring:
        seen[f] = True
        if track:
            touched, count = _listed(touched, count, f)
        area += _triangle_area(V, F, f)
    while area <= budget:
        size = 0
        for f in ring:
            for c in range(3):
                v = F[f, c]
                if reached[v]:
                    continue
                if not pinch[v]:
                    reached[v] = True
                for p in range(indptr[v], indptr[v + 1]):
                    g = indices[p]
                    if seen[g] or (pinch[v] and not _share_an_edge(F, f, g)):
                        continue
                    seen[g] = True
                    if track:
                        touched, count = _listed(touched, count, g)
                    grown, size = _listed(grown, size, g)
        if size == 0:  # the whole component, and no larger than the budget
            return area, grown, touched, count
        if track and count > cap:
            return _UNDECIDED, grown, touched, count
        ring = grown[:size].copy()
        for f in ring:
            area += _triangle_area(V, F, f)
    return -1.0, grown, touched, count


@njit(cache=True)
def _component_areas(indptr, indices, V, F, pinch, faces):
    """The component of each of ``faces`` (its root, (len(faces),) int64) and each root's area (float64).

    Components as the growth joins faces: a union-find over the vertices, each face joining its
    corners (the face's set is its first corner's; the root of a set its smallest vertex); a face
    at a pinch vertex is a node of its own (n + its rank among those faces), joined to its other
    corners and, at the pinch vertex, to the faces there it shares an edge with. Each face's area
    is added to its root.
    """
    n, m = V.shape[0], F.shape[0]
    at_pinch = np.zeros(m, np.bool_)
    for f in range(m):
        at_pinch[f] = pinch[F[f, 0]] or pinch[F[f, 1]] or pinch[F[f, 2]]
    held = np.flatnonzero(at_pinch)  # sorted: a face's node is n + its position here
    parent = np.arange(n + len(held))
    for f in range(m):
        if at_pinch[f]:
            continue
        a = _root(parent, F[f, 0])
        for c in range(1, 3):
            b = _root(parent, F[f, c])
            if a < b:
                parent[b] = a
            elif b < a:
                parent[a] = b
                a = b
    for i in range(len(held)):
        f = held[i]
        for k in range(3):
            v = F[f, k]
            if not pinch[v]:
                _join(parent, n + i, v)
                continue
            for p in range(indptr[v], indptr[v + 1]):
                g = indices[p]
                if g > f and _share_an_edge(F, f, g):
                    _join(parent, n + i, _node(F, held, at_pinch, n, g))
    area = np.zeros(n + len(held))
    for f in range(m):
        area[_root(parent, _node(F, held, at_pinch, n, f))] += _triangle_area(V, F, f)
    roots = np.empty(len(faces), np.int64)
    for i in range(len(faces)):
        roots[i] = _root(parent, _node(F, held, at_pinch, n, faces[i]))
    return roots, area


@njit(cache=True)
def _node(F, held, at_pinch, n, f):
    """Face f's node in :func:`_component_areas`' union-find: its first corner, or its own past the vertices."""
    return n + np.searchsorted(held, f) if at_pinch[f] else F[f, 0]


@njit(cache=True)
def _join(parent, a, b):
    """Join the sets of a and b (the smaller root becomes the root of both)."""
    a, b = _root(parent, a), _root(parent, b)
    if a < b:
        parent[b] = a
    elif b < a:
        parent[a] = b


@njit(cache=True)
def _root(parent, v):
    """The root of v's set, every vertex on the way pointed straight at it."""
    r = v
    while parent[r] != r:
        r = parent[r]
    while parent[v] != r:
        parent[v], v = r, parent[v]
    return r


@njit(cache=True)
def _listed(buffer, count, value):
    """``value`` appended at ``count`` (the buffer doubled when full): (buffer, count + 1)."""
    if count == len(buffer):
        larger = np.empty(2 * len(buffer), np.int64)
        larger[:count] = buffer[:count]
        buffer = larger
    buffer[count] = value
    return buffer, count + 1


def _diameter(P):
    """:func:`loop_measures`' diameter of the points P (k, 3) float64: the largest distance of two of
    them up to 2000 points, else their bounding box's diagonal."""
    if len(P) > 2000:
        return float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    # sqrt is monotone and correctly rounded: the root of the largest square is the largest root
    return float(np.sqrt(_largest_squared_distance(np.ascontiguousarray(P))))


@njit(cache=True)
def _largest_squared_distance(P):
    """The largest |P[a] - P[b]|^2 (0 for fewer than two points), its terms added x, y, z: the
    squares np.linalg.norm(P[:, None] - P[None], axis=2) takes the roots of, without its (k, k, 3) array."""
    best = 0.0
    for a in range(P.shape[0]):
        for b in range(a + 1, P.shape[0]):
            dx, dy, dz = P[a, 0] - P[b, 0], P[a, 1] - P[b, 1], P[a, 2] - P[b, 2]
            d = (dx * dx + dy * dy) + dz * dz
            if d > best:
                best = d
    return best


def hole_measures(V, loop):
    """Where a hole is and how large: the per-hole entries of a filter's result.

    Parameters
    ----------
    V : (n, 3) float
    loop : BoundaryLoop

    Returns
    -------
    dict
        ``centroid`` (3 floats, mean of the loop's vertices), ``perimeter``, ``diameter``
        (:func:`loop_measures`), ``area`` (the loop's vector area, an estimate of the missing
        surface's area: exact for a planar hole, smaller for a curved one) and ``planarity``.
    """
    points = V[np.asarray(loop.vertices, np.int64)]
    measures = loop_measures(points)
    return {"centroid": points.mean(axis=0).tolist(), "perimeter": float(measures["perimeter"]),
            "diameter": float(measures["diameter"]), "area": vector_area(points),
            "planarity": float(measures["planarity"])}


# Loops of up to this many vertices get their diameters from one pairwise-distance array per
# length; longer ones one at a time (:func:`_diameter`).
_BATCHED_DIAMETER = 64


def holes_measures(V, loops):
    """:func:`hole_measures` of many loops at once: the same entries, in one pass of array operations.

    A range scan can have tens of thousands of border loops (the outlines of its debris);
    measured one by one, each cost about 0.1 ms of small numpy calls. Sums over a loop's
    vertices are taken in their order, so a measure can differ from :func:`hole_measures`' in
    its last bits.

    Parameters
    ----------
    V : (n, 3) float
    loops : sequence of BoundaryLoop  closed, of at least 3 vertices

    Returns
    -------
    list of dict  per loop, as :func:`hole_measures`
    """
    if not len(loops):
        return []
    ids = [np.asarray(loop.vertices, np.int64) for loop in loops]
    k = np.array([len(i) for i in ids])
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    owner = np.repeat(np.arange(len(loops)), k)
    P = np.asarray(V, np.float64)[np.concatenate(ids)]  # (K, 3): the loops' points, loop after loop
    following = np.arange(len(P)) + 1
    following[first + k - 1] = first  # each point's successor along its loop
    centroid = np.add.reduceat(P, first) / k[:, None]
    perimeter = np.add.reduceat(np.linalg.norm(P[following] - P, axis=1), first)
    R = P - P[first][owner]  # relative to the loop's first point, as vector_area takes them
    area = 0.5 * np.linalg.norm(np.add.reduceat(cross_rows(R, R[following]), first), axis=1)
    C = P - centroid[owner]
    covariance = np.add.reduceat(C[:, :, None] * C[:, None, :], first) / k[:, None, None]  # (L, 3, 3)
    smallest = np.linalg.eigvalsh(covariance)[:, 0]
    diameter = np.empty(len(loops))
    for size in np.unique(k):
        which = np.flatnonzero(k == size)
        if size > _BATCHED_DIAMETER:
            diameter[which] = [_diameter(P[first[i]:first[i] + size]) for i in which]
            continue
        X = P[first[which][:, None] + np.arange(size)]  # (w, size, 3)
        diameter[which] = np.linalg.norm(X[:, :, None, :] - X[:, None, :, :], axis=3).max(axis=(1, 2))
    planarity = np.where(diameter > 0, np.sqrt(np.maximum(smallest, 0.0)) / np.where(diameter > 0, diameter, 1.0), 0.0)
    return [{"centroid": centroid[i].tolist(), "perimeter": float(perimeter[i]), "diameter": float(diameter[i]),
             "area": float(area[i]), "planarity": float(planarity[i])} for i in range(len(loops))]
