"""Hole filling by the modified minimum-angle triangulation, density refinement and bilateral filter.

Hu, Wang, Li and Liu, "Filling Holes in Triangular Meshes in Engineering" (Sec. III): the
hole is triangulated by repeatedly cutting the boundary vertex of smallest angle whose
neighbours' normals agree (III.B), refined to the density of the surrounding mesh (III.C),
and its interior vertices are moved along their normals by the bilateral filter (III.D).
"""
from __future__ import annotations

import time

import numpy as np

from ..geometry.bilateral import bilateral_filter
from ..geometry.fairing import fair_patch_in_context
from ..geometry.flips import relax_edges
from ..geometry.refine import refine_patch
from ..geometry.topology import edge_pair_set
from ..holes import inside_hole_sector, patch_crossings, patch_guard
from ..patch import HoleFillError, Patch
from ..registry import ParamSpec

RINGS = 2

PARAMS = [
    ParamSpec("alpha", "float", float(np.sqrt(2.0)),
              "Density control factor of the refinement (Sec. III.C); larger gives a denser patch.",
              minimum=0.5, maximum=10.0),
    ParamSpec("sigma_c", "float", 0.1,
              "Bilateral closeness width as a fraction of the local vertex density (mean incident edge length), Sec. IV.",
              minimum=1e-3, maximum=10.0),
    ParamSpec("sigma_s", "float", 0.5,
              "Bilateral feature-preserving width as a fraction of the local vertex density, Sec. IV.",
              minimum=1e-3, maximum=10.0),
    ParamSpec("iterations", "int", 3, "Bilateral filter iterations (Sec. IV).", minimum=0, maximum=100),
    ParamSpec("fairing", "enum", "none",
              "Extra step beyond the paper, off by default: solve a membrane ('membrane') or thin-plate "
              "('thinplate') energy for the new vertices, with the surrounding rings fixed, after refinement "
              "and before the bilateral filter. The filter is a smoother: after fairing it flattens the faired "
              "patch again, so combine fairing with iterations=0 (measured: distance to the removed surface "
              "per mille of the bbox diagonal, small/medium/large holes, 0.22/2.1/5.1 with iterations=0 "
              "against 0.38/3.1/5.4 with 3).",
              choices=("none", "membrane", "thinplate")),
]


def boundary_angles(P, normals):
    """Angle of each boundary vertex, with concave vertices reflexed (Sec. III.B, Eq. 2).

    With the loop in patch orientation, vertex i is convex when the normal of the oriented
    triangle (v_{i-1}, v_i, v_{i+1}) points the same way as the vertex normal (the paper's
    anticlockwise case); convex vertices get theta_i, concave ones 2 pi - theta_i.

    Parameters
    ----------
    P : (k, 3) float64  loop points in patch orientation
    normals : (k, 3) float64  vertex normals

    Returns
    -------
    angle : (k,) float64 in [0, 2 pi]
    convex : (k,) bool
    """
    prev, nxt = np.roll(P, 1, axis=0), np.roll(P, -1, axis=0)
    u, w = prev - P, nxt - P
    theta = np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w))
    n_t = np.cross(P - prev, nxt - prev)
    convex = np.einsum("ij,ij->i", n_t, normals) >= 0
    return np.where(convex, theta, 2 * np.pi - theta), convex


def normal_angle_threshold(normals):
    """Threshold sigma on the angle between neighbour normals (Sec. III.B).

    45 degrees when the largest angle between two boundary-vertex normals is below 55
    degrees, otherwise 85% of that largest angle.
    """
    N = np.asarray(normals, np.float64)
    largest = float(np.arccos(np.clip((N @ N.T).min(), -1.0, 1.0)))
    return np.radians(45.0) if largest < np.radians(55.0) else 0.85 * largest


def _vertex_angle(p_prev, p, p_next, normal):
    """Eq. 2 angle of one boundary vertex given its current neighbours."""
    u, w = p_prev - p, p_next - p
    cross = np.array([u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]])
    theta = np.arctan2(np.sqrt(cross @ cross), u @ w)
    # n_t = (p - p_prev) x (p_next - p_prev) = w x u ... = -(u x w) + 0; sign test against the normal
    return theta if -(cross @ normal) >= 0 else 2 * np.pi - theta, np.sqrt(cross @ cross)


