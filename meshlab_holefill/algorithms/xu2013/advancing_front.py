"""Advancing-front triangulation of a closed 3D polygon (a hole boundary).

The advancing front mesh technique of Zhao, Gao and Lin (2007) as used by Xu, Li and Tan
(2013, Sec. 3.2, Fig. 3): the front starts as the hole boundary (Step 1); at the front
vertex v with the smallest front angle theta (Step 2) triangles are created in the plane of
its two front edges (Step 3):

* theta <= 75 degrees: one triangle joining v's two front neighbours;
* 75 < theta <= 135 degrees: one new vertex on the bisector, two triangles;
* theta > 135 degrees: two new vertices trisecting the angle, three triangles.

A new vertex closer than ``merge_factor`` times the target edge length to another vertex of
the same front is merged with it (Step 4): with one of v's two neighbours the step falls back
to the rule with one vertex less, with any other vertex the front is split in two there. The
front is updated (Step 5) and the steps repeat until every front is closed (Step 6). Fronts
are cyclic linked lists of nodes (a vertex may be on two fronts after a split); a heap keeps
the angles (:mod:`._front_state`).

What the paper leaves open, as chosen here:

* **Edge length.** New vertices lie at a target length from v: a sizing value carried by
  every vertex, at a boundary vertex the mean length of its two boundary edges, at a new
  vertex the mean of v's and its neighbours'. (With the current front edges' lengths instead
  the mesh shrinks ring by ring: the rules never remove vertices from a convex front.)
* **Merge threshold.** 0.75 target lengths (see :func:`advancing_front_triangulation`). A
  merge with the vertex beyond p (or q) makes the triangle at p an ear holding p's whole
  front angle; like rule 1 it is then allowed only for angles a single triangle fits
  (``MERGE_EAR_MAX``, 120 degrees), otherwise the step falls back to the next rule.
* **Which side is inside.** The front angle is measured counter-clockwise about the normal
  of the edges' plane oriented like a reference normal (reflex when they disagree). The
  reference normal of a boundary vertex is given (default: the hole's unit vector area), a
  new vertex gets the mean of v's and its neighbours'. Where the edges' plane is unreliable
  (edges nearly collinear, or the plane more than 30 degrees from the reference normal, as on
  noisy boundaries where following it lets the front climb out of the hole) the angle is
  measured, and new vertices placed, in the plane orthogonal to the reference normal.

Beyond the paper (it has no safeguards), every step is checked before it is applied, so the
front never crosses itself: the new triangles may reuse an existing edge only to consume it
from the front, must face the way of the angle's plane and not fold back over the triangle
behind a consumed edge, every new edge must leave its existing front vertices strictly
inside their front angle, and no new edge may cross a nearby front edge (in the plane of the
angle). With ``obstacles`` (the mesh around the hole) no new triangle may cross a mesh face
and no new vertex may come within 0.35 target lengths of one. A rejected step is retried
with the next rule down (three triangles -> two -> one) and then at the vertex with the next
smallest angle; a front of at most 6 vertices on which every step is refused is closed by a
fan. The run stops with :class:`HoleFillError` when no step is possible, when the fronts grow
past 1.3 times the boundary's vertex count plus 20 or a new vertex lies outside the loop's ball
(``LEAVE_RADIUS``; either way the front has left the hole: it runs over the surrounding surface
or out of a hole wrapped around a tube), or past a bound on the triangle count: it always ends.

The whole step loop runs compiled (:mod:`._front_loop`, one step in :mod:`._front_step`; the
heap, the linked-list fronts and the edge tables in the arrays of :mod:`._front_state`, the
per-step checks in :mod:`._front_kernels`); this module sets up its state, runs it and reports
the outcome.
"""
from __future__ import annotations

import math

import numpy as np

