"""Hu et al.: modified minimum-angle triangulation, refinement, bilateral filter, and the filter end to end."""
import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dataclasses

from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill, relaxation_guard
from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import boundary_angles, min_angle_triangulation, normal_angle_threshold
from meshlab_holefill.geometry.flips import relax_edges
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.algorithms.hu2012.hole_guards import patch_guard
from meshlab_holefill.core.holes import boundary_loops, hole_context, vertex_face_incidence
from meshlab_holefill.core.patch import validate_patch

from conftest import assert_filled_cleanly, cut_disks, grid, mesh_arrays, meshset_from_arrays, random_planar_patch, sample, sphere_with_holes

UP = np.array([0.0, 0.0, 1.0])
# Counter-clockwise L shape seen from +z: the vertex (1, 1) is the concave one.
L_SHAPE = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)


def test_convex_and_concave_vertices_of_an_l_shape():
    angle, convex = boundary_angles(L_SHAPE, np.tile(UP, (6, 1)))
    assert convex.tolist() == [True, True, True, False, True, True]
    assert np.degrees(angle).round(6).tolist() == [90, 90, 90, 270, 90, 90]


def test_the_concave_reading_flips_with_the_normal():
    # Seen from below the same loop is clockwise: every vertex swaps convexity (Eq. 2's two cases).
    _, convex = boundary_angles(L_SHAPE, np.tile(-UP, (6, 1)))
    assert convex.tolist() == [False, False, False, True, False, False]


def test_normal_angle_threshold_rule():
    tilt = lambda deg: np.array([np.sin(np.radians(deg)), 0, np.cos(np.radians(deg))])
    assert np.degrees(normal_angle_threshold(np.array([tilt(0), tilt(50)]))) == pytest.approx(45)
    assert np.degrees(normal_angle_threshold(np.array([tilt(0), tilt(80)]))) == pytest.approx(0.85 * 80)


def test_min_angle_triangulation_of_the_l_shape_cuts_convex_ears_only():
    F = min_angle_triangulation(L_SHAPE, np.tile(UP, (6, 1)))
    assert len(F) == 4
    # Every face is counter-clockwise (oriented like the loop) and the concave vertex is never an ear tip.
    P = L_SHAPE
    normals = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    assert np.all(normals[:, 2] > 0)
    edges = {tuple(sorted(e)) for f in F.tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert (2, 4) not in edges  # the diagonal outside the L


def test_min_angle_triangulation_prefers_the_smallest_angle():
    # A thin triangle tip at vertex 1 (the sharpest angle) must be the first ear.
    P = np.array([[0, 0, 0], [10, 0.5, 0], [0, 1, 0], [-1, 0.5, 0]], float)
    F = min_angle_triangulation(P, np.tile(UP, (4, 1)))
    assert F[0].tolist() == [0, 1, 2]


def test_min_angle_triangulation_avoids_forbidden_edges():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    F = min_angle_triangulation(square, np.tile(UP, (4, 1)), forbidden_edges=[[0, 2]])
    edges = {tuple(sorted(e)) for f in F.tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert (1, 3) in edges and (0, 2) not in edges


def _first_hole_context(V, F, rings=2):
    loops = boundary_loops(F)
    inner = [lp for lp in loops if len(lp) < max(len(x) for x in loops)] or loops
    return hole_context(V, F, inner[0], vertex_face_incidence(F, len(V)), rings=rings)


def test_fill_of_a_planar_hole_stays_planar_and_matches_density():
    V, F = grid(20, 20)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.25)
    ctx = _first_hole_context(V, F)
    patch = fill(ctx)
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    assert np.abs(patch.vertices[:, 2]).max() < 1e-12
    X = patch.all_points(ctx.points)
    q = triangle_quality(X, patch.faces)
    assert q.mean() > 0.8 and q.min() > 0.3
    E = np.concatenate([patch.faces[:, [0, 1]], patch.faces[:, [1, 2]]])
    ratio = np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1).mean() / ctx.mean_edge_length
    assert 0.8 < ratio < 1.25


def test_fill_is_deterministic():
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.4)
    ctx = _first_hole_context(V, F)
    a, b = fill(ctx), fill(ctx)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


def test_fairing_option_brings_a_sphere_hole_closer_to_the_sphere():
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.6)
    ctx = _first_hole_context(V, F)
    flat = fill(ctx)
    faired = fill(ctx, fairing="thinplate")
    err = lambda p: np.abs(np.linalg.norm(p.vertices, axis=1) - 1).mean()
    assert err(faired) < 0.5 * err(flat)


def test_filter_closes_the_five_natural_holes_of_the_bunny_scan(bunny_scan):
    V0, F0 = mesh_arrays(bunny_scan)
    res = bunny_scan.meshing_close_holes_min_angle_bilateral()
    assert res["closed_holes"] == 5 and res["failed_holes"] == 0
    assert [h["boundary_edges"] for h in res["holes"]] == [38, 22, 22, 19, 8]
    V1, F1 = mesh_arrays(bunny_scan)
    assert np.array_equal(V1[: len(V0)], V0) and np.array_equal(F1[: len(F0)], F0)
    assert len(boundary_loops(F1)) == 0
    topo = bunny_scan.get_topological_measures()
    assert topo["non_two_manifold_edges"] == 0 and topo["boundary_edges"] == 0
    assert res["new_faces"] == len(F1) - len(F0)