def _ear_holds_a_vertex(P, p, v, n, others):
    """True when a boundary vertex of ``others`` lies in the ear triangle (p, v, n) or on its new edge.

    The test is made in the ear's plane, for vertices within half the ear's longest edge of
    that plane: the classic ear condition, which the paper's angle rule takes for granted.
    """
    A, B, C = P[p], P[v], P[n]
    nt = np.cross(B - A, C - A)
    area2 = np.linalg.norm(nt)
    if area2 == 0 or len(others) == 0:
        return False
    nt = nt / area2
    Q = P[others]
    height = (Q - A) @ nt
    reach = 0.5 * max(np.linalg.norm(B - A), np.linalg.norm(C - B), np.linalg.norm(A - C))
    Q = Q - np.outer(height, nt)
    # Barycentric signs: inside or on the boundary of the triangle (tolerance relative to its size).
    tol = -1e-9
    w_a = np.cross(C - B, Q - B) @ nt / area2
    w_b = np.cross(A - C, Q - C) @ nt / area2
    w_c = np.cross(B - A, Q - A) @ nt / area2
    inside = (w_a >= tol) & (w_b >= tol) & (w_c >= tol) & (np.abs(height) <= reach)
    return bool(inside.any())


def min_angle_triangulation(P, normals, forbidden_edges=()):
    """Modified principle of minimum angle (Sec. III.B, Steps 1-3).

    Repeatedly take the vertex v of smallest angle (Eq. 2) whose two loop neighbours'
    normals make an angle alpha <= sigma (:func:`normal_angle_threshold`), add the oriented
    triangle (v1, v, v2) and remove v, until three vertices remain, which form the last
    triangle (Step 3). When no vertex passes the normal test the smallest-angle vertex is
    used (the paper leaves this case open). An ear is never cut when its new edge (v1, v2)
    already exists in the mesh (``forbidden_edges``) or its area is zero; ears whose new
    edge leaves v1 or v2 outside the hole (:func:`inside_hole_sector`, about the vertex
    normal) or whose triangle holds another boundary vertex (:func:`_ear_holds_a_vertex`)
    are cut only when no other ear is left.

    After a cut only the ears within two positions of the removed vertex change, so each
    step costs O(1) updates plus one arg-min over the remaining vertices.

    Parameters
    ----------
    P : (k, 3) float64  loop points, patch orientation
    normals : (k, 3) float64
    forbidden_edges : (p, 2) int  loop-index pairs that must not become edges

    Returns
    -------
    F : (k - 2, 3) int64  faces in loop indices, oriented like the loop
    """
    k = len(P)
    if k < 3:
        raise HoleFillError("a hole needs at least 3 boundary vertices")
    N = np.asarray(normals, np.float64)
    P = np.asarray(P, np.float64)
    sigma = normal_angle_threshold(N)
    cos_sigma = np.cos(sigma)
    forbidden = edge_pair_set(forbidden_edges)
    prv = [(i - 1) % k for i in range(k)]
    nxt = [(i + 1) % k for i in range(k)]
    active = np.ones(k, bool)
    angle = np.full(k, np.inf)
    cuttable = np.zeros(k, bool)      # non-degenerate, new edge not already in the mesh
    normals_agree = np.zeros(k, bool)  # the normal test alpha <= sigma
    verdict = {}                       # cached ear/sector test, dropped when the ear changes
    area_tol = 1e-14 * float(np.ptp(P, axis=0).max()) ** 2

    def evaluate(v):
        p, n = prv[v], nxt[v]
        angle[v], area2 = _vertex_angle(P[p], P[v], P[n], N[v])
        cuttable[v] = area2 > area_tol and tuple(sorted((p, n))) not in forbidden
        normals_agree[v] = N[p] @ N[n] >= cos_sigma
        verdict.pop(v, None)

    def proper_ear(v):
        # Removing other vertices can only unblock an ear, so a cached False stays safe.
        if v not in verdict:
            p, n = prv[v], nxt[v]
            ok = (inside_hole_sector(P[p], N[p], P[prv[p]], P[v], P[n][None])[0]
                  and inside_hole_sector(P[n], N[n], P[v], P[nxt[n]], P[p][None])[0])
            if ok:
                others = np.flatnonzero(active)
                others = others[(others != p) & (others != v) & (others != n)]
                ok = not _ear_holds_a_vertex(P, p, v, n, others)
            verdict[v] = ok
        return verdict[v]

    for v in range(k):
        evaluate(v)
    faces = []
    remaining = k
    while remaining > 3:
        pick = None
        for tier in (active & cuttable & normals_agree, active & cuttable):
            candidates = np.flatnonzero(tier)
            for v in candidates[np.argsort(angle[candidates], kind="stable")].tolist():
                if proper_ear(v):
                    pick = v
                    break
            if pick is not None:
                break
        if pick is None:
            candidates = np.flatnonzero(active & cuttable)
            if len(candidates) == 0:
                raise HoleFillError("no valid ear left in the minimum-angle triangulation")
            pick = int(candidates[np.argmin(angle[candidates])])
        v = pick
        p, n = prv[v], nxt[v]
        faces.append((p, v, n))
        nxt[p], prv[n] = n, p
        active[v] = False
        remaining -= 1
        for u in {prv[p], p, n, nxt[n]}:
            evaluate(u)
    a = int(np.flatnonzero(active)[0])
    b, c = nxt[a], nxt[nxt[a]]
    if any(tuple(sorted(e)) in forbidden for e in ((a, b), (b, c), (c, a))):
        raise HoleFillError("the last triangle would duplicate an existing edge")
    faces.append((a, b, c))
    return np.asarray(faces, np.int64)


