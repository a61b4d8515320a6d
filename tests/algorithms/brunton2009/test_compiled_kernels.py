"""Curve unfolding's compiled and direct constructions against the numpy / scipy code they replace (same bits)."""

import numpy as np
import pytest

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import quality_swaps
from meshlab_holefill.algorithms.brunton2009 import embedding as emb
from meshlab_holefill.algorithms.brunton2009 import tangential_relaxation as tr
from meshlab_holefill.algorithms.brunton2009 import umbrella
from meshlab_holefill.core import examples
from meshlab_holefill.core.holes import boundary_loops, hole_context

from conftest import sphere_with_holes


def _joint_system_inputs(ctx, interior_faces, interior):
    k, n_ctx = ctx.size, len(ctx.vertices)
    faces = np.where(interior_faces < k, interior_faces, interior_faces - k + n_ctx)
    X = np.concatenate([ctx.vertices, interior])
    joint = np.concatenate([ctx.faces, faces])
    free = np.arange(len(X)) >= n_ctx
    free = np.flatnonzero(free)
    is_free = np.zeros(len(X), bool)
    is_free[free] = True
    star = joint[is_free[joint].any(axis=1)]
    frames = tr.tangent_frames(tr.vertex_normals(X, star)[free])
    return star, X, free, frames


def _filled_patches():
    """Hole contexts with their default patches: the bowl's round hole and two holes cut in a sphere."""
    V, F, loop = examples.bowl_with_hole()
    contexts = [hole_context(V, F, loop, rings=cu.RINGS)]
    V, F, _ = sphere_with_holes()
    contexts += [hole_context(V, F, loop, rings=cu.RINGS) for loop in boundary_loops(F)]
    return [(ctx, cu.fill(ctx)) for ctx in contexts]


def _same_sparse(A, B):
    A, B = A.tocsc(), B.tocsc()
    return (A.shape == B.shape and np.array_equal(A.indptr, B.indptr) and np.array_equal(A.indices, B.indices)
            and np.array_equal(A.data, B.data))


@pytest.mark.parametrize("subset", ["all", "half", "shuffled"])
def test_tangential_system_direct_equals_scipy_construction(subset):
    # The compiled structure (free_umbrella) with numpy's values gives the matrix and the umbrellas
    # of scipy's general construction to the last bit: the same arrays go to SuperLU.
    rng = np.random.default_rng(0)
    checked = 0
    for ctx, patch in _filled_patches():
        if len(patch.vertices) == 0:
            continue
        star, X, free, frames = _joint_system_inputs(ctx, patch.faces, patch.vertices)
        if subset != "all":  # a part of the vertices free, in any order, with any frames
            free = free[::2] if subset == "half" else rng.permutation(free)
            frames = tuple(rng.standard_normal((len(free), 3)) for _ in range(2))
            is_free = np.zeros(len(X), bool)
            is_free[free] = True
            star = star[is_free[star].any(axis=1)]
        A, U = tr.tangential_system(star, X, free, frames)
        A_ref, U_ref = tr.tangential_system(star, X, free, frames, direct=False)
        assert _same_sparse(A, A_ref)
        assert np.array_equal(U, U_ref)
        Wf = umbrella.umbrella_operator(star, len(X))[free]
        assert np.allclose(U, Wf @ X)
        checked += 1
    assert checked >= 2


def test_tangential_system_takes_the_general_construction_for_degenerate_faces():
    X = np.random.default_rng(1).standard_normal((5, 3))
    star = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [4, 4, 1]])
    free = np.array([4])
    frames = tr.tangent_frames(np.array([[0.0, 0.0, 1.0]]))
    A, U = tr.tangential_system(star, X, free, frames)
    A_ref, U_ref = tr.tangential_system(star, X, free, frames, direct=False)
    assert _same_sparse(A, A_ref) and np.array_equal(U, U_ref)


