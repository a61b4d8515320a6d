"""core.least_bend: the fallback for jagged borders, and the four filters closing a noisy scan's holes with it."""
import functools

import numpy as np
import pytest

from meshlab_holefill import fill_holes
from meshlab_holefill.core.crossings import context_crossings
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.least_bend import least_bend_triangulations
from meshlab_holefill.evaluation.analytic import analytic_mesh
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.noisy import normal_noise

from conftest import assert_filled_cleanly


@functools.lru_cache(maxsize=None)
def noisy_holes(surface, sigma, seed):
    """(V, F): an analytic surface with scan-like noise along its normals and two holes cut (jagged borders)."""
    V, F = analytic_mesh(surface)
    V = normal_noise(V, F, sigma, seed)
    _, holes = cut_holes(V, F, sizes=("large", "irregular"), seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    return V, F[~removed]


def test_each_round_leaves_out_the_triangles_of_the_last_that_crossed_and_stops_at_one_that_crosses_nothing():
    V, F = noisy_holes("sphere", 0.5, 1)
    loop = max(boundary_loops(F), key=lambda lp: len(lp.vertices))
    ctx = hole_context(V, F, loop, rings=3)
    rounds = list(least_bend_triangulations(ctx, rounds=3))
    assert 1 <= len(rounds) <= 3
    for before, after in zip(rounds, rounds[1:]):
        crossed = set(map(tuple, before[context_crossings(ctx, ctx.points, before)].tolist()))
        assert crossed and not crossed & set(map(tuple, after.tolist()))
    if len(rounds) < 3:
        assert len(context_crossings(ctx, ctx.points, rounds[-1])) == 0


def test_a_loop_longer_than_the_cap_gets_no_triangulation(monkeypatch):
    from meshlab_holefill.core import least_bend

    V, F = noisy_holes("sphere", 0.5, 1)
    loop = max(boundary_loops(F), key=lambda lp: len(lp.vertices))
    ctx = hole_context(V, F, loop, rings=3)
    monkeypatch.setattr(least_bend, "MAX_EDGES", ctx.size - 1)
    assert list(least_bend_triangulations(ctx)) == []


@pytest.mark.parametrize("algorithm, surface, sigma, seed", [
    ("min_angle_bilateral", "sphere", 0.5, 1),
    ("curve_unfolding", "sphere", 0.5, 1),
    ("lssvm_poisson", "torus", 0.5, 0),
])
def test_a_hole_with_a_jagged_noisy_border_is_closed_from_the_least_bend_triangulation(algorithm, surface, sigma, seed):
    V, F = noisy_holes(surface, sigma, seed)
    V2, F2, result = fill_holes(V, F, algorithm, workers=1, maxholesize=1000)
    assert result["closed_holes"] == 2
    assert "least bend" in {h.get("fallback") or h.get("afm_domain") for h in result["holes"]}
    assert_filled_cleanly(V, F, V2, F2, faces_kept=algorithm != "lssvm_poisson")  # LS-SVM splits border faces


@functools.lru_cache(maxsize=None)
def noisy_cow(seed, noise_seed=0):
    """(V, F): cow.obj Loop-subdivided twice, noise of 0.3 mean edge lengths along its normals, four holes cut.

    ``noise_seed=seed`` gives the holes of the benchmark's cow_noisy with that seed.
    """
    import pymeshlab

    from conftest import mesh_arrays, sample

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    V = normal_noise(V, F, 0.3, seed=noise_seed)
    _, holes = cut_holes(V, F, sizes=("small", "medium", "large", "irregular"), seed=seed, strict=False)
    return V, np.delete(F, np.concatenate([h.face_indices for h in holes]), axis=0)


def test_hpde_closes_a_long_jagged_loop_by_its_last_resort_on_the_least_bend_triangulation():
    """The benchmark's cow_noisy 307-edge hole: every HPDE layout folds, and the loop is too long for the
    last resort's pre-blocked Liepa triangulation (more than 60 edges)."""
    V, F = noisy_cow(0)
    V2, F2, result = fill_holes(V, F, "differential_evolution", workers=1, maxholesize=1000)
    assert result["closed_holes"] == 4
    assert [h["layout"] for h in result["holes"] if h["boundary_edges"] > 300] == ["loop only"]
    assert_filled_cleanly(V, F, V2, F2)


def test_the_min_angle_filter_closes_a_jagged_loop_from_the_least_bend_triangulation_with_the_faired_set():
    """A 267-edge irregular hole of the noisy cow: the paper's steps from every initial triangulation (its
    own, the faired set's, the least-bend ones) cross the mesh; the faired set grown from the least-bend
    triangulation does not."""
    V, F = noisy_cow(4)
    V2, F2, result = fill_holes(V, F, "min_angle_bilateral", workers=1, maxholesize=1000)
    assert result["closed_holes"] == 4
    assert [h["fallback"] for h in result["holes"] if h["boundary_edges"] > 250] == ["least bend, faired"]
    assert_filled_cleanly(V, F, V2, F2)


def test_the_min_angle_filter_defers_a_hole_plane_start_that_crosses_more_than_its_own():
    """The benchmark's cow_noisy 307-edge hole: the paper's triangulation has 6 faces crossing the mesh, the hole
    plane's 62, so the hole plane comes after the least-bend triangulations (its patches crossed too), and the
    least-bend one closes the hole."""
    from meshlab_holefill.algorithms.hu2012 import min_angle_bilateral
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import (hole_plane_triangulation,
                                                                            min_angle_triangulation)

    V, F = noisy_cow(0)
    loop = max(boundary_loops(F), key=len)
    ctx = hole_context(V, F, loop, rings=min_angle_bilateral.RINGS)
    own = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    plane = hole_plane_triangulation(ctx.points, ctx.forbidden_edges)
    assert 0 < len(context_crossings(ctx, ctx.points, own)) < len(context_crossings(ctx, ctx.points, plane))
    assert not min_angle_bilateral._hole_plane_start(ctx, own)[1]  # tried after the least-bend ones only
    patch = min_angle_bilateral.fill(ctx)
    assert patch.info["fallback"] == "least bend"


def test_hpde_closes_every_hole_of_another_noisy_cut():
    """Seed 2's 165-edge hole: the first layout's chords join loop vertices that the mesh joins, two of them in
    one triangle, and the patch must still be a disc (it had a non-manifold edge there)."""
    V, F = noisy_cow(2, noise_seed=2)
    V2, F2, result = fill_holes(V, F, "differential_evolution", workers=1, maxholesize=1000)
    assert result["closed_holes"] == 4, [h.get("reason") for h in result["holes"]]
    assert_filled_cleanly(V, F, V2, F2)