def test_filter_on_sphere_holes_gives_good_triangles_close_to_the_sphere():
    V, F, _ = sphere_with_holes(subdiv=5, centers=[(1, 0, 0), (0, 0, 1)], radius=0.3)
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_min_angle_bilateral()
    assert res["closed_holes"] == 2
    V1, F1 = mesh_arrays(ms)
    assert_filled_cleanly(V, F, V1, F1)
    new = F1[len(F):]
    q = triangle_quality(V1, new)
    assert q.mean() > 0.8 and q.min() > 0.25
    # A flat-ish cap over a hole of radius 0.3 on the unit sphere stays within its sagitta.
    r = np.linalg.norm(V1[len(V):], axis=1)
    assert np.all(r <= 1 + 1e-9) and np.all(r > 1 - 0.06)


def _triangulated_disk_hole():
    """A round hole in a flat grid, its context, its minimum-angle triangulation and loop edges."""
    V, F = grid(20, 20)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.3)
    ctx = _first_hole_context(V, F)
    k = ctx.size
    tri = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    return ctx, tri, loop


def test_relaxation_guard_lets_relaxation_converge_where_the_sector_test_misjudges():
    # Normals that disagree with the patch (here: flipped) make the tangent-plane sector test
    # refuse every swap at the border, as on strongly curved holes filled by a nearly flat patch.
    ctx, tri, loop = _triangulated_disk_hole()
    assert relax_edges(ctx.points, tri, loop)[1] > 0  # the triangulation is not Delaunay yet
    misjudged = dataclasses.replace(ctx, normals=-ctx.normals)
    _, swaps = relax_edges(ctx.points, tri, loop, allowed=patch_guard(misjudged))
    assert swaps == 0
    F, swaps = relax_edges(ctx.points, tri, loop, allowed=relaxation_guard(misjudged))
    assert swaps > 0
    # Converged: no interior edge fails the circumsphere test any more (Sec. III.C).
    assert relax_edges(ctx.points, F, loop)[1] == 0
    assert triangle_quality(ctx.points, F).mean() > triangle_quality(ctx.points, tri).mean()


def test_relaxation_guard_still_refuses_a_swap_through_the_surrounding_mesh():
    ctx, tri, loop = _triangulated_disk_hole()
    # A point outside the hole, over the surrounding faces: new triangles (0, d, 1), (2, 1, d)
    # would lie on top of them; the sector test refuses them and so must the exact check
    # that overrules it. The same swap inside the hole is allowed.
    centre = ctx.points.mean(axis=0)
    guard = relaxation_guard(ctx)
    for where, expected in ((ctx.points[1] + 0.5 * (ctx.points[1] - centre), False),
                            (0.5 * (ctx.points[1] + centre), True)):
        V = np.concatenate([ctx.points, where[None]])
        d = len(V) - 1
        A, B = np.array([[0, d, 1]]), np.array([[2, 1, d]])
        assert guard(V, np.zeros((0, 3), np.int64), A, B, np.zeros((1, 2), np.int64))[0] == expected


# ----------------------------------------------------------------------------- speed-ups kept exact

def test_scalar_sector_test_agrees_with_the_vectorised_one():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import _in_sector
    from meshlab_holefill.algorithms.hu2012.hole_guards import inside_hole_sector

    rng = np.random.default_rng(3)
    agree = 0
    for _ in range(300):
        apex, normal, prev, nxt, target = rng.normal(size=(5, 3))
        expected = bool(inside_hole_sector(apex, normal, prev, nxt, target[None])[0])
        assert _in_sector(*(x.tolist() for x in (apex, normal, prev, nxt, target))) == expected
        agree += expected
    assert 0 < agree < 300  # both outcomes occurred


def _disk_patch(n=6):
    """A flat triangulated disk: loop of 4 n points on a square's border first, grid inside."""
    V, F = grid(n, n)
    loops = boundary_loops(F)
    loop = loops[0].vertices[::-1]  # as the boundary of the grid's own (counter-clockwise) faces
    order = np.concatenate([loop, np.setdiff1d(np.arange(len(V)), loop)])
    inv = np.empty(len(V), np.int64)
    inv[order] = np.arange(len(V))
    return V[order].astype(float), inv[F], len(loop)


def test_embeds_in_projection_accepts_a_flat_disk_and_rejects_a_folded_one():
    from meshlab_holefill.algorithms.hu2012.crossing_test import embeds_in_projection
    from meshlab_holefill.geometry.intersections import intersecting_pairs

    V, F, k = _disk_patch()
    # Orientation of the loop as the patch's boundary: faces are counter-clockwise from +z.
    assert embeds_in_projection(V, F, k)
    bumped = V.copy()
    bumped[k:, 2] = 0.3 * np.sin(7 * bumped[k:, 0])  # a height field still embeds
    assert embeds_in_projection(bumped, F, k)
    # Drag one interior vertex far across its neighbours: the patch folds over itself.
    folded = V.copy()
    centre = k + np.argmin(np.linalg.norm(V[k:, :2] - 0.5, axis=1))
    folded[centre, :2] += [0.45, 0.0]
    assert len(intersecting_pairs(folded, F, np.arange(len(F)), np.arange(len(F)))) > 0
    assert not embeds_in_projection(folded, F, k)


def test_embeds_in_projection_rejects_a_doubly_wound_fan():
    # A fan around a centre that winds twice (a helicoid step): every face keeps its
    # orientation over the plane, yet the surface overlaps itself in projection.
    from meshlab_holefill.algorithms.hu2012.crossing_test import embeds_in_projection

    m = 12
    t = np.linspace(0, 4 * np.pi, m, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), 0.05 * t], axis=1)
    V = np.concatenate([ring, [[0.0, 0.0, 0.3]]])
    F = np.array([[i, (i + 1) % m, m] for i in range(m)])
    assert not embeds_in_projection(V, F, m)



