"""Hu et al.: the min-angle bilateral filter as a whole: whole-hole fills, MeshSet, parameters, fallback chain."""
import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill
from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.patch import validate_patch
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import (assert_filled_cleanly, assert_one_hole_filled_cleanly, cut_disks, grid, mesh_arrays,
                      meshset_from_arrays, sample, sphere_with_holes)
from hu2012_cases import first_hole_context


def test_fill_of_a_planar_hole_stays_planar_and_matches_density():
    V, F = grid(20, 20)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.25)
    ctx = first_hole_context(V, F)
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
    ctx = first_hole_context(V, F)
    a, b = fill(ctx), fill(ctx)
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)


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
    from meshlab_holefill.core.crossings import context_crossings
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
    # so the plane is tried: fewer of its faces cross the mesh or each other
    assert len(context_crossings(ctx, ctx.points, plane)) < len(context_crossings(ctx, ctx.points, paper))
    without = fill(ctx, fallback=False)
    assert crosses(ctx, without.all_points(ctx.points), without.faces)
    patch = fill(ctx)
    assert patch.info["fallback"] == chosen
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    V2, F2, res = fill_holes(V, F, "min_angle_bilateral", maxholesize=400)
    assert res["failed_holes"] == 0 and res["holes"][0]["fallback"] == chosen
    assert_filled_cleanly(V, F, V2, F2)


def test_a_triangulation_refined_again_gets_the_same_refinement_as_copies():
    """The fallbacks start from triangulations an earlier attempt refined: the refinement is handed out again,
    equal to a fresh one, and changing what a caller got changes nothing for the next."""
    from meshlab_holefill.algorithms.hu2012 import min_angle_bilateral as mab
    from meshlab_holefill.core import examples
    from meshlab_holefill.geometry.topology import boundary_edges_and_chords

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=mab.RINGS)
    F0 = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    fixed = boundary_edges_and_chords(ctx.size, ctx.forbidden_edges)
    fresh = mab._refine(ctx, F0, np.sqrt(2.0), fixed, criterion="angles")
    first = mab._refined(ctx, F0, np.sqrt(2.0), fixed, "angles")
    first[0][:] = 0.0
    first[3]["swaps"] = -1
    again = mab._refined(ctx, F0, np.sqrt(2.0), fixed, "angles")
    for a, b in zip(fresh[:3], again[:3]):
        np.testing.assert_array_equal(a, b)
    assert again[3] == fresh[3]


def test_a_hole_plane_that_crosses_as_much_as_the_papers_triangulation_is_tried_after_the_least_bend_ones():
    """A noisy range scan's 12-edge hole: the paper's triangulation crosses the mesh, the hole plane's
    as much, and each of the three least-bend triangulations' patches crosses too; the hole plane's
    patch, tried last, crosses nothing."""
    from meshlab_holefill.algorithms.hu2012 import min_angle_bilateral
    from meshlab_holefill.array_api import fill_holes
    from conftest import loop_nearest, noisy_cow_scan

    V, F = noisy_cow_scan(2)
    index, loop = loop_nearest(V, F, (-0.0932, 0.3182, 0.7037))
    ctx = hole_context(V, F, loop, rings=min_angle_bilateral.RINGS)
    assert ctx.size == 12
    own = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    plane, first = min_angle_bilateral._hole_plane_start(ctx, own)
    assert plane is not None and not first
    assert min_angle_bilateral.fill(ctx).info["fallback"] == "hole plane"
    selected = np.zeros(len(F), bool)
    selected[loop.border_faces] = True  # the faces on its border: only this hole is filled
    V2, F2, res = fill_holes(V, F, "min_angle_bilateral", selected_faces=selected, selected=True, workers=1)
    assert res["holes"][index]["status"] == "closed" and res["holes"][index]["fallback"] == "hole plane"
    assert_one_hole_filled_cleanly(V, F, V2, F2)