from ...errors import HoleFillError
from ._front_loop import CLOSED, GREW, LEFT_BALL, STUCK, initial_state, run_front
from ._front_obstacles import FrontObstacles
from ._front_predicates import PLANE_MIN_COS, PLANE_MIN_SIN
from ._front_state import (FAN_CLOSURES, KEPT_BLOCKED, MAX_FRONT, MERGES, N_FACES, N_VERT, OBSTACLE_TESTS, REJECTED,
                           RELEASED_NEAR, RULE1, RULE2, RULE3, SPLITS, STEPS, FrontObstacleArrays, FrontParams,
                           new_scratch)

__all__ = ["advancing_front_triangulation"]

ONE_TRIANGLE_MAX = math.radians(75.0)
TWO_TRIANGLES_MAX = math.radians(135.0)
# Falling back to the single triangle (p, v, q) is allowed only below this angle (quality).
FALLBACK_ONE_TRIANGLE_MAX = math.radians(150.0)
# New edges must leave an existing front vertex this far inside its front angle (radians).
ANGLE_MARGIN = math.radians(2.0)
# A new triangle may not fold over the triangle behind a front edge it consumes by more than
# 120 degrees (cosine of the angle between their normals below -0.5).
FOLD_MIN_COS = -0.5
# A merge (Step 4) that turns the triangle at v's neighbour p into an ear (p's two front edges
# and the chord joining their ends) is refused when p's front angle exceeds this: the ear keeps
# p's whole angle, and above ~133 degrees no triangle reaches quality 0.3. 120 degrees (best
# quality 0.46) still lets rule 2 close a square by merging with its opposite corner.
MERGE_EAR_MAX = math.radians(120.0)
# A front of a disk-like hole shrinks; one that grows past this many times the boundary's
# vertex count has run out of the hole (over the surrounding surface).
FRONT_GROWTH_LIMIT = 1.3
# The default triangle bound is this many times the estimate from the boundary's vector area and
# mean edge length, plus 10 k + 100. Fronts that close (120 runs on the benchmark's cut and natural
# holes and the Loop-subdivided samples' large and strip holes) used at most 0.29 of it and gave the
# same patches as with 20 times the estimate. A front that has left the hole runs on, most of its
# steps refused, until a bound stops it: on those holes such runs took 4.6 of the 5.3 s spent in the
# front with 20 times the estimate, 3.3 s with 4, and 2.1 s with the ball below as well.
FACE_BOUND = 4.0
# A front that closes keeps its vertices near the loop: within 0.99 times the largest distance of
# a loop vertex from the loop's centroid on the 120 closing runs above. A new vertex beyond this
# many times that distance has left the hole (the failing fronts there crossed it after 60 % of
# the vertices they made, the closing ones never).
LEAVE_RADIUS = 1.25
# A new vertex must keep this fraction of its target edge length away from the surrounding
# mesh: closer, the front is running over the existing surface instead of across the hole.
HOVER_FACTOR = 0.35
# The exponent of the compiled kernels' squares, passed at run time (see _front_kernels).
TWO = 2.0


def _obstacle_arrays(obstacles, cell, k):
    """The surrounding mesh's grid for the compiled loop, and its faces behind the boundary edges.

    Without obstacles (or without faces) empty arrays of the same types, so that one
    compiled loop serves both.
    """
    if obstacles is None or len(np.asarray(obstacles[1]).reshape(-1, 3)) == 0:
        empty_i, empty_f = np.zeros(0, np.int64), np.zeros((0, 3))
        arrays = FrontObstacleArrays(False, empty_f, np.zeros((0, 3), np.int64), np.zeros(3, np.int64),
                                     np.ones(3, np.int64), empty_i, np.zeros(1, np.int64), empty_i, empty_f,
                                     empty_f.copy(), np.zeros(1, np.int64), empty_i)
        return arrays, np.zeros((0, 3), np.int64)
    ob = FrontObstacles(obstacles[0], obstacles[1], cell, k)
    arrays = FrontObstacleArrays(True, ob.V, ob.F, ob._base.astype(np.int64), ob._dims.astype(np.int64),
                                 ob._keys.astype(np.int64), ob._starts, ob._cell_faces.astype(np.int64),
                                 np.ascontiguousarray(ob.lo), np.ascontiguousarray(ob.hi), ob._stamp, ob._out)
    return arrays, np.ascontiguousarray(ob.border_faces(), np.int64)


