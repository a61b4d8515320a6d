"""Hu et al. Sec. III.C-D: the fairing option (beyond the paper) against the flat fill and the bilateral step."""
import numpy as np

from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill, relaxation_guard
from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation
from meshlab_holefill.geometry.flips import relax_edges
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import sphere_with_holes
from hu2012_cases import first_hole_context


def test_fairing_option_brings_a_sphere_hole_closer_to_the_sphere():
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.6)
    ctx = first_hole_context(V, F)
    flat = fill(ctx)
    faired = fill(ctx, fairing="thinplate")
    err = lambda p: np.abs(np.linalg.norm(p.vertices, axis=1) - 1).mean()
    assert err(faired) < 0.5 * err(flat)


def test_faired_patch_is_relaxed_again():
    # Fairing (option) lifts the refined patch onto the sphere; Sec. III.C's relaxation is then
    # run again, so no interior edge of the result fails the (unfolded) test any more.
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.6)
    ctx = first_hole_context(V, F)
    k = ctx.size
    patch = fill(ctx, fairing="thinplate", iterations=0)
    X = patch.all_points(ctx.points)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    assert relax_edges(X, patch.faces, loop, allowed=relaxation_guard(ctx), criterion="angles")[1] == 0
    assert triangle_quality(X, patch.faces).min() > 0.5
    assert np.abs(np.linalg.norm(patch.vertices, axis=1) - 1).mean() < 0.02


def test_bilateral_step_pulls_a_flat_cap_inward_and_fairing_with_smoothing_beats_the_flat_fill():
    # Diagnosis of the distance to the removed surface (Sec. III.D): the filter moves each new
    # vertex toward its neighbours' tangent planes, so on a convex hole it pushes the refined
    # (nearly flat) patch further inside the sphere; the options fairing=thinplate with
    # iterations=0 and smoothing lie closer to the sphere than the plain minimum-angle fill.
    V, F, _ = sphere_with_holes(subdiv=5, centers=[(0, 0, 1)], radius=0.35)
    ctx = first_hole_context(V, F)
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