def relaxation_guard(ctx):
    """Veto for relaxation swaps: the hole-sector test, with an exact second opinion.

    The sector test (:func:`holes.patch_guard`) refuses a swap whose new edge leaves a
    boundary vertex outside its hole sector, measured in the tangent plane of the mesh
    normal there. Where the patch meets the surrounding surface at a large angle (a nearly
    flat patch in a strongly curved hole, up to 100 degrees on the bunny's largest cut
    hole) that projection misjudges edges that run almost along the border, and the
    refused swaps leave fans of slivers between nearly collinear boundary vertices that
    the circumsphere test of Sec. III.C would remove. A swap the sector test refuses is
    therefore allowed when its two new triangles intersect neither the surrounding faces
    nor the rest of the patch, which is what the sector test stands in for.

    Returns
    -------
    callable ``allowed(V, F, A, B, replaced) -> (s,) bool`` for :func:`geometry.flips.relax_edges`
    """
    from ..geometry.intersections import intersecting_pairs

    sector = patch_guard(ctx)

    def allowed(V, F, A, B, replaced):
        ok = sector(V, F, A, B, replaced)
        idx = np.flatnonzero(~ok)
        if len(idx) == 0:
            return ok
        s = len(idx)
        new = np.concatenate([A[idx], B[idx]])
        bad = np.zeros(2 * s, bool)
        bad[patch_crossings(ctx, V, None, faces=new)] = True
        allF = np.concatenate([new, F])
        pairs = intersecting_pairs(V, allF, np.arange(2 * s), np.arange(2 * s, len(allF)))
        if len(pairs):
            q, other = pairs[:, 0], pairs[:, 1] - 2 * s
            own = replaced[idx][q % s]
            # The two faces a swap replaces are not part of the patch after it.
            real = (other != own[:, 0]) & (other != own[:, 1])
            bad[q[real]] = True
        ok[idx] = ~(bad[:s] | bad[s:])
        return ok

    return allowed


