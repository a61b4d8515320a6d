"""Hu et al. Sec. III.C: the relaxation of the refined patch (circumsphere and unfolded tests) and its guard."""
import dataclasses

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.hu2012.hole_guards import patch_guard
from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill, relaxation_guard
from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation
from meshlab_holefill.core.holes import boundary_loops, hole_context, vertex_face_incidence
from meshlab_holefill.geometry.flips import relax_edges
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import cut_disks, grid, mesh_arrays, sample
from hu2012_cases import first_hole_context


def _triangulated_disk_hole():
    """A round hole in a flat grid, its context, its minimum-angle triangulation and loop edges."""
    V, F = grid(20, 20)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.3)
    ctx = first_hole_context(V, F)
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
