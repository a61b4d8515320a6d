"""Curve unfolding: the patch's density matches the surrounding mesh and it leaves no unforced sliver."""

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009 import slivers
from meshlab_holefill.algorithms.brunton2009.slivers import repair_slivers
from meshlab_holefill.geometry.flips import folds
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.patch import Patch, validate_patch
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.metrics import corner_quality_bound
from meshlab_holefill.geometry.quality import edge_lengths, triangle_quality

from conftest import cut_disks, mesh_arrays, sample


def _sphere(subdiv=4):
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    return mesh_arrays(ms)


def _torus():
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=96, vsubdiv=48)
    return mesh_arrays(ms)


def _holes(V, F, centre, radius):
    _, F_cut, _ = cut_disks(V, F, [centre], radius)
    return F_cut, [lp for lp in boundary_loops(F_cut) if lp.closed]


def _fill(V, F, loop, **params):
    ctx = hole_context(V, F, loop, rings=cu.RINGS)
    patch = cu.fill(ctx, **params)
    X = np.concatenate([ctx.points, patch.vertices])
    near = np.isin(F, loop.vertices).any(axis=1)
    ratio = edge_lengths(X, patch.faces).mean() / edge_lengths(V, F[near]).mean()  # as the benchmark's edge ratio
    return ctx, patch, X, float(ratio)


def _assert_density_and_quality(V, F, loop, ctx, patch, X, ratio):
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    assert 0.9 <= ratio <= 1.1
    bound = corner_quality_bound(V, F, loop.vertices)
    assert triangle_quality(X, patch.faces).min() >= min(0.1, bound) - 1e-9


@settings(max_examples=6, deadline=None)
@given(theta=st.floats(0.2, 2.9), phi=st.floats(0.0, 2 * np.pi), radius=st.floats(0.3, 0.7))
def test_sphere_holes_match_the_surrounding_density_without_slivers(theta, phi, radius):
    V, F = _sphere()
    centre = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    F_cut, loops = _holes(V, F, centre, radius)
    loop = max(loops, key=len)
    if len(loop) < 30:  # a patch of a few faces is mostly its border edges: no density to match
        return
    ctx, patch, X, ratio = _fill(V, F_cut, loop, domain="unfolding")
    _assert_density_and_quality(V, F_cut, loop, ctx, patch, X, ratio)
    # The shape is the energy's: on the sphere the patch stays as close as the finer reading's (on one
    # planar domain: the default's choice of domain may differ between the two densities).
    fine = cu.fill(ctx, density="equilateral", domain="unfolding")
    deviation = np.abs(np.linalg.norm(patch.vertices, axis=1) - 1.0).mean()
    fine_deviation = np.abs(np.linalg.norm(fine.vertices, axis=1) - 1.0).mean()
    assert deviation <= 1.25 * fine_deviation + 2e-4


@pytest.mark.parametrize("centre, radius", [((1.4, 0.0, 0.0), 0.35), ((0.0, 1.0, 0.4), 0.3), ((0.6, 0.0, 0.0), 0.3)])
def test_torus_holes_match_the_surrounding_density_without_slivers(centre, radius):
    V, F = _torus()
    F_cut, loops = _holes(V, F, np.asarray(centre, float), radius)
    loop = max(loops, key=len)
    ctx, patch, X, ratio = _fill(V, F_cut, loop)
    _assert_density_and_quality(V, F_cut, loop, ctx, patch, X, ratio)
    assert patch.info["resampled"]
    # Near the torus: the patch's vertices stay within a few per cent of the tube radius.
    tube = np.hypot(np.hypot(patch.vertices[:, 0], patch.vertices[:, 1]) - 1.0, patch.vertices[:, 2]) - 0.4
    assert np.abs(tube).mean() < 0.02


def test_the_previous_reading_is_finer_than_the_surroundings():
    """The measured reason for the default: the equilateral bound leaves a mean edge near 0.8."""
    V, F = _sphere()
    F_cut, loops = _holes(V, F, np.array([0.0, 0.0, 1.0]), 0.6)
    loop = max(loops, key=len)
    _, _, _, ratio_old = _fill(V, F_cut, loop, density="equilateral")
    _, _, _, ratio_twice = _fill(V, F_cut, loop, density="twice")
    _, _, _, ratio_new = _fill(V, F_cut, loop)
    assert ratio_old < 0.88 < ratio_twice and 0.95 <= ratio_new <= 1.05