def _refine(ctx, F0, alpha, fixed, max_passes=4):
    """Refinement of Sec. III.C run until neither a split nor a relaxation swap is left.

    The rounds of :func:`refine_patch` use the fast sector test; the swaps it refuses are then
    reconsidered with :func:`relaxation_guard` (an exact intersection check, too slow to run
    in every round), and when any of them is made, refinement resumes from the relaxed patch,
    since the new triangles may need splitting.
    """
    sector, exact = patch_guard(ctx), relaxation_guard(ctx)
    V, F, scale, info = refine_patch(ctx.points, F0, ctx.edge_scale, alpha=alpha, fixed_edges=fixed, allowed=sector)
    for _ in range(max_passes):
        F, swaps = relax_edges(V, F, fixed, allowed=exact)
        info["swaps"] += swaps
        if swaps == 0:
            break
        V, F, scale, more = refine_patch(V, F, scale, alpha=alpha, fixed_edges=fixed, allowed=sector)
        info["split_rounds"] += more["split_rounds"]
        info["swaps"] += more["swaps"]
    return V, F, scale, info


def _optimise(ctx, V, F, interior, scale, fairing, sigma_c, sigma_s, iterations):
    """Optional fairing (beyond the paper) then the bilateral filter of Sec. III.D on the new vertices."""
    V = V.copy()
    k = ctx.size
    if fairing != "none" and interior.any():
        V[k:] = fair_patch_in_context(ctx.vertices, ctx.faces, k, V[k:], F,
                                      order=1 if fairing == "membrane" else 2)
    if iterations > 0 and interior.any():
        V = bilateral_filter(V, F, interior, sigma_c * scale, sigma_s * scale, iterations)
    return V


def _crosses(ctx, V, F):
    """Does the patch (V loop-first, F) intersect itself or the surrounding faces?"""
    from ..geometry.intersections import intersecting_pairs

    return bool(len(patch_crossings(ctx, V, F))
                or len(intersecting_pairs(V, F, np.arange(len(F)), np.arange(len(F)))))


def fill(ctx, alpha=np.sqrt(2.0), sigma_c=0.1, sigma_s=0.5, iterations=3, fairing="none"):
    """Fill one hole by Hu et al.'s three steps (Sec. III.B-III.D).

    Parameters
    ----------
    ctx : HoleContext
    alpha, sigma_c, sigma_s, iterations, fairing : see PARAMS

    Returns
    -------
    Patch
        ``info`` has ``initial_faces``, ``split_rounds``, ``swaps`` and per-step seconds.
    """
    k = ctx.size
    t0 = time.perf_counter()
    F0 = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    t1 = time.perf_counter()
    loop_edges = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    fixed = np.concatenate([loop_edges, ctx.forbidden_edges.reshape(-1, 2)])
    V, F, scale, info = _refine(ctx, F0, alpha, fixed)
    t2 = time.perf_counter()
    interior = np.arange(len(V)) >= k
    Vb = _optimise(ctx, V, F, interior, scale, fairing, sigma_c, sigma_s, iterations)
    info["refinement"], info["bilateral_iterations"] = "plain", iterations
    if _crosses(ctx, Vb, F):
        # Swaps can fold a patch through a strongly curved border or onto itself: redo the
        # refinement with every swap checked for intersections, and as a last resort without
        # swaps (centroid splits alone never create an intersection).
        for mode, guard in (("guarded", patch_guard(ctx, check_intersections=True)),
                            ("splits only", lambda V, F, A, B, r: np.zeros(len(A), bool))):
            if not _crosses(ctx, V, F) or _crosses(ctx, ctx.points, F0):
                break
            V, F, scale, info2 = refine_patch(ctx.points, F0, ctx.edge_scale, alpha=alpha, fixed_edges=fixed,
                                              allowed=guard)
            info.update(info2, refinement=mode)
        interior = np.arange(len(V)) >= k
        # The filter moves vertices along their normals; on a large, nearly flat patch that
        # can fold it. Use as many iterations as keep it free of intersections.
        for n_iter in range(iterations, -1, -1):
            Vb = _optimise(ctx, V, F, interior, scale, fairing, sigma_c, sigma_s, n_iter)
            if n_iter == 0 or not _crosses(ctx, Vb, F):
                break
        info["bilateral_iterations"] = n_iter
    V = Vb
    t3 = time.perf_counter()
    info.update(initial_faces=len(F0), triangulation_seconds=t1 - t0, refinement_seconds=t2 - t1,
                filter_seconds=t3 - t2)
    return Patch(vertices=V[k:], faces=F, info=info)
