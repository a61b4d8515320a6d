"""HPDE Sec. 4.7: Taubin and curvature smoothing, decimation, edge swaps and splits, and vertex moves."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as hpde
from meshlab_holefill.algorithms.xie_zou2013 import folds as hpde_folds, triangulation as hpde_mesh, optimisation as hpde_optimisation, smoothing as hpde_smoothing
from meshlab_holefill.geometry.quality import corner_angles, face_areas
from meshlab_holefill.core.patch import Patch, validate_patch

import hpde_cases
from hpde_cases import check_patch, context, cut, _cyclic, grid_plane, sphere_mesh

sphere_hole = hpde_cases.sphere_hole  # the shared module-scoped fixture


# ----------------------------------------------------------------- step 7: Sec. 4.7

def test_taubin_smoothing_keeps_boundary_and_a_planar_patch_planar():
    V, F = grid_plane(8)
    rng = np.random.default_rng(0)
    fixed = np.zeros(len(V), bool)
    fixed[np.flatnonzero((V[:, 0] % 1 == 0) | (V[:, 1] % 1 == 0))] = True
    W = V.copy()
    W[~fixed, :2] += rng.normal(scale=0.02, size=((~fixed).sum(), 2))
    S = hpde_smoothing.taubin_smooth(W, F, fixed, passes=60)
    assert np.array_equal(S[fixed], W[fixed])
    assert np.abs(S[:, 2]).max() == 0.0
    # Non-shrinking: a bump keeps most of its height (plain Laplacian smoothing would flatten it).
    B = V.copy()
    r2 = ((V[:, :2] - 0.5) ** 2).sum(1)
    B[:, 2] = np.where(fixed, 0, 0.3 * (0.25 - np.minimum(r2, 0.25)))
    S = hpde_smoothing.taubin_smooth(B, F, fixed, passes=60)
    lap = B.copy()
    for _ in range(120):
        lap = hpde_smoothing.taubin_smooth(lap, F, fixed, passes=1, lam=0.33, mu=0.0)
    assert S[:, 2].max() > lap[:, 2].max()


def umbrella_modes(V, F, fixed):
    """Frequencies and modes of K = I - D^-1 A on the free vertices (dense reference), ascending."""
    from meshlab_holefill.geometry.laplacian import adjacency_matrix

    A = adjacency_matrix(F, len(V)).toarray()
    free = np.flatnonzero(~fixed)
    K = np.eye(len(free)) - (A / A.sum(1, keepdims=True))[np.ix_(free, free)]
    w, U = np.linalg.eig(K)
    order = np.argsort(w.real)
    return w.real[order], U.real[:, order]


def test_lowest_dirichlet_frequency_matches_the_dense_spectrum():
    from meshlab_holefill.geometry.laplacian import lowest_dirichlet_frequency

    for n in (8, 24):  # 49 free vertices (dense path) and 529 (sparse shift-invert path)
        V, F = grid_plane(n)
        fixed = (V[:, 0] % 1 == 0) | (V[:, 1] % 1 == 0)
        w, _ = umbrella_modes(V, F, fixed)
        assert lowest_dirichlet_frequency(F, len(V), ~fixed) == pytest.approx(w[0], rel=1e-9)
        assert 0 < w[0] <= 1
    assert np.isnan(lowest_dirichlet_frequency(F, len(V), np.zeros(len(V), bool)))


def test_taubin_pass_band_at_the_lowest_frequency_keeps_the_smoothest_shape_and_damps_the_rest():
    # Sec. 4.7 / ref. [26] with k_PB = k_1: the lowest mode of the patch passes with gain
    # exactly 1, the next one is scaled by f(k_2)^N, f(k) = (1 - lambda k)(1 - mu k) < 1.
    V, F = grid_plane(6)  # 25 free vertices, k_1 = 0.165: a small hole's patch
    fixed = (V[:, 0] % 1 == 0) | (V[:, 1] % 1 == 0)
    w, U = umbrella_modes(V, F, fixed)
    lam = hpde_smoothing.TAUBIN_LAMBDA
    mu = hpde_smoothing.taubin_mu(lam, w[0])
    for mode, gain in ((0, 1.0), (1, ((1 - lam * w[1]) * (1 - mu * w[1])) ** 60)):
        X = V.copy()
        X[~fixed, 2] = 0.1 * U[:, mode] / np.abs(U[:, mode]).max()
        S = hpde_smoothing.taubin_smooth(X, F, fixed, passes=60)
        assert np.allclose(S[:, :2], V[:, :2], atol=1e-12)  # a regular grid has no tangential umbrella
        assert np.allclose(S[:, 2], gain * X[:, 2], atol=1e-9)
    assert gain < 0.9
    # Taubin's closed-surface band (k_PB ~ 0.09 < k_1) damps even the smoothest shape.
    X[~fixed, 2] = 0.1 * U[:, 0] / np.abs(U[:, 0]).max()
    S = hpde_smoothing.taubin_smooth(X, F, fixed, passes=60, mu=-0.34)
    damped = ((1 - lam * w[0]) * (1 + 0.34 * w[0])) ** 60
    assert damped < 0.95 and np.allclose(S[:, 2], damped * X[:, 2], atol=1e-9)
    with pytest.raises(ValueError, match="pass band"):
        hpde_smoothing.taubin_mu(lam, 1.0 / lam)


def test_hpde_default_smoothing_is_taubin_with_the_patch_pass_band():
    names = {p.name: p for p in hpde.PARAMS}
    assert names["smoothing"].default == "taubin" and names["num_smooth"].default == 60
    assert names["taubin_pass_band"].default == 0.0 and names["taubin_lambda"].default == 0.33
    # Every allowed pair gives a valid mu (k_PB < 1 / lambda), so no combination fails mid-run.
    assert names["taubin_pass_band"].maximum < 1.0 / names["taubin_lambda"].maximum
    assert hpde_smoothing.taubin_mu(names["taubin_lambda"].maximum, names["taubin_pass_band"].maximum) < 0


def test_decimation_collapses_short_edges_to_midpoints():
    V, F = grid_plane(6)
    k_boundary = np.flatnonzero((V[:, 0] % 1 == 0) | (V[:, 1] % 1 == 0))
    order = np.r_[k_boundary, np.setdiff1d(np.arange(len(V)), k_boundary)]
    inv = np.argsort(order)
    V, F = V[order], inv[F]
    k = len(k_boundary)
    a = k + 3
    nb = np.unique(F[np.any(F == a, axis=1)])
    b = [x for x in nb if x >= k and x != a][0]
    V2 = V.copy()
    V2[b] = V[a] + 0.05 * (V[b] - V[a])  # one very short interior edge
    mid = 0.5 * (V2[a] + V2[b])
    Vd, Fd, collapses, keep = hpde_optimisation.decimate_short_edges(V2, F, k, 0.05)
    assert collapses == 1 and len(Vd) == len(V) - 1 and len(Fd) == len(F) - 2
    assert np.array_equal(Vd[:k], V2[:k])
    assert np.any(np.all(np.isclose(Vd, mid), axis=1))
    assert np.isin(np.arange(len(Vd)), Fd).all()


def test_edge_swaps_raise_the_minimum_angle():
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.15, 0], [1, -0.15, 0.0]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    F2, swaps = hpde_optimisation.swap_edges_min_angle(V, F)
    assert swaps == 1
    assert corner_angles(V, F2).min() > corner_angles(V, F).min()


def test_edge_swaps_keep_the_shape_of_a_bent_quad():
    # Bent by 108 degrees along (0, 1): the swap would raise the smallest angle (0.337 -> 0.449)
    # but turn the new triangle (1, 2, 3) by about 73 degrees, more than the 60 allowed.
    th = np.radians(108.0)
    V = np.array([[0, 0, 0], [2, 0, 0], [0.8, 1.0, 0], [2.0, -0.7 * np.cos(th), 0.7 * np.sin(th)]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert corner_angles(V, np.array([[0, 3, 2], [1, 2, 3]])).min() > corner_angles(V, F).min()
    F2, swaps = hpde_optimisation.swap_edges_min_angle(V, F)
    assert swaps == 0 and np.array_equal(F2, F)


def test_fold_swaps_repair_folds_only():
    # Triangle (1, 0, 3) lies inside (0, 1, 2) facing the other way: swapping (0, 1) to (2, 3)
    # turns the pair into two triangles facing +z.
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 1, 0], [1, 0.3, 0.0]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert hpde_folds.local_folds(V, F).all()
    F2, swaps = hpde_folds.unfold_by_swaps(V, F)
    assert swaps == 1 and not hpde_folds.local_folds(V, F2).any()
    assert np.all(np.cross(V[F2[:, 1]] - V[F2[:, 0]], V[F2[:, 2]] - V[F2[:, 0]])[:, 2] > 0)
    # A thin pair without a fold is left to the min-angle swaps.
    W = np.array([[0, 0, 0], [2, 0, 0], [1, 0.15, 0], [1, -0.15, 0.0]])
    assert hpde_folds.unfold_by_swaps(W, F)[1] == 0
    assert hpde_optimisation.swap_edges_min_angle(W, F)[1] == 1


def test_forbidden_edges_are_split():
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    V2, F2, n = hpde_mesh.split_forbidden_edges(V, F, [[0, 2]])
    assert n == 1 and len(F2) == 4
    E = np.sort(np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]]), axis=1)
    assert not np.any((E[:, 0] == 0) & (E[:, 1] == 2))


@pytest.mark.parametrize("forbidden", [[[0, 2], [2, 4]], [[2, 4], [0, 2]], [[0, 2], [2, 4], [4, 0]]])
def test_forbidden_edges_sharing_a_triangle_are_split_into_a_disc(forbidden):
    # A hexagon fanned from the triangle (0, 2, 4): its chords may all join loop vertices the mesh
    # joins already. Each split must find its triangles as the earlier splits left them.
    angles = np.arange(6) * np.pi / 3
    V = np.stack([np.cos(angles), np.sin(angles), 0.1 * np.cos(3 * angles)], axis=1)
    F = np.array([[0, 1, 2], [2, 3, 4], [4, 5, 0], [0, 2, 4]])
    V2, F2, n = hpde_mesh.split_forbidden_edges(V, F, forbidden)
    assert n == len(forbidden) and len(F2) == len(F) + 2 * n and len(V2) == len(V) + n
    validate_patch(Patch(vertices=V2[6:], faces=F2), V[:6], forbidden)
    assert np.all(face_areas(V2, F2) > 0)
    assert np.isclose(face_areas(V2, F2).sum(), face_areas(V, F).sum())  # split, not moved


def removed_patch(V, F, center, radius):
    """Cut a round hole and return its context and, as its patch, the removed triangles.

    Returns (ctx, points X with the loop first, faces in patch numbering, number of inner vertices).
    """
    F_cut, removed = cut(V, F, center, radius)
    ctx = context(V, F_cut)
    index = {int(g): i for i, g in enumerate(ctx.global_index[:ctx.size])}
    inner = [int(v) for v in np.unique(removed) if int(v) not in index]
    for j, v in enumerate(inner):
        index[v] = ctx.size + j
    X = np.concatenate([ctx.points, V[inner]])
    return ctx, X, np.vectorize(index.get)(removed).astype(np.int64), len(inner)


def sphere_cap_patch(radius):
    """A hole in the unit sphere and, as its patch, the removed triangles (vertices exactly on the sphere)."""
    return removed_patch(*sphere_mesh(4), (0, 0, 1.0), radius)[:3]


def test_curvature_smoothing_keeps_a_small_sphere_patch_on_the_sphere():
    # Sec. 4.7 / 5.2.2 reading: the smoothing evens out the turning angles; a patch already on
    # the sphere (constant turning) must stay there. Taubin's lambda|mu filter with the loop
    # fixed draws a patch this small towards the flat membrane of the loop (the defect behind
    # HPDE losing to meshing_close_holes on small holes).
    ctx, X, F = sphere_cap_patch(0.25)  # 24 loop edges, like the benchmark's small holes
    k = ctx.size
    assert len(X) - k >= 10
    fixed = np.arange(len(X)) < k
    depth = lambda Y: np.abs(np.linalg.norm(Y[k:], axis=1) - 1.0).mean()  # noqa: E731
    sag = 1.0 - ctx.points[:, 2].mean()  # depth of the flat cap below the sphere
    curv = hpde_smoothing.curvature_smooth(X, F, k, ctx.vertices, ctx.faces, passes=60)
    taubin = hpde_smoothing.taubin_smooth(X, F, fixed, passes=60, mu=-0.34)  # Taubin's example filter
    assert np.array_equal(curv[:k], X[:k])
    assert depth(taubin) > 0.03 * sag > depth(curv)
    assert depth(curv) < 0.25 * depth(taubin)


def flat_hole_patch(radius):
    """A round hole in a flat grid and its removed faces as a patch: (ctx, points X, faces, inner count)."""
    return removed_patch(*grid_plane(30), (0.5, 0.5, 0), radius)


def test_curvature_smoothing_removes_noise_and_keeps_a_plane():
    ctx, X, Fp, n_inner = flat_hole_patch(0.2)
    noisy = X.copy()
    noisy[ctx.size:, 2] = np.random.default_rng(0).normal(0, 0.01, n_inner)
    S = hpde_smoothing.curvature_smooth(noisy, Fp, ctx.size, ctx.vertices, ctx.faces, passes=60)
    assert np.abs(S[ctx.size:, 2]).max() < 0.2 * np.abs(noisy[ctx.size:, 2]).max()
    flat = hpde_smoothing.curvature_smooth(X, Fp, ctx.size, ctx.vertices, ctx.faces, passes=60)
    assert np.abs(flat[:, 2]).max() < 1e-12


def bump_patch(noise=0.0, height=0.05):
    """A flat hole in a grid and a patch on a Gaussian bump inside it (the loop stays flat)."""
    ctx, X, F, n_inner = flat_hole_patch(0.25)
    r2 = ((X[ctx.size:, :2] - 0.5) ** 2).sum(axis=1)
    truth = height * np.exp(-r2 / 0.01)
    X[ctx.size:, 2] = truth + np.random.default_rng(1).normal(0, noise, n_inner)
    return ctx, X, F, truth


def test_anchored_smoothing_keeps_the_prediction_and_removes_jitter():
    # Free second-order smoothing converges on a patch a few edges across to the thin-plate
    # fill of the loop, whatever was predicted (bone.ply's medium hole: 1.05 -> 2.9 per mille
    # after 60 passes). Anchored to the predicted positions it keeps a shape the loop does not
    # imply and still removes the section-plane jitter.
    ctx, X, F, truth = bump_patch(noise=0.004)
    k = ctx.size
    err = lambda Y: np.abs(Y[k:, 2] - truth).mean()  # noqa: E731
    free = hpde_smoothing.curvature_smooth(X, F, k, ctx.vertices, ctx.faces, passes=60)
    anchored = hpde_smoothing.curvature_smooth(X, F, k, ctx.vertices, ctx.faces, passes=60, anchor=0.15)
    assert np.array_equal(anchored[:k], X[:k])
    assert err(free) > 0.3 * truth.mean()  # the bump is mostly gone
    assert err(anchored) < 0.6 * err(X)  # most of the jitter removed
    assert err(anchored) < 0.5 * err(free)
    # Without noise the anchored smoothing barely moves a smooth prediction.
    ctx, X, F, truth = bump_patch(noise=0.0)
    anchored = hpde_smoothing.curvature_smooth(X, F, k, ctx.vertices, ctx.faces, passes=60, anchor=0.15)
    assert np.abs(anchored[k:, 2] - truth).max() < 0.2 * truth.max()


def test_smoothing_anchor_parameter_defaults_and_reaches_the_smoothing(sphere_hole, monkeypatch):
    names = {p.name: p for p in hpde.PARAMS}
    assert names["smoothing_anchor"].default == 0.15 and names["arc_tangent"].default == "secant"
    _, _, _, ctx = sphere_hole
    seen = []
    real = hpde_smoothing.curvature_smooth

    def recording(*args, **kwargs):
        seen.append(kwargs.get("anchor"))
        return real(*args, **kwargs)

    monkeypatch.setattr(hpde_smoothing, "curvature_smooth", recording)
    for anchor in (0.0, 0.4):
        seen.clear()
        patch = hpde.fill(ctx, seed=0, smoothing="curvature", smoothing_anchor=anchor)
        assert seen and set(seen) == {anchor}
        check_patch(ctx, patch)


def test_worst_vertex_moves_lift_a_sliver_on_the_loop():
    # A free vertex almost on a loop edge: no swap can fix the triangle on that edge (the loop
    # edge stays); moving the vertex inward does.
    loop = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 2, 0], [1, 2, 0], [0, 2, 0]], float)
    V = np.vstack([loop, [[1.0, 0.05, 0]]])
    F = np.array([[0, 1, 6], [1, 2, 6], [2, 3, 6], [3, 4, 6], [4, 5, 6], [5, 0, 6]])
    from meshlab_holefill.geometry.quality import triangle_quality

    before = triangle_quality(V, F).min()
    W, moved = hpde_optimisation.improve_worst_vertices(V, F, 6)
    assert moved >= 1 and np.array_equal(W[:6], V[:6])
    assert before < 0.1 and triangle_quality(W, F).min() > 0.5
    assert np.allclose(W[:, 2], 0.0)  # tangential moves keep the plane


# ----------------------------------------------------------------- direct tests of building blocks

def test_split_obtuse_edges_splits_the_long_interior_edge_at_the_quad_centroid():
    from meshlab_holefill.geometry.quality import face_areas, face_normals

    # (0, 1, 2) is flat (157 degrees at 2) on the interior edge (0, 1) shared with (1, 0, 3).
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.2, 0], [1, -1, 0.0]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert np.degrees(corner_angles(V, F).max()) > 150
    V2, F2, splits = hpde_optimisation.split_obtuse_edges(V, F, 4)
    assert splits == 1
    assert np.array_equal(V2[:4], V) and np.allclose(V2[4], [1.0, -0.2, 0.0])  # (a + b + c + d) / 4
    assert {_cyclic(f) for f in F2} == {(0, 4, 2), (1, 4, 3), (1, 2, 4), (0, 3, 4)}
    assert np.all(face_normals(V2, F2)[:, 2] > 0)  # same orientation, no fold
    assert face_areas(V2, F2).sum() == pytest.approx(face_areas(V, F).sum())  # the same quad
    assert np.degrees(corner_angles(V2, F2).max()) < 120
    # A loop edge (one face only) is never split, however flat its triangle.
    V3, F3, splits = hpde_optimisation.split_obtuse_edges(V, F[:1], 3)
    assert splits == 0 and np.array_equal(V3, V) and np.array_equal(F3, F[:1])


def test_remove_valence_three_merges_the_star_and_renumbers():
    # Square 0..3 around centre 5 (valence 4); free vertex 4 splits the face (0, 1, 5) in three.
    V = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [1, 0.3, 0], [1, 1, 0.0]])
    F = np.array([[1, 2, 5], [2, 3, 5], [3, 0, 5], [0, 1, 4], [1, 5, 4], [5, 0, 4]])
    V2, F2, removed, keep = hpde_optimisation.remove_valence_three(V, F, 4)
    assert removed == 1 and keep.tolist() == [0, 1, 2, 3, 5]
    assert np.array_equal(V2, V[[0, 1, 2, 3, 5]])
    # The centre is renumbered 5 -> 4; its star is the three old faces and the merged (0, 1, 4).
    assert sorted(_cyclic(f) for f in F2) == [(0, 1, 4), (0, 4, 3), (1, 2, 4), (2, 3, 4)]
    # Fixed vertices stay, whatever their valence; a forbidden edge in the new triangle refuses too.
    for args in ((V, F, 5), (V, F, 4, [[1, 5]])):
        V3, F3, removed, keep = hpde_optimisation.remove_valence_three(*args)
        assert removed == 0 and np.array_equal(V3, V) and np.array_equal(F3, F) and keep.tolist() == list(range(6))