def test_twice_bound_keeps_every_refined_edge_at_most_twice_the_surrounding_one():
    e = 0.1
    m = 60
    t = np.linspace(0, 2 * np.pi, m, endpoint=False)
    Q = np.c_[np.cos(t), np.sin(t)] * (e / (2 * np.sin(np.pi / m)))
    points, F = tri.refine_planar(Q, e, max_area=tri.area_bound(e, "twice"))
    X = np.c_[points, np.zeros(len(points))]
    assert edge_lengths(X, F).max() <= 2 * e + 1e-12
    assert tri.area_bound(e, "twice") > tri.area_bound(e, "equilateral")


def test_sample_patch_reproduces_the_patch_at_its_own_vertices_and_interpolates_inside():
    Q = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    points, F = tri.refine_planar(Q, 0.3)
    X = np.c_[points, points[:, 0] * 2 + points[:, 1]]  # a plane: barycentric sampling is exact
    targets = np.random.default_rng(0).uniform(0.05, 0.95, (50, 2))
    Y = tri.sample_patch(points, F, X, np.concatenate([points[4:], targets]))
    assert np.allclose(Y[: len(points) - 4], X[4:])
    assert np.allclose(Y[len(points) - 4:, 2], targets[:, 0] * 2 + targets[:, 1])


def test_repair_slivers_lifts_a_cap_pulled_onto_a_border_edge():
    V, F = _sphere(3)
    F_cut, loops = _holes(V, F, np.array([0.0, 0.0, 1.0]), 0.5)
    loop = max(loops, key=len)
    ctx = hole_context(V, F_cut, loop, rings=cu.RINGS)
    patch = cu.fill(ctx, slivers=False)
    X = np.concatenate([ctx.points, patch.vertices])
    k = ctx.size
    # Pull the inner vertex of a border-edge triangle almost onto that edge: a sliver.
    f = next(i for i, t in enumerate(patch.faces) if (t < k).sum() == 2)
    a, b = sorted(patch.faces[f][patch.faces[f] < k])
    v = int(patch.faces[f][patch.faces[f] >= k][0])
    Y = X.copy()
    Y[v] = 0.5 * (X[a] + X[b]) + 0.03 * (X[v] - 0.5 * (X[a] + X[b]))
    q0 = triangle_quality(Y, patch.faces).min()
    assert q0 < 0.1
    V2, F2, rounds = repair_slivers(ctx, Y[k:], patch.faces, lambda W, G: len(crossing_repair.crossing_faces(ctx, W, G)))
    Z = np.concatenate([ctx.points, V2])
    assert rounds > 0 and triangle_quality(Z, F2).min() >= 0.1
    assert not folds(Z, F2)
    validate_patch(type(patch)(vertices=V2, faces=F2), ctx.points, ctx.forbidden_edges)


def test_repair_slivers_leaves_a_good_patch_alone():
    V, F = _sphere(3)
    F_cut, loops = _holes(V, F, np.array([0.0, 0.0, 1.0]), 0.5)
    ctx = hole_context(V, F_cut, max(loops, key=len), rings=cu.RINGS)
    patch = cu.fill(ctx)
    V2, F2, rounds = repair_slivers(ctx, patch.vertices, patch.faces, lambda W, G: 0, floor=0.05)
    assert rounds == 0 and V2 is patch.vertices and F2 is patch.faces


