"""Curve unfolding: the repair of patches that cross the mesh (other domains, clipped ears, least-bend fallbacks)."""
import os

import numpy as np
import pymeshlab

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009.unfolding import unfold_loop
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.evaluation.metrics import corner_quality_bound
from meshlab_holefill.core.patch import validate_patch
from meshlab_holefill.array_api import fill_holes
from meshlab_holefill.evaluation.mesh_cases import prepare_case
from meshlab_holefill.evaluation.metrics import mesh_checks
from meshlab_holefill.evaluation.virtual_scan import virtual_scan_case

from conftest import grid
from brunton_cases import flat_disk_hole


def test_repair_prefers_a_domain_whose_patch_clears_a_folded_border_to_a_sliver_ear(bunny_loops):
    """bunny10k_textured's loop 1 (22 edges): a border face folds back over the hole at loop vertex 1,
    so the annealed domain's patch crosses it; clipping the ear there leaves a 0.116 sliver (the
    corner is 152 degrees wide), while the 0.2-relaxed development's patch crosses nothing."""
    V, F, loops = bunny_loops
    ctx = hole_context(V, F, loops[1], rings=cu.RINGS)
    assert len(loops[1]) == 22 and corner_quality_bound(V, F, loops[1].vertices) > 0.3
    first, _ = unfold_loop(ctx.points, np.random.default_rng(0))
    X, Fp = tri.triangulate_and_embed(ctx, first, np.arange(ctx.size), [], "fairing", True, True)
    assert len(crossing_repair.crossing_faces(ctx, X, Fp)) > 0  # the paper's patch crosses the fold
    # Ear clipping alone (the first domain only) ends with a sliver ear.
    n_bad, Xe, Fe, clipped, _, _ = crossing_repair.repair_crossings(ctx, [(first, "annealing", None)], X, Fp, "fairing", True, True)
    assert n_bad == 0 and clipped > 0
    assert triangle_quality(np.concatenate([ctx.points, Xe]), Fe).min() < 0.3
    patch = cu.fill(ctx)
    q = triangle_quality(patch.all_points(ctx.points), patch.faces)
    assert patch.info["ears_clipped"] == 0 and patch.info["crossing_faces"] == 0
    assert patch.info["unfolding"] == "development" and patch.info["development_relax"] > 0
    assert q.min() >= 0.3
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0
    validate_patch(patch, ctx.points, ctx.forbidden_edges)


def fill_rest(ctx, Q, keep, ears):
    """Ears plus a plain triangulation of the sub-loop ``keep``: a loop-only patch (Patch numbering)."""
    from meshlab_holefill.geometry.triangulate import triangulate_polygon

    _, T = triangulate_polygon(Q[keep])
    return np.concatenate([np.asarray(ears, np.int64).reshape(-1, 3), np.asarray(keep)[T]])


def test_clip_ears_cuts_exactly_the_convex_corners_of_a_staircase_hole():
    from meshlab_holefill.geometry.triangulate import polygon_signed_area
    from meshlab_holefill.core.patch import Patch

    ctx = flat_disk_hole()
    k, Q = ctx.size, ctx.points[:, :2]
    assert k == 20 and polygon_signed_area(Q) > 0
    # Turn of each corner (counter-clockwise loop): > 0 convex, < 0 reflex, 0 straight.
    d_in, d_out = Q - np.roll(Q, 1, axis=0), np.roll(Q, -1, axis=0) - Q
    turn = np.round(d_in[:, 0] * d_out[:, 1] - d_in[:, 1] * d_out[:, 0], 12)
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(k), [], list(range(k)))
    # Every vertex offends, yet a reflex ear would lie on the mesh and a straight one has no area:
    # exactly the 8 convex corners go, and never two neighbours in one round.
    assert clipped == len(ears) == 8
    assert sorted(e[1] for e in ears) == np.flatnonzero(turn > 0).tolist()
    assert keep.tolist() == np.flatnonzero(turn <= 0).tolist()
    assert all((e[0], e[2]) == ((e[1] - 1) % k, (e[1] + 1) % k) for e in ears)  # (prev, v, next) of the loop
    # The ears and the rest of the loop close the hole once, oriented like the loop.
    validate_patch(Patch(np.zeros((0, 3)), fill_rest(ctx, Q, keep, ears)), ctx.points, ctx.forbidden_edges)
    # Nothing offending, nothing clipped.
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(k), [], [])
    assert clipped == 0 and ears == [] and keep.tolist() == list(range(k))


