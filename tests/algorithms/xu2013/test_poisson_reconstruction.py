"""Xu et al. 2013 Sec. 2.3/3.4: the Poisson solves (repeats, folds, sliver repair) and context fairing."""
import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.xu2013 import laplacian_regression as lr
from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.algorithms.xu2013 import poisson_patch as pp
from meshlab_holefill.algorithms.xu2013 import poisson_reconstruction as pr
from meshlab_holefill.algorithms.xu2013.advancing_front import advancing_front_triangulation
from meshlab_holefill.algorithms.xu2013.poisson_patch import normalized_cotangent_laplacian
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import cut_disks, grid, mesh_arrays, sample
from xu2013_cases import UP, context_of, fold_case, sphere_hole


def test_poisson_solve_with_zero_laplacian_is_the_membrane():
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    patch = xu.fill(ctx, laplacian_prediction="zero", poisson_boundary="dirichlet", relax=False)
    X = patch.all_points(ctx.points)
    L = normalized_cotangent_laplacian(X, patch.faces)
    inner = np.arange(len(X)) >= ctx.size
    # The solve's weights are the initial patch's, not the result's: check the membrane property loosely.
    assert np.abs(L[inner] @ X).max() < 0.02 * ctx.mean_edge_length


def test_repeated_poisson_solves_converge_to_their_own_weights():
    # Sec. 3.4: L_Vn depends on the positions, so each further solve uses the previous result's
    # weights; the displacement shrinks and the final positions satisfy their own Laplacian system.
    from meshlab_holefill.algorithms.xu2013.poisson_reconstruction import poisson_reposition

    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    patch = xu.fill(ctx, laplacian_prediction="zero", relax=False)
    X, fixed = patch.all_points(ctx.points), np.arange(ctx.size + len(patch.vertices)) < ctx.size
    X[~fixed] += 0.3 * ctx.mean_edge_length * np.random.default_rng(0).normal(size=((~fixed).sum(), 3))
    residuals, changes = [], []
    for iterations in (1, 2, 4, 8):
        Y, G, info = poisson_reposition(X, patch.faces, fixed, None, iterations=iterations)
        assert info["poisson_solves"] == iterations and not info["poisson_rejected"]
        changes.append(info["poisson_last_change"])
        residuals.append(np.abs(normalized_cotangent_laplacian(Y, G)[~fixed] @ Y).max() / ctx.mean_edge_length)
    assert np.all(np.diff(changes) < 0) and np.all(np.diff(residuals) < 0)
    assert residuals[-1] < 0.05 * residuals[0]


def test_poisson_solve_folded_across_one_edge_is_kept_when_a_swap_unfolds_it():
    # The path of 335d403: a solve that turns one quad over is kept with the quad's other diagonal
    # instead of being discarded. The right-hand side is set so that the solve lands exactly on T.
    from meshlab_holefill.geometry.flips import folds

    X, F, T, ctx = fold_case()
    free = np.arange(len(X)) >= ctx.size
    rhs = np.asarray(normalized_cotangent_laplacian(X, F) @ T)[free]
    regressors = [lambda x, d=d: rhs[:, d] for d in range(3)]
    assert not folds(X, F) and folds(T, F)
    Y, G, info = pr.poisson_reposition(X, F, ~free, regressors, relax_ctx=ctx)
    assert not info["poisson_rejected"] and info["poisson_solves"] == 1
    assert np.allclose(Y, T, atol=1e-9)  # the solve is kept ...
    assert not folds(Y, G) and not np.array_equal(np.sort(G, axis=1), np.sort(F, axis=1))  # ... with swapped faces
    assert sorted(map(sorted, G[(G == 10).any(axis=1)].tolist())).count([3, 8, 10]) == 0
    # Without the swaps (no HoleContext) the folded solve is discarded.
    Y0, G0, info0 = pr.poisson_reposition(X, F, ~free, regressors)
    assert info0["poisson_rejected"] and info0["poisson_solves"] == 0
    assert np.array_equal(Y0, X) and np.array_equal(G0, F)


@pytest.fixture(scope="module")
def face_hole_227():
    """face000.ply's largest natural hole (227 edges; the benchmark's face000 hole 1) after Sec. 3.1."""
    from meshlab_holefill.evaluation.metrics import corner_quality_bound

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("rangemaps/face000.ply"))
    V, F = mesh_arrays(ms)
    loop = [lp for lp in boundary_loops(F) if len(lp) == 227][0]
    bound = corner_quality_bound(V, F, loop.vertices)
    ref = xu.prepare_boundary(V, F, [loop], {})
    return hole_context(ref.V, ref.F, ref.loops[0], rings=xu.RINGS), bound