def test_compiled_turn_test_answers_as_the_numpy_code():
    from meshlab_holefill.algorithms.hu2012._projection_kernels import projected_turns
    from meshlab_holefill.algorithms.hu2012.crossing_test import _turns_numpy

    rng = np.random.default_rng(12)
    V, F, k = _disk_patch()
    answers = set()
    for trial in range(60):
        Q = V[:, :2] + rng.normal(scale=10.0 ** rng.uniform(-4, -0.5), size=(len(V), 2))  # folds at large moves
        G = F if trial % 5 else F[1:]  # a face less: a vertex may lose its full turn or every face
        ok, sure = projected_turns(Q, np.ascontiguousarray(G, np.int64), k, 1e-6)
        assert sure and ok == _turns_numpy(Q, G, k)
        answers.add(bool(ok))
    assert answers == {True, False}


# ----------------------------------------------------------------------------- quality and the filter's neighbourhood

def _noisy_grid(noise, seed=1):
    V, F = grid(9, 9)
    V = V.astype(float)
    V[:, 2] = np.random.default_rng(seed).normal(scale=noise, size=len(V))
    movable = np.ones(len(V), bool)
    movable[boundary_loops(F)[0].vertices] = False
    return V, F, movable


def test_bilateral_guard_keeps_every_face_above_its_floor():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F, movable = _noisy_grid(0.1)
    h = 0.125  # grid spacing: sigma_c = 0.1 and sigma_s = 0.5 of it, as the filter's defaults
    q0 = triangle_quality(V, F)
    floor = np.minimum(q0, 0.3)
    plain = bilateral_filter(V, F, movable, 0.1 * h, 0.5 * h, 1)
    assert np.any(triangle_quality(plain, F) < floor - 1e-12)  # the unguarded step makes slivers here
    guarded = bilateral_filter(V, F, movable, 0.1 * h, 0.5 * h, 3, min_quality=0.3)
    # (three iterations: each one's floor is the quality before it, so the first one's bound holds throughout)
    assert np.all(triangle_quality(guarded, F) >= floor - 1e-12)
    assert np.abs(guarded - V).max() > 0.01  # the guard undoes offending moves only
    n0 = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n1 = np.cross(guarded[F[:, 1]] - guarded[F[:, 0]], guarded[F[:, 2]] - guarded[F[:, 0]])
    assert np.all(np.einsum("ij,ij->i", n0, n1) > 0)


def test_bilateral_default_is_unchanged_by_the_new_keywords():
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F, movable = _noisy_grid(0.05)
    a = bilateral_filter(V, F, movable, 0.06, 0.1, 3)
    b = bilateral_filter(V, F, movable, 0.06, 0.1, 3, neighbourhood="ring", fixed_points=V[:4], min_quality=None)
    assert np.array_equal(a, b)


def test_radius_neighbourhood_reaches_the_fixed_surrounding_points():
    # A flat patch with fixed points lifted beside it: only Eq. 4's spatial neighbourhood sees them.
    from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter

    V, F = grid(5, 5)
    V = V.astype(float)
    movable = np.zeros(len(V), bool)
    movable[12] = True  # the centre (0.5, 0.5)
    lifted = np.array([[0.5, 0.5 + 0.3, 0.05], [0.5, 0.5 - 0.3, 0.05]])
    ring = bilateral_filter(V, F, movable, 0.2, 1.0, 1, fixed_points=lifted)
    assert np.array_equal(ring, V)  # 1-ring neighbours are all at z = 0
    spatial = bilateral_filter(V, F, movable, 0.2, 1.0, 1, neighbourhood="radius", fixed_points=lifted)
    assert spatial[12, 2] > 0.005 and np.array_equal(np.delete(spatial, 12, 0), np.delete(V, 12, 0))
    # rho = 2 sigma_c below the grid spacing: no neighbour at all, nothing moves (the literal sigma_c = 0.1 reading).
    tiny = bilateral_filter(V, F, movable, 0.1, 1.0, 1, neighbourhood="radius", fixed_points=lifted)
    assert np.array_equal(tiny, V)


def test_unfolded_relaxation_equals_the_circumcircle_test_in_the_plane_and_converges_on_a_bumpy_patch():
    from meshlab_holefill.geometry.quality import corner_angles
    from meshlab_holefill.geometry.topology import interior_edges

    ctx, tri, loop = _triangulated_disk_hole()
    flat_sphere, _ = relax_edges(ctx.points, tri, loop, criterion="sphere")
    flat_angles, _ = relax_edges(ctx.points, tri, loop, criterion="angles")
    assert np.array_equal(flat_sphere, flat_angles)
    # Lift the loop onto a saddle: the unfolded test leaves no interior edge whose opposite angles exceed pi.
    P = ctx.points.copy()
    P[:, 2] = 3 * (P[:, 0] - 0.5) * (P[:, 1] - 0.5)
    F, swaps = relax_edges(P, tri, loop, criterion="angles")
    assert swaps > 0
    E, f1, c1, f2, c2 = interior_edges(F, len(P))
    A = corner_angles(P, F)
    opposite = A[f1, (c1 + 2) % 3] + A[f2, (c2 + 2) % 3]
    assert np.all(opposite <= np.pi * (1 + 1e-9))


