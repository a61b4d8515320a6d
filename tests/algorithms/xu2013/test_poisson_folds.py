"""Xu et al. 2013, Sec. 3.4: which folds of a Poisson solution discard it, and which the relaxation undoes."""
import numpy as np

from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.algorithms.xu2013 import poisson_reconstruction as pr
from meshlab_holefill.algorithms.xu2013.poisson_patch import solve_folds
from meshlab_holefill.core import examples, hole_context
from meshlab_holefill.geometry.flips import folds


def test_a_fold_between_triangles_of_fixed_vertices_is_not_the_solve_s():
    # Two triangles on the edge (0, 1), vertex 3 on the same side as vertex 2: the second lies
    # turned back over the first (their normals nearly opposite).
    X = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0.9, 0.05]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert folds(X, F)
    assert not solve_folds(X, F, np.ones(4, bool))  # nothing the solve moves
    assert solve_folds(X, F, np.array([True, True, True, False]))  # vertex 3 is the solve's


def test_a_degenerate_triangle_of_fixed_vertices_is_not_the_solve_s():
    X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], float)  # 0, 1, 2 collinear
    F = np.array([[0, 1, 2], [0, 2, 3]])
    assert folds(X, F)
    assert not solve_folds(X, F, np.array([True, True, True, False]))
    assert solve_folds(X, F, np.array([True, False, True, False]))


def bowl_patch():
    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=xu.RINGS)
    patch = xu.fill(ctx)
    X = np.concatenate([ctx.points, patch.vertices])
    return ctx, X, patch.faces


def test_a_vertex_pressed_over_the_border_is_spread_again_by_the_relaxation():
    ctx, X, F = bowl_patch()
    k = ctx.size
    fixed = np.arange(len(X)) < k
    assert not solve_folds(X, F, fixed)
    # Press the free vertex next to loop vertex 0 across the loop, as a solve does at a spike of the border.
    near = [v for v in np.unique(F[np.any(F == 0, axis=1)]) if v >= k]
    v = near[0]
    Y = X.copy()
    Y[v] = X[0] + 0.45 * (X[0] - X[v])  # just beyond the loop vertex, outside the hole
    assert solve_folds(Y, F, fixed)
    Z, G = pr.unfold(Y, F, fixed, relax_ctx=ctx)
    assert Z is not None and not solve_folds(Z, G, fixed)
    assert np.array_equal(Z[:k], X[:k])  # the boundary stays
    assert np.linalg.norm(Z[v] - X[v]) < np.linalg.norm(Y[v] - X[v])  # back towards its place
    # Without the relaxation (relax off) the fold discards the solve.
    assert pr.unfold(Y, F, fixed)[0] is None


def test_a_patch_crossing_itself_counts_as_a_hit_of_the_context():
    # Two triangles of new vertices, hanging below the bowl's hole far from every mesh face,
    # pierce each other: the mesh is not crossed, the patch is.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import context_hits

    ctx, X, F = bowl_patch()
    assert len(context_hits(X, F, ctx)) == 0
    c = ctx.points.mean(axis=0) - np.array([0.0, 0.0, 0.05])
    cross = c + 0.01 * np.array([[-1, 0, 0], [1, 0, 0], [0, 0, 1], [0, -1, -0.5], [0, 1, -0.5], [0, 0, 0.5]])
    base = len(X)
    X2 = np.concatenate([X, cross])
    F2 = np.concatenate([F, base + np.array([[0, 1, 2], [3, 4, 5]])])
    assert context_hits(X2, F2, ctx).tolist() == [len(F), len(F) + 1]


def test_a_fold_the_initial_patch_had_does_not_discard_the_solve(monkeypatch):
    """airplane.obj Loop-subdivided once, a 296-edge hole (``scripts/large_holes.py``'s airplane1_s1 hole 0):
    the lifted development folds a fan into a narrow notch of the border, and every solve kept that fold."""
    import pymeshlab

    from meshlab_holefill.core.holes import boundary_loops
    from meshlab_holefill.evaluation.cut_holes import cut_holes
    from meshlab_holefill.evaluation.metrics import closest_faces

    from conftest import sample

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("airplane.obj"))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
    V, F = np.asarray(ms.current_mesh().vertex_matrix(), np.float64), ms.current_mesh().face_matrix()
    _, holes = cut_holes(V, F, sizes=("irregular", "irregular", "large"), seed=1, strict=False)
    removed = np.zeros(len(F), bool)
    removed[holes[0].face_indices] = True
    kept = F[~removed]
    ctx = hole_context(V, kept, max(boundary_loops(kept), key=len), rings=xu.RINGS)
    assert ctx.size == 296
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))

    def off_surface(patch):
        return closest_faces(patch.vertices, V, F[removed])[0].mean() / diagonal

    patch = xu.fill(ctx)
    assert patch.info["afm_domain"] == "developed" and not patch.info["poisson_rejected"]
    # Judged by every fold, as before, the solves are discarded and the lifted patch is kept.
    monkeypatch.setattr(pr, "solve_folds", lambda X, F, fixed, before=None: solve_folds(X, F, fixed))
    lifted = xu.fill(ctx)
    assert lifted.info["poisson_rejected"] and lifted.info["poisson_solves"] == 0
    assert off_surface(patch) < 0.75 * off_surface(lifted)