def test_tangential_kernels_equal_numpy():
    # The relaxation's compiled steps against the numpy they replace, to the last bit.
    from meshlab_holefill.algorithms.brunton2009 import _tangential_kernels as K
    from meshlab_holefill.geometry.quality import cross_rows

    rng = np.random.default_rng(2)
    checked = 0
    for ctx, patch in _filled_patches():
        if len(patch.vertices) == 0:
            continue
        star, X, free, frames = _joint_system_inputs(ctx, patch.faces, patch.vertices)
        k, n_ctx = ctx.size, len(ctx.vertices)
        joint = np.concatenate([ctx.faces, np.where(patch.faces < k, patch.faces, patch.faces - k + n_ctx)])
        assert np.array_equal(K.faces_touching(joint, free, len(X)), star)
        b1, b2 = K.free_frames(X, star, free)
        assert np.array_equal(b1, frames[0]) and np.array_equal(b2, frames[1])
        assert np.array_equal(K.face_cross(X, star), cross_rows(X[star[:, 1]] - X[star[:, 0]],
                                                                 X[star[:, 2]] - X[star[:, 0]]))
        Wf = umbrella.umbrella_operator(star, len(X))[free]
        assert np.array_equal(K.rows_times(Wf.indptr.astype(np.int64), Wf.indices, Wf.data, X), Wf @ X)
        r, c = rng.integers(0, len(free), 50), rng.integers(0, len(free), 50)
        left, right = K.frame_pairs(b1, b2, r, c)
        blocks = [(b1, b1), (b1, b2), (b2, b1), (b2, b2)]
        assert np.array_equal(left, np.concatenate([bi[r] for bi, _ in blocks]))
        assert np.array_equal(right, np.concatenate([bj[c] for _, bj in blocks]))
        checked += 1
    assert checked >= 2
    # Degenerate normals: a zero normal gives zero frames, as numpy's.
    X = np.zeros((4, 3))
    star = np.array([[0, 1, 2], [0, 2, 3]])
    free = np.array([0, 2])
    b1, b2 = K.free_frames(X, star, free)
    ref = tr.tangent_frames(tr.vertex_normals(X, star)[free])
    assert np.array_equal(b1, ref[0]) and np.array_equal(b2, ref[1])


def _running_best(start, rounds, base, count):
    """The swaps' rule as a running best: a round is kept when it scores above the best so far and
    crosses no more than the input (the reference of ``_best_round``)."""
    best = (start, "input")
    for sc, r in rounds:
        if sc > best[0] and count(r) <= base:
            best = (sc, r)
    return best[1]


@pytest.mark.parametrize("seed", range(6))
def test_best_swap_round_is_the_running_best(seed):
    # Scores with ties and crossing counts drawn at random: the best-first search keeps the
    # round the running best keeps, and counts fewer patches.
    rng = np.random.default_rng(seed)
    start = (0.2, 0.5)
    rounds = [((float(rng.choice([0.1, 0.3, 0.4])), float(rng.choice([0.5, 0.6]))), r) for r in range(4)]
    crossing = {r: int(rng.integers(0, 3)) for r in range(4)}
    base = int(rng.integers(0, 3))
    counted = []

    def count(interior, F):
        counted.append(interior)
        return base if interior == "input" else crossing[interior]

    better = [(sc, r, r, np.zeros((0, 3), np.int64), r + 1) for sc, r in rounds if sc > start]
    kept, _, swaps = quality_swaps._best_round(None, better, "input", None, None, count)
    assert kept == _running_best(start, rounds, base, lambda r: crossing[r])
    assert swaps == (0 if kept == "input" else kept + 1)
    assert len(counted) <= len(better) + 1


def _random_loops(count, seed=0):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        m = int(rng.integers(4, 40))
        t = np.sort(rng.uniform(0.0, 2.0 * np.pi, m))
        radius = rng.uniform(0.3, 1.0, m)  # star-shaped, sometimes self-crossing once tilted out of plane
        yield np.stack([radius * np.cos(t), radius * np.sin(t), rng.normal(0.0, rng.uniform(0.01, 1.0), m)], axis=1)