@pytest.fixture(scope="module")
def cow_cut_holes():
    """The benchmark suite's cut holes in pymeshlab's cow.obj (seed 0): contexts and loops."""
    from meshlab_holefill.evaluation.cut_holes import cut_holes, hole_plan

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("cow.obj"))
    V, F = mesh_arrays(ms)
    plan = hole_plan(4, ("small", "medium", "large"))
    _, cut = cut_holes(V, F, sizes=[s for s, _ in plan], shapes=[sh for _, sh in plan], seed=0, strict=False)
    keep = np.ones(len(F), bool)
    keep[np.concatenate([h.face_indices for h in cut])] = False
    F0 = F[keep]
    loops = sorted(boundary_loops(F0), key=lambda lp: -len(lp))
    return V, F0, loops


def test_spiky_cow_hole_gets_no_sliver(cow_cut_holes):
    # The suite's cow hole 0 (22 edges) alternates spikes of 27-40 degrees with concave vertices;
    # with the circumsphere relaxation a triangle joining three concave vertices kept quality 0.276.
    V, F, loops = cow_cut_holes
    loop = next(lp for lp in loops if len(lp) == 22)
    ctx = hole_context(V, F, loop, vertex_face_incidence(F, len(V)), rings=2)
    patch = fill(ctx)
    q = triangle_quality(patch.all_points(ctx.points), patch.faces)
    assert q.min() >= 0.3 and q.mean() > 0.7
    before = fill(ctx, relaxation="sphere")
    assert triangle_quality(before.all_points(ctx.points), before.faces).min() < 0.3


def test_faired_patch_is_relaxed_again():
    # Fairing (option) lifts the refined patch onto the sphere; Sec. III.C's relaxation is then
    # run again, so no interior edge of the result fails the (unfolded) test any more.
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.6)
    ctx = _first_hole_context(V, F)
    k = ctx.size
    patch = fill(ctx, fairing="thinplate", iterations=0)
    X = patch.all_points(ctx.points)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    assert relax_edges(X, patch.faces, loop, allowed=relaxation_guard(ctx), criterion="angles")[1] == 0
    assert triangle_quality(X, patch.faces).min() > 0.5
    assert np.abs(np.linalg.norm(patch.vertices, axis=1) - 1).mean() < 0.02


# ----------------------------------------------------------------------------- tangential smoothing (option)

def test_tangential_smoothing_lifts_a_vertex_off_a_border_edge_and_keeps_the_plane():
    # A square hole split into a fan around an interior vertex pushed next to the bottom edge:
    # the triangle on that edge is flat (no split or swap of Sec. III.C may touch it, the edge
    # being the hole border). Smoothing moves the vertex up, in the plane, and never lowers the
    # smallest quality around it.
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import tangential_smoothing

    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [2, 2, 0], [1, 2, 0], [0, 2, 0], [0, 1, 0],
                  [1.0, 0.1, 0]], float)
    k = 8
    F = np.array([[i, (i + 1) % k, k] for i in range(k)])
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    q0 = triangle_quality(V, F)
    movable = np.arange(len(V)) >= k
    one, _, _ = tangential_smoothing(V, F, movable, 1, fixed=loop, split=False)
    assert triangle_quality(one, F).min() >= q0.min()
    V1, F1, _ = tangential_smoothing(V, F, movable, 10, fixed=loop, split=False)
    assert np.array_equal(V1[:k], V[:k]) and np.abs(V1[:, 2]).max() < 1e-12
    q1 = triangle_quality(V1, F1)
    assert q0.min() < 0.3 and q1.min() > 0.6
    assert np.allclose(V1[k], [1, 1, 0], atol=0.05)
    # With the bisections (the option's default) the patch stays planar and no worse.
    V2, F2, _ = tangential_smoothing(V, F, movable, 10, fixed=loop)
    assert np.abs(V2[:, 2]).max() < 1e-12 and triangle_quality(V2, F2).min() > 0.6


def test_smoothing_is_off_by_default_and_leaves_the_default_patch_alone():
    import inspect

    from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import PARAMS

    assert next(p for p in PARAMS if p.name == "smoothing").default == 0
    assert inspect.signature(fill).parameters["smoothing"].default == 0
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.4)
    ctx = _first_hole_context(V, F)
    a, b = fill(ctx), fill(ctx, smoothing=0)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


@pytest.mark.parametrize("edges", [86, 142])
def test_smoothing_option_lifts_the_slivers_the_refinement_leaves_on_scan_holes(face_scan, edges):
    # face000's holes of 86 and 142 edges: the paper's steps leave centroids next to border
    # edges (min quality 0.298 and 0.211, although no border corner forces a triangle below
    # 0.76 / 0.64); the smoothing option (beyond the paper) lifts them.
    from meshlab_holefill.evaluation.metrics import corner_quality_bound

    V, F, loops = face_scan
    loop = next(lp for lp in loops if len(lp) == edges)
    ctx = hole_context(V, F, loop, vertex_face_incidence(F, len(V)), rings=2)
    assert corner_quality_bound(V, F, loop.vertices) > 0.6
    plain = fill(ctx)
    smoothed = fill(ctx, smoothing=10)
    q0 = triangle_quality(plain.all_points(ctx.points), plain.faces)
    q1 = triangle_quality(smoothed.all_points(ctx.points), smoothed.faces)
    assert q0.min() < 0.3 and q0.mean() < 0.86
    assert q1.min() >= 0.3 and q1.mean() >= 0.9
    validate_patch(smoothed, ctx.points, ctx.forbidden_edges)


