"""Hu et al. Sec. III.C-D: the tangential smoothing option (beyond the paper): bisections, collapses, guard."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill
from meshlab_holefill.core.holes import hole_context, vertex_face_incidence
from meshlab_holefill.core.patch import validate_patch
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import random_planar_patch, sphere_with_holes
from hu2012_cases import first_hole_context


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
    ctx = first_hole_context(V, F)
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


def _refuse_worse_by_full_recompute(V_old, V_new, F, moved):
    """Oracle of one step of tangential_smoothing._guarded_moves: every face's quality recomputed each pass."""
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


def test_one_step_undoes_exactly_the_moves_a_full_recompute_undoes():
    from conftest import grid
    from meshlab_holefill.algorithms.hu2012.tangential_smoothing import _guarded_moves
    from meshlab_holefill.geometry.quality import triangle_quality

    rng = np.random.default_rng(0)
    for _ in range(100):
        V, F = grid(int(rng.integers(4, 9)))
        V = np.asarray(V, np.float64)
        d = rng.normal(size=V.shape) * rng.choice([0.01, 0.1, 0.5])
        moved = rng.random(len(V)) < 0.7
        V_new = V + 1.0 * d * moved[:, None]
        got = _guarded_moves(V, d, F, moved, (1.0,))
        np.testing.assert_array_equal(got, _refuse_worse_by_full_recompute(V, V_new, F, moved))
        worst = np.full(len(V), np.inf)
        np.minimum.at(worst, F.ravel(), np.repeat(triangle_quality(got, F), 3))
        worst_old = np.full(len(V), np.inf)
        np.minimum.at(worst_old, F.ravel(), np.repeat(triangle_quality(V, F), 3))
        kept = moved & np.any(got != V, axis=1)
        assert np.all(worst[kept] >= worst_old[kept] - 1e-12)  # no kept move lowers its faces' minimum
