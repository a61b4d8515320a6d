"""Triangle-triangle intersection queries between face sets of one mesh.

Used to reject hole patches that cross the surrounding surface and to count
patch faces that intersect the mesh.  Two faces that merely share a vertex or
an edge (as neighbouring faces of a mesh do) are *not* reported unless they
really overlap:

* sharing three vertices (duplicate faces): intersect.
* sharing an edge: intersect only if folded onto each other, i.e. the opening
  angle between the two faces around the edge is below ``fold_angle``.  Two
  triangles through a common edge can meet elsewhere only when coplanar and on
  the same side, so this test is complete.
* sharing one vertex ``S``: intersect iff the edge opposite ``S`` of one face
  meets the other face, tested both ways.  This is complete: ``T1 & T2`` is
  convex and contains ``S``; if it contains another point, walk from ``S``
  away along that direction to the last common point ``Z``.  ``Z`` lies on the
  boundary of one face, and a boundary point of a triangle reached from its
  corner ``S`` lies on the edge opposite ``S`` (if it lies on an edge through
  ``S``, the walk runs along that edge and, if it stopped early, it stopped on
  the other face's boundary instead).  This includes a face piercing the other
  from ``S`` and an edge through ``S`` running inside the other face.
* sharing nothing: intersect iff some edge of one face meets the other face
  (both ways).  For non-coplanar faces the common part is a segment on the
  planes' line whose endpoints lie on edges; for coplanar faces either edges
  cross or one face contains the other's edges.

Vertices are shared if they have the same index *or* identical coordinates, so
unwelded meshes (e.g. from STL) do not report their seams; with ``weld=False`` only the
same index is shared, and faces that touch at coincident but distinct vertices intersect
(as in MeshLab's per-face self-intersection test). The filters' crossing checks use
``weld=False``: a patch is joined to the mesh by index only, so a coincident vertex of another
part is a contact with that part.

Tolerance: an edge meets a face if it passes within ``tol`` of it (a slab of
half-thickness ``tol`` around the face, grown by ``tol`` in the plane, with
sharp corners capped).  Such near touches of unshared geometry count as
intersections; contact at a shared edge, or within ``tol`` of a shared vertex,
never does.  Default ``tol`` is ``1e-9`` times the bounding box
diagonal of the involved vertices (plus a rounding floor for coordinates far
from the origin).

Degenerate faces (some height <= ``tol``, including repeated vertex indices)
have no interior: they only act as segments (all their edges, also those through
a shared vertex) that may cross a non-degenerate face.  Two degenerate faces never intersect, nor does a
degenerate face with a face it shares an edge with.
"""
import numpy as np

from . import _broad_phase_kernels as broad
from . import _narrow_phase_kernels as narrow
from .sets import isin_ints, unique_ints

FOLD_ANGLE = 1e-3  # radians of opening below which edge-adjacent faces overlap
_LOG4 = np.log(4)

__all__ = ["intersecting_pairs", "faces_intersecting", "FixedFaces", "intersecting_pairs_with_fixed"]