def test_bilateral_step_pulls_a_flat_cap_inward_and_fairing_with_smoothing_beats_the_flat_fill():
    # Diagnosis of the distance to the removed surface (Sec. III.D): the filter moves each new
    # vertex toward its neighbours' tangent planes, so on a convex hole it pushes the refined
    # (nearly flat) patch further inside the sphere; the options fairing=thinplate with
    # iterations=0 and smoothing lie closer to the sphere than the plain minimum-angle fill.
    V, F, _ = sphere_with_holes(subdiv=5, centers=[(0, 0, 1)], radius=0.35)
    ctx = _first_hole_context(V, F)
    refined, filtered = fill(ctx, iterations=0), fill(ctx)
    assert np.array_equal(refined.faces, filtered.faces)
    r = lambda p: np.linalg.norm(p.vertices, axis=1)
    assert r(filtered).mean() < r(refined).mean() - 1e-4

    def sphere_gap(patch, samples=6):
        # Mean radial gap over points spread on the patch faces (barycentric grid).
        X = patch.all_points(ctx.points)
        T = X[patch.faces]
        w = [(a, b, samples - a - b) for a in range(samples + 1) for b in range(samples + 1 - a)]
        P = np.concatenate([(a * T[:, 0] + b * T[:, 1] + c * T[:, 2]) / samples for a, b, c in w])
        area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
        return np.average(np.abs(np.linalg.norm(P, axis=1) - 1), weights=np.tile(area, len(w)))

    from meshlab_holefill.core.patch import Patch

    flat = Patch(vertices=np.zeros((0, 3)), faces=min_angle_triangulation(ctx.points, ctx.loop_normals,
                                                                          ctx.forbidden_edges))
    faired = fill(ctx, fairing="thinplate", iterations=0, smoothing=10)
    assert sphere_gap(filtered) > sphere_gap(flat)
    assert sphere_gap(faired) < 0.5 * sphere_gap(flat)
    q = triangle_quality(faired.all_points(ctx.points), faired.faces)
    assert q.min() > 0.5 and q.mean() > 0.9


def test_bisect_obtuse_splits_the_chord_of_an_obtuse_ear():
    # An ear with a 140-degree border corner at vertex 1: its chord (0, 2) is split at its
    # midpoint, which joins vertex 1 to the rest of the patch (no swap or move could).
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import bisect_obtuse

    h = np.tan(np.radians(20))
    V = np.array([[0, 0, 0], [1, -h, 0], [2, 0, 0], [1, 1.5, 0]], float)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    loop = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    q0 = triangle_quality(V, F).min()
    V1, F1, movable, scale = bisect_obtuse(V, F, np.zeros(4, bool), loop, np.array([1.0, 2, 3, 4]))
    assert len(V1) == 5 and np.allclose(V1[4], [1, 0, 0]) and movable.tolist() == [False] * 4 + [True]
    assert scale.tolist() == [1, 2, 3, 4, 2]
    assert len(F1) == 4 and triangle_quality(V1, F1).min() > q0
    n = np.cross(V1[F1[:, 1]] - V1[F1[:, 0]], V1[F1[:, 2]] - V1[F1[:, 0]])
    assert np.all(n[:, 2] > 0)  # orientation kept
    # A fixed chord is never split.
    assert len(bisect_obtuse(V, F, np.zeros(4, bool), np.concatenate([loop, [[0, 2]]]))[0]) == 4


def test_smoothing_option_removes_a_centroid_stuck_in_a_narrow_scan_hole(face_scan):
    # face000's 23-edge hole is a strip about one edge wide: the refinement leaves a centroid
    # next to its 2.2-long border edge (quality 0.117, corner bound 0.50); no tangential move
    # frees it, a collapse (collapse_poor, part of the smoothing option) does.
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import tangential_smoothing

    V, F, loops = face_scan
    loop = next(lp for lp in loops if len(lp) == 23)
    ctx = hole_context(V, F, loop, vertex_face_incidence(F, len(V)), rings=2)
    plain = fill(ctx)
    assert triangle_quality(plain.all_points(ctx.points), plain.faces).min() < 0.15
    X, Fp = plain.all_points(ctx.points), plain.faces
    k = ctx.size
    loop_edges = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    fixed = np.concatenate([loop_edges, ctx.forbidden_edges.reshape(-1, 2)])
    movable = np.arange(len(X)) >= k
    no_collapse, F1, _ = tangential_smoothing(X, Fp, movable, 10, fixed=fixed, split=False)
    assert triangle_quality(no_collapse, F1).min() < 0.3
    smoothed = fill(ctx, smoothing=10)
    q = triangle_quality(smoothed.all_points(ctx.points), smoothed.faces)
    assert q.min() >= 0.3 and q.mean() >= 0.8
    validate_patch(smoothed, ctx.points, ctx.forbidden_edges)