def test_sliver_repair_lifts_the_border_row_the_poisson_solve_squeezes(face_hole_227, monkeypatch):
    # The 3D front leaves this hole, so the filter's patch is the developed boundary's front
    # (fill() takes ~3 s to find that out; this builds that patch directly). The Poisson solve
    # with the square Dirichlet system squeezes the triangles along a stretch of the border;
    # smoothing and swaps alone leave 0.216, while the corner bound is 0.596. The local repair
    # lifts them above 0.3. The boundary rows (the default) do not squeeze that row.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import harmonic_lift, planar_boundaries

    ctx, bound = face_hole_227
    assert bound > 0.5
    D = dict(planar_boundaries(ctx))["developed"]
    new_vertices, F0, _ = advancing_front_triangulation(D, ctx.forbidden_edges, 0.75, reference_normal=UP)
    X0 = harmonic_lift(np.concatenate([D, new_vertices]), F0, ctx.points)
    regressors = lr.fit_laplacian_regressors(*lr.training_set(ctx, 2), 10.0, 0.5)
    X, F, info = pr.reposition(ctx, X0, F0, regressors, 1, True, "dirichlet")
    q = triangle_quality(X, F)
    assert info["sliver_repairs"] >= 1 and info["poisson_damping"] == 1.0
    assert q.min() >= 0.3 and q.mean() >= 0.85
    assert len(pp.context_hits(X, F, ctx)) == 0
    monkeypatch.setattr(pr, "SLIVER_QUALITY", 0.0)  # without the repair
    X1, F1, _ = pr.reposition(ctx, X0, F0, regressors, 1, True, "dirichlet")
    assert triangle_quality(X1, F1).min() < 0.3
    X2, F2, info2 = pr.reposition(ctx, X0, F0, regressors, 1, True)
    assert triangle_quality(X2, F2).min() >= 0.3 and info2["sliver_repairs"] == 0


def patch_of_removed_faces(V, F_kept, F_removed, rings=2):
    """HoleContext of the cut hole and the removed faces as its patch: (ctx, true new vertices, patch faces)."""
    ctx = hole_context(V, F_kept, min(boundary_loops(F_kept), key=len), rings=rings)
    k = ctx.size
    new = np.setdiff1d(np.unique(F_removed), ctx.loop)
    index = np.full(len(V), -1)
    index[ctx.loop], index[new] = np.arange(k), k + np.arange(len(new))
    return ctx, V[new], index[F_removed]


def test_fair_patch_in_context_restores_a_flat_grid_exactly():
    from meshlab_holefill.algorithms.hu2012.fairing import fair_patch_in_context

    # On a regular flat grid every vertex is the mean of its 1-ring, so L x = 0 and L^2 x = 0 hold
    # at the true positions: fairing any start must give them back, flat.
    V, F, removed = cut_disks(*grid(11, 11), [(0.5, 0.5, 0.0)], 0.3)
    ctx, truth, Fp = patch_of_removed_faces(V, F, removed)
    start = truth + np.random.default_rng(0).normal(scale=0.05, size=truth.shape)
    for order in (1, 2):
        out = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, start, Fp, order=order)
        assert out.shape == truth.shape and np.abs(out - truth).max() < 1e-12


def test_fair_patch_in_context_bulges_a_flat_patch_onto_the_sphere():
    from meshlab_holefill.algorithms.hu2012.fairing import fair_patch_in_context

    V, F, removed = sphere_hole(radius=0.5)
    ctx, truth, Fp = patch_of_removed_faces(V, F, removed)
    plane_z = ctx.points[:, 2].mean()
    flat = truth.copy()
    flat[:, 2] = plane_z  # the cap pressed into the loop's plane: up to 0.125 inside the sphere
    assert np.abs(np.linalg.norm(flat, axis=1) - 1).max() > 0.1
    # Thin plate (default order 2): the fixed ring outside the loop carries the sphere's slope in,
    # the patch rises above the loop plane to within 0.01 of the sphere.
    out = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, flat, Fp)
    assert np.abs(np.linalg.norm(out, axis=1) - 1).max() < 0.01
    assert out[:, 2].min() > ctx.points[:, 2].max()
    # The membrane (order 1) only spans the loop: it stays near the plane, far from the sphere.
    membrane = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, flat, Fp, order=1)
    assert np.abs(np.linalg.norm(membrane, axis=1) - 1).max() > 0.1