def intersecting_pairs(V, F, query, against, tol=None, *, fold_angle=FOLD_ANGLE, weld=True):
    """Pairs of intersecting faces, one from `query` and one from `against`.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int
        Triangles as vertex indices into `V`.
    query, against : (q,) int, (a,) int
        Face indices into `F`.  The sets may overlap (e.g. a patch tested
        against itself); duplicates are ignored.
    tol : float, optional
        Contact distance, see module docstring.  Default: scale-aware.
    fold_angle : float
        Opening angle (radians) below which faces sharing an edge overlap.
    weld : bool
        Vertices with identical coordinates count as shared (default); False: only equal indices.

    Returns
    -------
    pairs : (p, 2) int64
        Face indices into `F`, column 0 from `query`, column 1 from `against`,
        sorted.  No face is paired with itself and each unordered pair appears
        once (when both faces are in both sets, the smaller index comes first).
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(np.asarray(F, dtype=np.int64).reshape(-1, 3))
    q = _sorted_unique(np.asarray(query, dtype=np.int64).ravel())
    a = _sorted_unique(np.asarray(against, dtype=np.int64).ravel())
    empty = np.empty((0, 2), np.int64)
    if len(q) == 0 or len(a) == 0:
        return empty

    # boxes, centroids and radii of all faces in one compiled pass (no (n, 3, 3) arrays)
    bq, ba = broad.face_bounds(V, F, q), broad.face_bounds(V, F, a)
    tol = _default_tol(bq, ba) if tol is None else float(tol)
    # Faces of `against` outside the query faces' common box (grown by tol) meet none of them;
    # dropping them first spares the candidate search and the welding that work (a few new
    # triangles tested against a whole ring of faces).
    inside = broad.boxes_meeting(bq[0], bq[1], ba[0], ba[1], tol)
    if len(inside) == 0:
        return empty
    if len(inside) < len(a):
        a, ba = a[inside], tuple(x[inside] for x in ba)
    return _tested_pairs(V, F, q, a, bq, ba, tol, fold_angle, weld)


class FixedFaces:
    """The per-face bounds of a face set that many queries are tested against (a hole's surroundings).

    :func:`intersecting_pairs_with_fixed` reads them instead of computing them for every query:
    the boxes, centroids and radii of `_broad_phase_kernels.face_bounds`, and the box of them all,
    the same numbers for faces with the same corner coordinates.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    """

    def __init__(self, V, F):
        V = np.ascontiguousarray(V, dtype=np.float64)
        F = np.ascontiguousarray(np.asarray(F, dtype=np.int64).reshape(-1, 3))
        self.count = len(F)
        self.bounds = broad.face_bounds(V, F, np.arange(len(F)))  # lo, hi, centroid (m, 3); radius (m,)
        lo, hi = self.bounds[0], self.bounds[1]
        if len(F):
            box_lo, box_hi, _ = broad.common_box(lo[:1], hi[:1], lo, hi)
            lo, hi = box_lo[None], box_hi[None]
        self.box = (lo, hi)  # (1, 3) each; (0, 3) without faces


def intersecting_pairs_with_fixed(V, F, query, fixed, start, also=None, *, fold_angle=FOLD_ANGLE, weld=True):
    """:func:`intersecting_pairs` of `query` against `also` and the faces F[start:start + fixed.count].

    Those faces are the ones :class:`FixedFaces` `fixed` was built from, in order and with the
    same corner coordinates, so their bounds are not computed again: the answer is that of
    ``intersecting_pairs(V, F, query, np.concatenate([also, np.arange(start, start + fixed.count)]))``
    with the default tolerance, bit for bit.

    Parameters
    ----------
    V, F, query, fold_angle, weld : as for :func:`intersecting_pairs`
    fixed : FixedFaces
    start : int
    also : (b,) int, optional
        More faces to test against, each below `start`.

    Returns
    -------
    pairs : (p, 2) int64  as :func:`intersecting_pairs`
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(np.asarray(F, dtype=np.int64).reshape(-1, 3))
    q = _sorted_unique(np.asarray(query, dtype=np.int64).ravel())
    also = _sorted_unique(np.asarray([] if also is None else also, dtype=np.int64).ravel())
    empty = np.empty((0, 2), np.int64)
    if len(q) == 0 or len(also) + fixed.count == 0:
        return empty
    bq = broad.face_bounds(V, F, q)
    b_also = bq if np.array_equal(also, q) else broad.face_bounds(V, F, also)  # a patch also against itself
    # the box of all `against` boxes: those of `also`, then the fixed faces' own box
    tol = _default_tol(bq, (np.concatenate([b_also[0], fixed.box[0]]), np.concatenate([b_also[1], fixed.box[1]])))
    inside_also = broad.boxes_meeting(bq[0], bq[1], b_also[0], b_also[1], tol)
    inside_fixed = broad.boxes_meeting(bq[0], bq[1], fixed.bounds[0], fixed.bounds[1], tol)
    if len(inside_also) + len(inside_fixed) == 0:
        return empty
    a = np.concatenate([also[inside_also], start + inside_fixed])
    ba = tuple(np.concatenate([x[inside_also], y[inside_fixed]]) for x, y in zip(b_also, fixed.bounds))
    return _tested_pairs(V, F, q, a, bq, ba, tol, fold_angle, weld)


def _tested_pairs(V, F, q, a, bq, ba, tol, fold_angle, weld):
    """The pairs of :func:`intersecting_pairs` from its sets q, a (the faces of `a` near `q` only) and their bounds."""
    i, j, in_q, in_a = _candidates(bq, ba, tol, q, a, len(F))
    if weld:
        canon = broad.weld_labels(V, F, np.concatenate([q, a]))
    else:
        canon = np.arange(len(V), dtype=np.int64)
    code, fy, fx = narrow.narrow_codes(V, F, canon, i, j, in_q, in_a, tol)
    hit = code == narrow.HIT
    fold = np.flatnonzero(code == narrow.FOLD)
    if len(fold):
        hit[fold] = np.arctan2(fy[fold], fx[fold]) < fold_angle  # numpy's arctan2, as before
    # i and j each come from a set of distinct faces, so the keys are distinct: their order is the pairs'
    key = np.sort(i[hit] * len(F) + j[hit])
    return np.stack([key // len(F), key % len(F)], axis=1)


def faces_intersecting(V, F, query, against, tol=None, *, fold_angle=FOLD_ANGLE, weld=True):
    """Faces of `query` that intersect at least one other face of `against`.

    Parameters are as for :func:`intersecting_pairs`.

    Returns
    -------
    faces : (k,) int64
        Sorted unique face indices into `F`.
    """
    pairs = intersecting_pairs(V, F, query, against, tol, fold_angle=fold_angle, weld=weld)
    # a pair of two faces that are both in both sets is listed once, either way round
    flipped = pairs[isin_ints(pairs[:, 1], query) & isin_ints(pairs[:, 0], against), 1]
    return unique_ints(np.concatenate([pairs[:, 0], flipped]))


def _default_tol(bounds_q, bounds_a):
    """1e-9 of the diagonal of the faces' common box, plus a rounding floor for coordinates far from the origin.

    The box of the used vertices is the box of their faces' boxes.
    """
    lo, hi, far = broad.common_box(bounds_q[0], bounds_q[1], bounds_a[0], bounds_a[1])
    return float(1e-9 * np.linalg.norm(hi - lo) + 1e-13 * far)


def _candidates(bounds_q, bounds_a, tol, q, a, n_faces):
    """Global face pairs (i, j) worth the narrow test, and the marks in_q, in_a (n_faces,) bool of the sets.

    A pair is kept when the boxes overlap (query boxes grown by tol) and the centroids lie
    within the sum of the faces' bounding-sphere radii plus tol (self-pairs and mirrored pairs
    are left out, see `_broad_phase_kernels.box_pairs`). `bounds_q`, `bounds_a` are
    `_broad_phase_kernels.face_bounds` of the face sets `q`, `a` (lo, hi, centroid, radius).
    A single radius would be set by the largest face, so faces are binned by radius (factors
    of 4) and each pair of bins is bounded by its largest radii (the bound the former dual-tree
    search on centroids used; the grid of `_broad_phase_kernels.candidate_pairs` applies it
    pair by pair). The bins take numpy's logarithm here, whose last bits may differ from the
    compiled one's.
    """
    logs = np.log(broad.radius_ratios(bounds_q[3], bounds_a[3]))
    return broad.candidate_pairs(bounds_q, bounds_a, logs, _LOG4, tol, q, a, n_faces)


def _sorted_unique(x):
    """np.unique(x) for an int array, skipping the sort when x already increases (an arange, usually)."""
    if len(x) and np.all(x[1:] > x[:-1]):
        return x
    return unique_ints(x)