def test_stage_test_equals_projection_and_simplicity_test():
    # The annealing's stage test against the function it stands for: the same answer, for simple
    # and self-crossing projections and clearances near d_MD.
    from meshlab_holefill.algorithms.brunton2009 import linear_motion
    from meshlab_holefill.geometry.segments import min_segment_distance, nonadjacent_mask

    answers = set()
    for P in _random_loops(300):
        Q = linear_motion.project_to_best_plane(P)[0]
        h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())
        d_md = min_segment_distance(Q)
        for eps in (1e-5 * h, d_md * (1 - 1e-12), d_md, 1.5 * d_md):
            expected = linear_motion.linear_motion_is_simple(Q, eps, 4.0 * h) if eps < 4.0 * h else None
            if expected is None:
                continue
            assert linear_motion.projection_is_simple(P, nonadjacent_mask(len(P)), eps, 4.0 * h) == expected
            answers.add(expected)
    assert answers == {True, False}


def test_keeps_clearance_fails_on_nan():
    from meshlab_holefill.geometry.segments import keeps_clearance
    from meshlab_holefill.geometry.segments import nonadjacent_mask

    Q = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [np.nan, 1.0]])
    assert not keeps_clearance(Q, np.roll(Q, -1, axis=0), nonadjacent_mask(4), 4.0, 1e-5)


def test_area_rows_are_the_rows_touching_a_free_vertex():
    # E_AREA's anchor rows, found from U's structure: the fixed vertices whose umbrella has a
    # non-zero weight on a free vertex (the column slice's absolute row sums), free rows first.
    for ctx, patch in _filled_patches():
        if len(patch.vertices) == 0:
            continue
        star, X, free, _ = _joint_system_inputs(ctx, patch.faces, patch.vertices)
        k, n_ctx = ctx.size, len(ctx.vertices)
        joint = np.concatenate([ctx.faces, np.where(patch.faces < k, patch.faces, patch.faces - k + n_ctx)])
        is_free = np.zeros(len(X), bool)
        is_free[free] = True
        W = umbrella.umbrella_operator(joint, len(X))
        touching = np.asarray(abs(W[:, free]).sum(axis=1)).ravel() > 0
        rows = np.concatenate([free, np.flatnonzero(touching & ~is_free)])
        R = emb.energy_rows(joint, len(X), is_free, order=1, anchors=True)
        expected = W[rows].tocsr()
        assert R.shape == expected.shape and np.array_equal(R.toarray(), expected.toarray())
        assert len(rows) > len(free)  # the loop's rows are there


def _scipy_normal_equations(F, X, is_free):
    """R_f^T R_f and -R_f^T R_c X_c as minimise_embedding_energy builds them from energy_rows (anchors)."""
    R = emb.energy_rows(F, len(X), is_free, order=1, anchors=True).tocsc()
    A = R[:, np.flatnonzero(is_free)].tocsc()
    b = -(R[:, np.flatnonzero(~is_free)] @ X[~is_free])
    return (A.T @ A).tocsc(), A.T @ b


@pytest.mark.parametrize("subset", ["patch", "scattered"])
def test_area_normal_equations_equal_scipy_construction(subset):
    # The compiled normal equations of the least-squares mesh are scipy's to the last bit, and the
    # solve through them gives minimise_embedding_energy's positions.
    from meshlab_holefill.algorithms.brunton2009._embedding_kernels import area_normal_equations

    rng = np.random.default_rng(3)
    checked = 0
    for ctx, patch in _filled_patches():
        if len(patch.vertices) == 0:
            continue
        _, X, free, _ = _joint_system_inputs(ctx, patch.faces, patch.vertices)
        k, n_ctx = ctx.size, len(ctx.vertices)
        joint = np.concatenate([ctx.faces, np.where(patch.faces < k, patch.faces, patch.faces - k + n_ctx)])
        is_free = np.zeros(len(X), bool)
        is_free[free] = True
        if subset == "scattered":  # free vertices anywhere, some of them without a fixed neighbour
            is_free = rng.random(len(X)) < 0.5
        M, rhs = _scipy_normal_equations(joint, X, is_free)
        ok, indptr, indices, data, rhs_k = area_normal_equations(joint, is_free, X)
        assert ok
        assert np.array_equal(indptr, M.indptr) and np.array_equal(indices, M.indices)
        assert np.array_equal(data, M.data) and np.array_equal(rhs_k, rhs)
        R = emb.energy_rows(joint, len(X), is_free, order=1, anchors=True)
        assert np.array_equal(emb.minimise_area_energy(X, joint, is_free), emb.minimise_embedding_energy(X, R, is_free))
        checked += 1
    assert checked >= 2


