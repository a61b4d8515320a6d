"""Xu et al. 2013 Sec. 2.1: the Laplacian, the Sec. 3.3 training set, initial patches and safeguards."""
import numpy as np

from meshlab_holefill.algorithms.xu2013 import laplacian_regression as lr
from meshlab_holefill.algorithms.xu2013.poisson_patch import normalized_cotangent_laplacian
from meshlab_holefill.core.patch import HoleFillError, Patch, validate_patch
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import cut_disks, grid
from xu2013_cases import context_of, fold_case, sphere_hole


def test_normalised_cotangent_laplacian_rows():
    V, F = grid(6, 6, z=lambda x, y: 0.3 * x * y)
    L = normalized_cotangent_laplacian(V, F)
    assert np.allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0)  # Eq. 6: w_ij sum to 1, L_ii = -1
    assert np.allclose(L.diagonal(), -1.0)
    flat, _ = grid(6, 6)
    inner = np.flatnonzero((flat[:, 0] > 0) & (flat[:, 0] < 1) & (flat[:, 1] > 0) & (flat[:, 1] < 1))
    assert np.allclose((normalized_cotangent_laplacian(flat, F) @ flat)[inner], 0.0)  # planar: delta = 0


def test_training_set_is_k_layers_with_laplacians_toward_the_centre():
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    for layers in (1, 2, 3):
        X, delta = lr.training_set(ctx, layers)
        assert len(X) == np.count_nonzero((ctx.depth >= 1) & (ctx.depth <= layers))
        # On the unit sphere the cotangent Laplacian points to the centre (mean curvature normal).
        assert np.all(np.einsum("ij,ij->i", delta, X) < 0)
        cosines = -np.einsum("ij,ij->i", delta, X) / np.linalg.norm(delta, axis=1)
        assert cosines.min() > 0.95
    assert len(lr.training_set(ctx, 2)[0]) > len(lr.training_set(ctx, 1)[0])


def tilted_plane_hole(n=13, radius=0.3):
    """HoleContext of a disk cut from a grid on the plane z = 0.3 x + 0.2 y (a staircase loop)."""
    V, F = grid(n, n, z=lambda x, y: 0.3 * x + 0.2 * y)
    V, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.25)], radius)
    return context_of(V, F, inside=lambda P: np.linalg.norm(P[:, :2] - 0.5, axis=1) < 0.45)  # not the outer border


def tilted_polar_hole(m=24, rings=10, hole=0.42):
    """HoleContext of a polar disc mesh on the plane z = 0.3 x + 0.2 y, the rings inside r = 0.4 cut:
    the loop is a regular m-gon (no collinear edges)."""
    t = 2 * np.pi * np.arange(m) / m
    r = np.linspace(0, 1, rings + 1)[1:]
    P = np.concatenate([[[0.0, 0.0]], (r[:, None, None] * np.stack([np.cos(t), np.sin(t)], 1)).reshape(-1, 2)])
    V = np.column_stack([P, 0.3 * P[:, 0] + 0.2 * P[:, 1]])
    ring = 1 + np.arange(rings * m).reshape(rings, m)
    nxt = np.roll(ring, -1, axis=1)
    F = np.concatenate([np.stack([np.zeros(m, np.int64), ring[0], nxt[0]], 1),
                        np.stack([ring[:-1], ring[1:], nxt[1:]], 2).reshape(-1, 3),
                        np.stack([ring[:-1], nxt[1:], nxt[:-1]], 2).reshape(-1, 3)])
    V, F, _ = cut_disks(V, F, [(0.0, 0.0, 0.0)], hole)
    return context_of(V, F, inside=lambda Q: np.linalg.norm(Q[:, :2], axis=1) < 0.5)


def off_plane(X):
    return np.abs(X[:, 2] - 0.3 * X[:, 0] - 0.2 * X[:, 1]).max()


def test_initial_patches_yield_every_domain_in_order_each_closing_the_hole_on_its_plane():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import initial_patches

    ctx = tilted_polar_hole()
    k = ctx.size
    assert k == 24
    failures = []
    domains = []
    for X, F, stats, layout in initial_patches(ctx, 0.75, failures):
        domains.append(stats["domain"])
        # Loop first and bit-exact: the planar domains are lifted back onto the loop, not left in z = 0.
        assert np.array_equal(X[:k], ctx.points)
        validate_patch(Patch(X[k:], F), ctx.points, ctx.forbidden_edges)
        assert len(X) > k and off_plane(X) < 1e-12  # a planar hole gives a planar patch in every domain
    assert domains == ["3d", "developed", "projected", "ears", "least bend"] and failures == []