def leave_ball(P):
    """Centre (x, y, z) and squared radius of the ball a closing front stays in (``LEAVE_RADIUS``).

    The loop's centroid and ``LEAVE_RADIUS`` times its vertices' largest distance from it.
    """
    centre = P.mean(axis=0)
    radius = LEAVE_RADIUS * float(np.sqrt(((P - centre) ** 2).sum(axis=1).max()))
    return float(centre[0]), float(centre[1]), float(centre[2]), radius * radius


def _run(P, n_ref, forbidden_edges, merge_factor, max_faces, obstacles, merge_ear_max):
    """Set up the compiled loop's state (Step 1) and run it (Steps 2-6); (new vertices, faces, stats)."""
    k = len(P)
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    S = 0.5 * (lengths + np.roll(lengths, 1))
    # Cell of the uniform grids of neighbourhood queries (the kernels' query boxes, the obstacles).
    cell = max(2.0 * float(np.mean(lengths)), 1e-300)
    params = FrontParams(int(k), float(merge_factor), math.inf if merge_ear_max is None else float(merge_ear_max),
                         float(S.max()), float(lengths.max()), float(cell), int(max_faces),
                         float(FRONT_GROWTH_LIMIT * k + 20), PLANE_MIN_SIN, PLANE_MIN_COS, ONE_TRIANGLE_MAX,
                         TWO_TRIANGLES_MAX, FALLBACK_ONE_TRIANGLE_MAX, ANGLE_MARGIN, FOLD_MIN_COS, HOVER_FACTOR, TWO,
                         *leave_ball(P))
    ob, border_faces = _obstacle_arrays(obstacles, cell, k)
    # a writable copy always: the compiled loop is typed by its arguments' flags too, so that a
    # read-only input would load (or compile) a second version of it
    normals = np.array(np.broadcast_to(n_ref, (k, 3)), np.float64, order="C")
    forbidden = np.ascontiguousarray(np.asarray(forbidden_edges, np.int64).reshape(-1, 2))
    st = initial_state(P, normals, S, forbidden, border_faces, ob.V, params)
    outcome, size, st = run_front(st, params, ob, new_scratch())
    C = st.C
    if outcome == GREW:
        raise HoleFillError(f"advancing front grew to {size} vertices from {k}: it left the hole")
    if outcome == LEFT_BALL:
        raise HoleFillError(f"advancing front left the hole: a new vertex lies more than {LEAVE_RADIUS} times the "
                            "loop's radius from the loop's centre")
    if outcome == STUCK:
        raise HoleFillError("advancing front is stuck: no valid triangle can be added "
                            f"({size} front vertices left)")
    if outcome != CLOSED:
        raise HoleFillError(f"advancing front did not close within {max_faces} triangles")
    stats = {name: int(C[i]) for name, i in (("steps", STEPS), ("rule1", RULE1), ("rule2", RULE2), ("rule3", RULE3),
                                              ("merges", MERGES), ("splits", SPLITS), ("rejected", REJECTED),
                                              ("obstacle_tests", OBSTACLE_TESTS), ("max_front", MAX_FRONT))}
    # Keys in the order the counts first occurred (a first release after a fan closure is stamped > 1).
    late = [("kept_blocked", KEPT_BLOCKED)] if C[RELEASED_NEAR] else []
    if C[FAN_CLOSURES]:
        late.insert(0 if C[RELEASED_NEAR] > 1 else len(late), ("fan_closures", FAN_CLOSURES))
    stats.update((name, int(C[i])) for name, i in late)
    return st.P[k:C[N_VERT]].copy(), st.faces[:C[N_FACES]].copy(), stats