def test_area_normal_equations_leave_degenerate_and_square_cases_to_scipy():
    from meshlab_holefill.algorithms.brunton2009._embedding_kernels import area_normal_equations

    X = np.random.default_rng(4).standard_normal((5, 3))
    fan = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    centre = np.arange(5) == 4
    assert area_normal_equations(np.array([[0, 1, 4], [4, 4, 1]]), centre, X)[0] is False  # a repeated vertex
    assert area_normal_equations(fan, np.ones(5, bool), X)[0] is False  # every vertex free: no fixed row
    assert area_normal_equations(fan, np.zeros(5, bool), X)[0] is False  # nothing to solve
    assert area_normal_equations(np.zeros((0, 3), np.int64), centre, X)[0] is False
    degenerate = np.concatenate([fan, [[4, 4, 1]]])
    R = emb.energy_rows(degenerate, 5, centre, order=1, anchors=True)
    assert np.array_equal(emb.minimise_area_energy(X, degenerate, centre), emb.minimise_embedding_energy(X, R, centre))


def _best_candidates_numpy(targets, todo, cand, A, B, C, best_score, best_face, best_w):
    """The numpy steps best_candidates replaces (sample_patch's round over the k-d tree's candidates)."""
    a, b, c = A[cand], B[cand], C[cand]
    p = targets[todo][:, None, :]
    v0, v1, v2 = b - a, c - a, p - a
    den = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    den = np.where(den == 0.0, 1e-300, den)
    w1 = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / den
    w2 = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / den
    w = np.stack([1.0 - w1 - w2, w1, w2], axis=-1)
    score = w.min(axis=-1)
    j = np.argmax(score, axis=1)
    rows = np.arange(len(todo))
    better = score[rows, j] > best_score[todo]
    sel = todo[better]
    best_score[sel] = score[rows, j][better]
    best_face[sel] = cand[rows, j][better]
    best_w[sel] = w[rows, j][better]


@pytest.mark.parametrize("seed", range(4))
def test_best_candidates_equal_numpy(seed):
    # Random triangles (some degenerate, some with NaN corners) and points inside, outside, on
    # corners and NaN, over two rounds as sample_patch runs them: the same choices and coordinates.
    from meshlab_holefill.algorithms.brunton2009._sampling_kernels import best_candidates

    rng = np.random.default_rng(seed)
    t, p = 60, 40
    A, B, C = (rng.standard_normal((t, 2)) for _ in range(3))
    C[:5] = A[:5] + 2.0 * (B[:5] - A[:5])  # collinear: den = 0 or rounding
    B[5:8] = A[5:8]
    A[8, 0] = np.nan
    targets = rng.standard_normal((p, 2))
    targets[:6] = A[10:16]  # on corners: ties between triangles
    targets[6, 1] = np.nan
    state = [np.full(p, -np.inf), np.zeros(p, np.int64), np.full((p, 3), np.nan)]
    reference = [x.copy() for x in state]
    for k in (4, 12):
        todo = np.flatnonzero(state[0] < -1e-9)
        assert np.array_equal(todo, np.flatnonzero(reference[0] < -1e-9))
        cand = rng.integers(0, t, (len(todo), k))
        best_candidates(targets, todo, cand, A, B, C, *state)
        _best_candidates_numpy(targets, todo, cand, A, B, C, *reference)
        for x, y in zip(state, reference):
            assert np.array_equal(x.view(np.int64), y.view(np.int64))