def test_collapse_poor_keeps_the_link_condition_and_fixed_edges():
    # A vertex squeezed against the bottom edge (0, 1) of a fan: it is collapsed into the
    # neighbour that gives the best smallest quality around it; the patch stays a valid disk.
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import collapse_poor
    from meshlab_holefill.core.patch import Patch

    V = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [1, 2.2, 0], [0, 2, 0], [1.0, 0.05, 0], [1.0, 1.2, 0]], float)
    k = 5
    F = np.array([[0, 1, 5], [1, 6, 5], [1, 2, 6], [2, 3, 6], [3, 4, 6], [4, 0, 6], [0, 5, 6]])
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    movable = np.arange(len(V)) >= k
    q0 = triangle_quality(V, F).min()
    V1, F1, m1, a1 = collapse_poor(V, F, movable, loop, np.arange(7.0))
    assert len(V1) == 6 and len(F1) == 5 and a1.tolist() == [0, 1, 2, 3, 4, 6]
    assert triangle_quality(V1, F1).min() > q0
    validate_patch(Patch(vertices=V1[k:], faces=F1), V1[:k], np.zeros((0, 2), np.int64))
    assert np.array_equal(V1[:k], V[:k])  # loop vertices never go
    # Once nothing is poor, nothing changes.
    V2, F2, _, _ = collapse_poor(V1, F1, m1, loop)
    assert np.array_equal(V2, V1) and np.array_equal(F2, F1)


@settings(max_examples=25, deadline=None)
@given(k=st.integers(6, 16), points=st.integers(3, 25), seed=st.integers(0, 10_000), split=st.booleans())
def test_smoothing_option_keeps_the_loop_and_the_disc(k, points, seed, split):
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import tangential_smoothing
    from meshlab_holefill.geometry.quality import face_areas, face_normals

    X, F = random_planar_patch(k, points, seed)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    V2, F2, _ = tangential_smoothing(X, F, np.arange(len(X)) >= k, 5, fixed=loop, split=split)
    assert np.array_equal(V2[:k], X[:k])
    assert np.abs(V2[:, 2]).max() < 1e-12 and np.all(face_normals(V2, F2)[:, 2] > 0)  # no fold, no flip
    assert face_areas(V2, F2).sum() == pytest.approx(face_areas(X, F).sum())  # the same disc, no tear
    if not split:
        assert triangle_quality(V2, F2).min() >= triangle_quality(X, F).min() - 1e-12


def test_reading_parameters_reach_the_filter_and_are_validated(bunny_scan):
    # The readings of Sec. III.C-D are filter parameters (test_filter_contract checks all keywords);
    # bad values are refused before anything runs.
    res = bunny_scan.meshing_close_holes_min_angle_bilateral(relaxation="sphere", neighbourhood="radius", sigma_c=0.5,
                                                              filter_guard=0.0)
    assert res["closed_holes"] == 5
    with pytest.raises(ValueError, match="neighbourhood"):
        bunny_scan.meshing_close_holes_min_angle_bilateral(neighbourhood="sphere")
    with pytest.raises(ValueError, match="filter_guard"):
        bunny_scan.meshing_close_holes_min_angle_bilateral(filter_guard=1.5)


def _refuse_worse_by_full_recompute(V_old, V_new, F, moved):
    """Oracle of tangential_smoothing._refuse_worse: every face's quality recomputed each pass."""
    from meshlab_holefill.geometry.quality import triangle_quality

    n = len(V_old)
    worst_old = np.full(n, np.inf)
    np.minimum.at(worst_old, F.ravel(), np.repeat(triangle_quality(V_old, F), 3))
    n_old = np.cross(V_old[F[:, 1]] - V_old[F[:, 0]], V_old[F[:, 2]] - V_old[F[:, 0]])
    V, moved = V_new.copy(), moved.copy()
    while True:
        n_new = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        q = np.where(np.einsum("ij,ij->i", n_old, n_new) <= 0, -1.0, triangle_quality(V, F))
        worst = np.full(n, np.inf)
        np.minimum.at(worst, F.ravel(), np.repeat(q, 3))
        back = moved & (worst < worst_old - 1e-12)
        if not back.any():
            return V
        V[back] = V_old[back]
        moved &= ~back


def test_refuse_worse_undoes_exactly_the_moves_a_full_recompute_undoes():
    from conftest import grid
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import _refuse_worse
    from meshlab_holefill.geometry.quality import triangle_quality

    rng = np.random.default_rng(0)
    for _ in range(100):
        V, F = grid(int(rng.integers(4, 9)))
        V = np.asarray(V, np.float64)
        V_new = V + rng.normal(size=V.shape) * rng.choice([0.01, 0.1, 0.5])
        moved = rng.random(len(V)) < 0.7
        V_new[~moved] = V[~moved]
        got = _refuse_worse(V, V_new, F, moved)
        np.testing.assert_array_equal(got, _refuse_worse_by_full_recompute(V, V_new, F, moved))
        worst = np.full(len(V), np.inf)
        np.minimum.at(worst, F.ravel(), np.repeat(triangle_quality(got, F), 3))
        worst_old = np.full(len(V), np.inf)
        np.minimum.at(worst_old, F.ravel(), np.repeat(triangle_quality(V, F), 3))
        kept = moved & np.any(got != V, axis=1)
        assert np.all(worst[kept] >= worst_old[kept] - 1e-12)  # no kept move lowers its faces' minimum


def random_loop_sectors(rng):
    """A bumpy loop of 3-29 points around the z axis with noisy normals, and its LoopSectors: (k, P, sectors)."""
    from meshlab_holefill.algorithms.hu2012.hole_guards import LoopSectors

    k = int(rng.integers(3, 30))
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    P = np.stack([np.cos(t), np.sin(t), 0.2 * rng.normal(size=k)], axis=1)
    N = np.array([0.0, 0.0, 1.0]) + 0.3 * rng.normal(size=(k, 3))
    return k, P, LoopSectors(P, N)