def test_initial_patches_fall_back_lazily_and_record_why(monkeypatch):
    from meshlab_holefill.algorithms.xu2013 import poisson_patch as patch_module

    ctx = tilted_polar_hole()
    calls = []
    real = patch_module.advancing_front_triangulation

    def front(P, *args, **kwargs):
        calls.append(kwargs.get("obstacles") is not None)
        if len(calls) == 1:
            raise HoleFillError("front ran out of the hole")
        return real(P, *args, **kwargs)

    monkeypatch.setattr(patch_module, "advancing_front_triangulation", front)
    failures = []
    patches = patch_module.initial_patches(ctx, 0.75, failures)
    assert calls == [] and failures == []  # a generator: nothing runs before it is asked
    X, F, stats, layout = next(patches)
    assert stats["domain"] == "developed" and calls == [True, False]  # only the 3D front and one planar front ran
    assert failures == ["3d advancing front: front ran out of the hole"]
    assert np.array_equal(X[:ctx.size], ctx.points) and off_plane(X) < 1e-12
    validate_patch(Patch(X[ctx.size:], F), ctx.points, ctx.forbidden_edges)


def test_planar_boundaries_offer_the_projection_of_a_planar_hole_with_collinear_edges():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import planar_boundaries
    from meshlab_holefill.geometry.segments import polygon_edges_touch

    # Minimal: a U whose two top edges lie on y = 2, far apart; the polygon is simple.
    U = np.array([[0, 0], [3, 0], [3, 2], [2, 2], [2, 1], [1, 1], [1, 2], [0, 2.0]])
    assert not polygon_edges_touch(U)
    U[6] = [2, 2]  # the right top edge now overlaps the left one's end: they touch
    assert polygon_edges_touch(U)
    # A disk cut from a tilted grid: its loop is a staircase with many collinear edges, and its
    # projection onto its own plane is congruent to it, hence simple.
    ctx = tilted_plane_hole()
    assert [name for name, _ in planar_boundaries(ctx)] == ["developed", "projected"]


def test_swaps_do_not_cut_off_a_worse_ear():
    # Boundary p, v, q with a 146-degree corner at v, inner vertex c: swapping (v, c) to (p, q)
    # would leave the ear (p, v, q), worse than the two triangles it replaces.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import _ear_guard

    V = np.array([[-1.0, 0.0, 0.0], [0.0, 0.3, 0.0], [1.0, 0.0, 0.0], [0.0, -0.6, 0.0]])
    F = np.array([[0, 3, 1], [1, 3, 2]])
    A, B, replaced = np.array([[0, 3, 2]]), np.array([[1, 0, 2]]), np.array([[0, 1]])
    assert triangle_quality(V, B).min() < triangle_quality(V, F).min()
    assert not _ear_guard(3)(V, F, A, B, replaced)[0]   # p, v, q on the hole boundary: refused
    assert _ear_guard(0)(V, F, A, B, replaced)[0]       # inner vertices: left to the Delaunay test
    V2 = np.array([[-1.0, 0.0, 0.0], [0.0, 1.5, 0.0], [1.0, 0.0, 0.0], [0.0, -1.5, 0.0]])
    # A 67-degree corner: the ear is better than the thin pair it replaces, the swap may go.
    assert triangle_quality(V2, B).min() > triangle_quality(V2, F).min()
    assert _ear_guard(3)(V2, F, A, B, replaced)[0]


def test_sliver_repair_leaves_good_patches_alone():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import repair_slivers

    X, F, T, ctx = fold_case()
    fixed = np.arange(len(X)) < ctx.size
    Y, G, kept = repair_slivers(X, F, fixed, ctx, floor=0.3)
    assert triangle_quality(X, F).min() >= 0.3
    assert kept == 0 and Y is X and G is F


SLIT_HOLE = (-0.0938, 0.3015, 0.6943)  # centroid of the noisy cow scan's (seed 2) slit-like 9-edge hole


def test_a_cap_of_loop_vertices_only_is_split_and_smoothed():
    """A noisy range scan's slit-like 9-edge hole, six of whose chords are mesh edges: only its loop-only
    least-bend triangulation stays clear of the mesh, with a loop vertex almost on the chord of two others
    (a cap of 177 degrees, quality 0.002) whose swap would duplicate a mesh edge. No move reaches a
    triangle of loop vertices only: the cap is split, and the split's vertex smoothed."""
    from meshlab_holefill.algorithms.xu2013 import lssvm_poisson
    from meshlab_holefill.core.crossings import context_crossings
    from meshlab_holefill.core.holes import hole_context
    from meshlab_holefill.core.least_bend import least_bend_triangulations
    from conftest import loop_nearest, noisy_cow_scan

    V, F = noisy_cow_scan(2)
    _, loop = loop_nearest(V, F, SLIT_HOLE)
    ctx = hole_context(V, F, loop, rings=lssvm_poisson.RINGS)
    assert ctx.size == 9 and len(ctx.forbidden_edges) == 6
    (loop_only,) = least_bend_triangulations(ctx)
    assert triangle_quality(ctx.points, loop_only).min() < 0.01
    patch = lssvm_poisson.fill(ctx)
    assert patch.info["afm_domain"] == "least bend" and patch.info["sliver_repairs"] >= 1
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    X = patch.all_points(ctx.points)
    assert len(patch.vertices) >= 1 and triangle_quality(X, patch.faces).min() > 0.1
    assert len(context_crossings(ctx, X, patch.faces)) == 0