def test_clip_ears_never_uses_a_chord_the_mesh_already_has():
    from meshlab_holefill.core.patch import Patch

    # A 2 x 2 block of squares cut from a 6 x 6 grid except the triangle (14, 15, 21) of its
    # lower-left square: the loop runs 14 -> 21 -> 15, and the chord (14, 15) is a mesh edge.
    V, F = grid(6, 6)
    cells = [2 * 5 + 2, 2 * 5 + 3, 3 * 5 + 2, 3 * 5 + 3]  # grid() puts the (a, b, c) halves first, then (a, c, d)
    removed = [c for c in cells if c != 12] + [25 + c for c in cells]
    F = np.delete(F, removed, axis=0)
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)
    assert ctx.loop[:3].tolist() == [14, 21, 15] and ctx.forbidden_edges.tolist() == [[0, 2]]
    Q = ctx.points[:, :2]
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(ctx.size), [], [1])
    assert clipped == 0 and ears == [] and keep.tolist() == list(range(ctx.size))
    # With every vertex offending, the corner at 21 still stays; what is clipped closes cleanly.
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(ctx.size), [], list(range(ctx.size)))
    assert clipped > 0 and 1 in keep.tolist() and all(e[1] != 1 for e in ears)
    validate_patch(Patch(np.zeros((0, 3)), fill_rest(ctx, Q, keep, ears)), ctx.points, ctx.forbidden_edges)
    # The rule on its own (that ear above also lies on the mesh face): on the staircase hole the
    # convex corner 0 is clipped unless its chord (19, 1) is declared a mesh edge (as across a
    # thin wall); the other seven convex corners go as before.
    import dataclasses

    ctx = flat_disk_hole()
    walled = dataclasses.replace(ctx, forbidden_edges=np.array([[1, 19]]))
    _, ears, clipped = crossing_repair.clip_ears(ctx, ctx.points[:, :2], np.arange(20), [], list(range(20)))
    assert 0 in [e[1] for e in ears] and clipped == 8
    keep, ears, clipped = crossing_repair.clip_ears(walled, ctx.points[:, :2], np.arange(20), [], list(range(20)))
    assert clipped == 7 and 0 in keep.tolist() and all(e[1] != 0 for e in ears)


def test_a_hole_whose_embedded_patches_all_cross_a_fold_closes_on_its_least_bend_triangulation():
    """A noisy range scan's 80-edge occlusion hole beside a fold of the cow: every embedded patch (the
    domains', then the least-bend triangulations') crosses the fold, which the triangulations
    themselves stay clear of; the last fallback takes a refined triangulation as it is."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes", "cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    direction = np.random.default_rng(1).normal(size=3)
    case = prepare_case(virtual_scan_case("cow scan", V, F, direction, noise=0.15, seed=1))
    (hole,) = [h for h in case.holes if h.index == 8]
    assert hole.boundary_edges == 80
    selected = np.zeros(len(case.F0), bool)
    selected[hole.border[1]] = True  # the faces on its border: only this hole is filled
    V2, F2, result = fill_holes(case.V0, case.F0, "curve_unfolding", selected_faces=selected, selected=True,
                                workers=1)
    entry = result["holes"][8]
    assert entry["status"] == "closed" and entry["fallback"] == "least bend, not embedded"
    assert mesh_checks(case.V0, case.F0, V2, F2)["intersecting_new_faces"] == 0
    assert triangle_quality(V2, F2[len(case.F0):]).min() > 0.1