def test_compiled_sector_test_answers_as_the_numpy_code():
    rng = np.random.default_rng(8)
    for _ in range(30):
        k, P, sectors = random_loop_sectors(rng)
        i = rng.integers(0, k, 200)
        targets = np.concatenate([rng.normal(size=(190, 3)), P[rng.integers(0, k, 10)]])  # loop points too
        np.testing.assert_array_equal(sectors.contains(i, targets), sectors.contains_numpy(i, targets))


def test_compiled_swap_sector_test_answers_as_the_numpy_code_at_both_ends():
    rng = np.random.default_rng(9)
    for _ in range(30):
        k, P, sectors = random_loop_sectors(rng)
        V = np.concatenate([P, 0.5 * rng.normal(size=(20, 3))])  # loop first, then interior points
        B = np.stack([rng.integers(0, len(V), 200), rng.integers(0, len(V), 200), rng.integers(0, len(V), 200)], 1)
        oracle = np.ones(len(B), bool)
        for end, other in ((B[:, 1], B[:, 2]), (B[:, 2], B[:, 1])):
            on_loop = end < k
            oracle[on_loop] &= sectors.contains_numpy(end[on_loop], V[other[on_loop]])
        assert (~oracle).any() and oracle.any()
        np.testing.assert_array_equal(sectors.swaps_allowed(V, B), oracle)


def test_a_direction_on_the_sector_bound_is_left_to_numpy():
    from meshlab_holefill.algorithms.hu2012._sector_kernels import sector_contains
    from meshlab_holefill.algorithms.hu2012.hole_guards import LoopSectors

    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    sectors = LoopSectors(P, np.tile([0.0, 0.0, 1.0], (3, 1)))
    i = np.array([0, 0])
    targets = np.array([[2.0, 0.0, 0.0], [0.5, 0.5, 0.0]])  # along the next edge (angle 0), and inside
    assert not sector_contains(sectors.points, sectors.u, sectors.w, sectors.limit, i, targets, 0.0)[1]
    np.testing.assert_array_equal(sectors.contains(i, targets, margin=0.0), sectors.contains_numpy(i, targets, 0.0))
    assert sectors.contains(i[1:], targets[1:]).tolist() == [True]


def test_warm_up_loads_every_kernel_of_the_filter():
    from numba.core.registry import CPUDispatcher

    from meshlab_holefill.algorithms.hu2012 import _bilateral_kernels, _min_angle_kernels, _sector_kernels
    from meshlab_holefill.algorithms.hu2012 import _projection_kernels, _relax_kernels, _smoothing_kernels
    from meshlab_holefill.algorithms.hu2012 import min_angle_bilateral
    from meshlab_holefill.geometry import _flip_kernels, _quality_kernels, _refine_kernels

    min_angle_bilateral.warm_up()
    assert min_angle_bilateral.WARM_UP is min_angle_bilateral.warm_up
    for module in (_bilateral_kernels, _min_angle_kernels, _sector_kernels, _projection_kernels, _relax_kernels,
                   _smoothing_kernels, _flip_kernels, _refine_kernels):
        for name in module.__all__:
            kernel = getattr(module, name)
            if isinstance(kernel, CPUDispatcher):
                assert kernel.signatures, f"{module.__name__}.{name} not loaded"
    assert _quality_kernels.triangle_quality_kernel.signatures


def test_remembered_crossing_answers_are_those_of_the_check():
    from meshlab_holefill.algorithms.hu2012.crossing_test import crosses, crosses_uncached
    from meshlab_holefill.core import examples

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=2)
    patch = fill(ctx)
    X = np.concatenate([ctx.points, patch.vertices])
    pierced = X.copy()
    pierced[ctx.size:] = X[ctx.size:][::-1] + [0.05, 0.0, 0.0]  # new vertices shuffled: the patch folds through itself
    for _ in range(2):  # the second round answers from memory
        assert crosses(ctx, X, patch.faces) is False
        assert crosses(ctx, pierced, patch.faces) is True
    assert crosses_uncached(ctx, pierced, patch.faces) is True


# A hole's border at the corner of a subdivided box (pymeshlab's cube, midpoint-subdivided 4 times):
# it runs straight along two creases into the corner (0), whose two border neighbours already
# share a face of the mesh (the forbidden edge (1, 14)).
BOX_CORNER = np.array([[-0.5, -0.5, -0.5], [-0.4375, -0.5, -0.5], [-0.375, -0.5, -0.5], [-0.375, -0.5, -0.4375],
                       [-0.375, -0.5, -0.375], [-0.375, -0.5, -0.3125], [-0.4375, -0.5, -0.25],
                       [-0.5, -0.5, -0.1875], [-0.5, -0.4375, -0.25], [-0.5, -0.375, -0.3125],
                       [-0.5, -0.3125, -0.375], [-0.5, -0.3125, -0.4375], [-0.5, -0.3125, -0.5],
                       [-0.5, -0.375, -0.5], [-0.5, -0.4375, -0.5]])
_S, _C, _H = 0.31622776601683794, 0.9486832980505138, 0.7071067811865475
BOX_CORNER_NORMALS = np.array([[0, 0, -1], [0, 0, -1], [0, -_S, -_C], [0, -1, 0], [0, -1, 0], [0, -1, 0], [0, -1, 0],
                               [-_H, -_H, 0], [-1, 0, 0], [-1, 0, 0], [-1, 0, 0], [-1, 0, 0], [-_S, 0, -_C],
                               [0, 0, -1], [0, 0, -1]], float)