def advancing_front_triangulation(points, forbidden_edges=(), merge_factor=0.75, max_faces=None,
                                  reference_normal=None, obstacles=None, merge_ear_max=MERGE_EAR_MAX):
    """Triangulate a hole by the advancing front method (Xu et al. 2013, Sec. 3.2).

    Parameters
    ----------
    points : (k, 3) float64
        Boundary polygon in patch orientation (see :mod:`meshlab_holefill.core.holes`).
    forbidden_edges : (p, 2) int
        Pairs of boundary vertices that must not be joined (already joined by the mesh).
    merge_factor : float
        A new vertex closer than ``merge_factor`` times the target edge length to a vertex of
        the same front is merged with it (Sec. 3.2, Step 4). The paper gives no value; 0.75
        keeps every new front edge at least 3/4 of the target length, which holds the
        patch's density to that of the boundary (with 0.5 a round hole gets ~1.4 times the
        triangles of an equilateral mesh of the boundary's edge length, with 0.75 ~1.1 times)
        and raises the mean triangle quality.
    max_faces : int, optional
        Bound on the number of triangles before giving up; default ``FACE_BOUND`` times the estimate
        from the boundary's vector area and mean edge length, plus 10 k + 100.
    reference_normal : (3,) or (k, 3) float64, optional
        Reference normal(s) at the boundary vertices: they orient the front angles (convex or
        reflex) and give their plane where the plane of the two front edges is unreliable.
        Default: the boundary's unit vector area, which points to the side the patch will face.
        (:mod:`meshlab_holefill.algorithms.xu2013.poisson_patch` passes each vertex's surface
        normal plus that mean normal.)
    obstacles : ((n, 3) float64, (m, 3) int), optional
        Surrounding mesh (vertices with the boundary first, as in a HoleContext, and faces):
        a step whose triangles would intersect one of these faces is rejected, so the
        patch goes around folds of the surface next to the hole.

    Returns
    -------
    new_vertices : (p, 3) float64
    faces : (q, 3) int64
        Indices into ``concatenate([points, new_vertices])``, oriented like the boundary.
    stats : dict
        ``steps``, ``rule1``, ``rule2``, ``rule3``, ``merges``, ``splits``, ``rejected``
        (and ``fan_closures`` when the last resort was used, ``kept_blocked`` when refused
        nodes were left out of a retry because the step was beyond their reach).

    Raises
    ------
    HoleFillError
        When the front gets stuck or does not close within ``max_faces`` triangles.
    """
    P = np.asarray(points, np.float64).reshape(-1, 3)
    k = len(P)
    if k < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    Q = P - P[0]  # about a loop vertex: raw coordinates far from the origin cancel to noise
    vector_area = 0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)
    area = float(np.linalg.norm(vector_area))
    if reference_normal is None:
        if area <= 0.0:
            raise HoleFillError("the hole boundary encloses no area")
        reference_normal = vector_area / area
    n_ref = np.asarray(reference_normal, np.float64).reshape(-1, 3)
    n_ref = n_ref / np.maximum(np.linalg.norm(n_ref, axis=1, keepdims=True), 1e-300)
    if max_faces is None:
        h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean()) or 1.0
        max_faces = int(FACE_BOUND * area / (0.43 * h * h) + 10 * k + 100)
    return _run(P, n_ref, forbidden_edges, merge_factor, max_faces, obstacles, merge_ear_max)


_WARM = []  # set once the kernels are loaded in this process


def warm_up():
    """Load (or compile) the front's numba kernels now, by running the front on a small hole.

    The compiled loop (:func:`._front_loop.initial_state`, :func:`._front_loop.run_front`, with
    the kernels they call linked in) is compiled lazily, on first use, and cached on disk;
    loading it takes a few tenths of a second per process. A caller about to fork worker processes can call this
    first, so that the workers inherit the loaded kernels instead of each loading them again
    inside its first hole's time.
    """
    if _WARM:
        return
    t = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), 0.1 * np.cos(3 * t)], axis=1)
    outer = 1.5 * ring
    V = np.concatenate([ring, outer])
    k = len(ring)
    F = [(i, (i + 1) % k, k + i) for i in range(k)] + [((i + 1) % k, k + (i + 1) % k, k + i) for i in range(k)]
    advancing_front_triangulation(ring, obstacles=(V, np.array(F)))
    _WARM.append(True)