def test_a_loop_only_patchs_cap_is_split_and_its_vertex_moved():
    """A noisy range scan's slit-like 9-edge hole closes on its loop-only least-bend triangulation, with a loop
    vertex almost on the chord of two others (a cap of quality 0.002) whose swap would duplicate a mesh edge:
    the repair has no inner vertex to move, so the cap is split first."""
    from meshlab_holefill.core.crossings import context_crossings
    from meshlab_holefill.core.least_bend import least_bend_triangulations
    from conftest import loop_nearest, noisy_cow_scan

    V, F = noisy_cow_scan(2)
    _, loop = loop_nearest(V, F, (-0.0938, 0.3015, 0.6943))  # the slit-like 9-edge hole
    ctx = hole_context(V, F, loop, rings=cu.RINGS)
    assert ctx.size == 9
    (loop_only,) = least_bend_triangulations(ctx)
    assert triangle_quality(ctx.points, loop_only).min() < 0.01
    V2, F2, rounds = repair_slivers(ctx, np.zeros((0, 3)), loop_only,
                                    lambda W, G: len(crossing_repair.crossing_faces(ctx, W, G)))
    Z = np.concatenate([ctx.points, V2])
    assert rounds >= 1 and len(V2) >= 1 and triangle_quality(Z, F2).min() > 0.1
    validate_patch(Patch(vertices=V2, faces=F2), ctx.points, ctx.forbidden_edges)
    assert len(context_crossings(ctx, Z, F2)) == 0
    patch = cu.fill(ctx)
    assert patch.info["fallback"] == "least bend"
    assert triangle_quality(patch.all_points(ctx.points), patch.faces).min() > 0.1


def _largest_cut_hole(name, subdivisions, seed):
    """A pymeshlab sample Loop-subdivided, with the holes ``scripts/large_holes.py`` cuts for ``seed``:
    (V, the faces left, the longest boundary loop)."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample(name))
    ms.meshing_surface_subdivision_loop(iterations=subdivisions, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=("irregular", "irregular", "large"), seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    F_cut = F[~removed]
    return V, F_cut, max(boundary_loops(F_cut), key=len)


@pytest.fixture(scope="module")
def folded_tail_hole():
    """airplane.obj Loop-subdivided once, its 296-edge hole over the tail (cut_holes seed 1): the patch
    folds near the tail, and a sliver sits on a border edge there."""
    V, F_cut, loop = _largest_cut_hole("airplane.obj", 1, seed=1)
    assert len(loop) == 296
    ctx = hole_context(V, F_cut, loop, rings=cu.RINGS)
    return ctx, cu.fill(ctx, slivers=False)


def test_repair_slivers_withdraws_the_moves_that_cross_the_mesh(folded_tail_hole, monkeypatch):
    ctx, patch = folded_tail_hole
    X = np.concatenate([ctx.points, patch.vertices])
    assert triangle_quality(X, patch.faces).min() < 0.1
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0

    def count(W, G):
        return len(crossing_repair.crossing_faces(ctx, W, G))

    V2, F2, rounds = repair_slivers(ctx, patch.vertices, patch.faces, count)
    Z = np.concatenate([ctx.points, V2])
    assert rounds > 0 and triangle_quality(Z, F2).min() >= 0.3
    assert count(V2, F2) == 0
    validate_patch(type(patch)(vertices=V2, faces=F2), ctx.points, ctx.forbidden_edges)
    # Without the withdrawals every round crosses the mesh there and the sliver stays.
    monkeypatch.setattr(slivers, "WITHDRAWALS", 0)
    V3, F3, rounds = repair_slivers(ctx, patch.vertices, patch.faces, count)
    assert rounds == 0 and triangle_quality(np.concatenate([ctx.points, V3]), F3).min() < 0.1


def test_withdrawn_moves_are_those_that_started_within_an_edge_of_a_crossing_face():
    crossing = np.array([[0, 1, 2]])
    V_new = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    V = np.array([[0.5, 0.5, 0.5], [2.2, 0, 0], [3.0, 3.0, 0], [0.0, 0.0, -1.4]])
    # longest edge sqrt(2): within it of a corner are the first and last vertices only
    assert slivers._withdrawn_near(V, V_new, crossing).tolist() == [True, True, False, True]


def test_a_sampled_patch_that_crosses_the_mesh_is_embedded_again():
    # cow.obj Loop-subdivided twice, its 308-edge hole of cut_holes seed 2: the patch embedded on its
    # planar domain folds (190 faces crossing the mesh) until the swaps' solves unfold it, and the
    # patch sampled from it at the surrounding density inherits the fold.
    V, F_cut, loop = _largest_cut_hole("cow.obj", 2, seed=2)
    assert len(loop) == 308
    ctx, patch, X, ratio = _fill(V, F_cut, loop)
    assert patch.info["resampled"] == "embedded"
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    assert ratio > 0.8  # the unsampled patch's is 0.52
    assert triangle_quality(X, patch.faces).min() >= min(0.1, corner_quality_bound(V, F_cut, loop.vertices))