def test_a_loop_the_greedy_ear_order_cannot_close_is_closed_by_the_search():
    import importlib

    from meshlab_holefill.errors import HoleFillError

    module = importlib.import_module("meshlab_holefill.algorithms.hu2012.min_angle_triangulation")
    with pytest.raises(HoleFillError, match="no valid ear left"):  # the paper's greedy order alone
        module.greedy_ear_faces(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]])
    for faces in (min_angle_triangulation(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]]),
                  module.min_angle_triangulation_python(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]])):
        assert faces.shape == (len(BOX_CORNER) - 2, 3)
        P = BOX_CORNER
        assert np.linalg.norm(np.cross(P[faces[:, 1]] - P[faces[:, 0]], P[faces[:, 2]] - P[faces[:, 0]]), axis=1).min() > 1e-3
        directed = {(int(a), int(b)) for f in faces for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
        assert len(directed) == 3 * len(faces)  # no edge used twice in one direction: oriented
        k = len(P)
        assert all((i, (i + 1) % k) in directed for i in range(k))  # every border edge, with the loop's orientation
        assert (1, 14) not in directed and (14, 1) not in directed


def test_a_loop_that_cannot_be_closed_still_raises():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation_python
    from meshlab_holefill.errors import HoleFillError

    collinear = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    with pytest.raises(HoleFillError, match="no valid ear left"):
        min_angle_triangulation_python(collinear, np.tile(UP, (4, 1)))


# ----------------------------------------------------------------------------- fallback (beyond the paper)

@pytest.mark.parametrize("share", [0.1, 0.3])
def test_a_paper_patch_crossing_the_mesh_falls_back_to_the_faired_patch(share):
    """The bunny's bottom cut off by height: a 271- or 292-edge loop whose minimum-angle surface, filtered
    along its normals, crosses the bunny's feet; the faired option set's patch crosses nothing."""
    from meshlab_holefill.algorithms.hu2012.crossing_test import crosses
    from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import FAIRED_OPTIONS, RINGS

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny.obj"))
    V, F = mesh_arrays(ms)
    height = V[F].mean(axis=1)[:, 1]
    F = F[height > np.quantile(height, share)]
    loop = max(boundary_loops(F), key=len)
    assert len(loop) > 250
    ctx = hole_context(V, F, loop, rings=RINGS)
    paper = fill(ctx, fallback=False)
    assert crosses(ctx, paper.all_points(ctx.points), paper.faces)
    patch = fill(ctx)
    assert patch.info["fallback"] == "faired"
    faired = fill(ctx, **FAIRED_OPTIONS)
    assert np.array_equal(patch.vertices, faired.vertices) and np.array_equal(patch.faces, faired.faces)
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(maxholesize=400)
    assert res["closed_holes"] == 1 and res["failed_holes"] == 0
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(maxholesize=400, fallback=False)
    assert res["closed_holes"] == 0 and "intersect" in res["holes"][0]["reason"]


def test_a_patch_that_crosses_nothing_is_the_papers():
    V, F, _ = sphere_with_holes(subdiv=3)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=2)
    patch, paper = fill(ctx), fill(ctx, fallback=False)
    assert patch.info["fallback"] is None
    assert np.array_equal(patch.vertices, paper.vertices) and np.array_equal(patch.faces, paper.faces)


def cut_across(name, axis, share):
    """A sample mesh without the faces reaching below ``share`` of its extent along ``axis``, and its largest loop."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample(name))
    V, F = mesh_arrays(ms)
    h = V[:, axis]
    F = F[V[F, axis].min(axis=1) > h.min() + share * (h.max() - h.min())]
    return V, F, max(boundary_loops(F), key=len)


@pytest.mark.parametrize("name, axis, share, chosen", [("bone.ply", 2, 0.4, "hole plane, faired"),
                                                       ("cow.obj", 0, 0.2, "hole plane")])
def test_a_cut_across_walls_is_triangulated_about_the_holes_plane(name, axis, share, chosen):
    """Cut across, the mesh stands on the hole's plane: its vertex normals lie in that plane, Eq. 2's
    convexity test decides by noise and the triangulation folds over itself or through the walls. About
    the loop's own normal it does not fold, and the patch grown from it crosses nothing (before, the
    hole failed)."""
    from meshlab_holefill.algorithms.hu2012.crossing_test import crosses
    from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import RINGS
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import hole_plane_triangulation
    from meshlab_holefill.array_api import fill_holes
    from meshlab_holefill.geometry.intersections import intersecting_pairs

    V, F, loop = cut_across(name, axis, share)
    ctx = hole_context(V, F, loop, rings=RINGS)
    paper = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    assert crosses(ctx, ctx.points, paper)  # itself (the bone: 67 pairs of its triangles) or the walls (the cow)
    plane = hole_plane_triangulation(ctx.points, ctx.forbidden_edges)
    assert len(intersecting_pairs(ctx.points, plane, np.arange(len(plane)), np.arange(len(plane)))) == 0
    without = fill(ctx, fallback=False)
    assert crosses(ctx, without.all_points(ctx.points), without.faces)
    patch = fill(ctx)
    assert patch.info["fallback"] == chosen
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    V2, F2, res = fill_holes(V, F, "min_angle_bilateral", maxholesize=400)
    assert res["failed_holes"] == 0 and res["holes"][0]["fallback"] == chosen
    assert_filled_cleanly(V, F, V2, F2)


def test_a_loop_without_area_has_no_plane():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import hole_plane_triangulation
    from meshlab_holefill.errors import HoleFillError

    there_and_back = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0.0]])
    with pytest.raises(HoleFillError, match="encloses no area"):
        hole_plane_triangulation(there_and_back)
