"""The compiled HPDE kernels give bit for bit the numpy / scipy expressions they replace."""
import numpy as np

from meshlab_holefill.algorithms.xie_zou2013 import _de_kernels as K
from meshlab_holefill.algorithms.xie_zou2013 import _optimisation_kernels as KO
from meshlab_holefill.algorithms.xie_zou2013.de_rand_1_bin import reflect_into_bounds


def _problem(rng, B=3, N=7, n=5):
    lower = rng.normal(size=(B, n))
    upper = lower + rng.random((B, n)) * 2.0
    upper[:, -1] = lower[:, -1]  # a fixed (padding) component
    X = lower[:, None, :] + (rng.random((B, N, n)) * 3.0 - 1.0) * (upper - lower + 0.5)[:, None, :]
    return X, lower, upper


def select_variation(X, fX, U, square_sum, total, count, active, angles, trial_angles):
    """Reference (plain Python over the kernels' helpers): Eq. 4 in place with f(U) from its turning-angle sums (:func:`_variation`; count (B,) angles per problem).

    Where U[b, i] is taken, its turning angles trial_angles[b, i] replace angles[b, i] too.
    """
    B, N, n = X.shape
    for b in range(B):
        for i in range(N):
            if active[b, i]:
                f = K._variation(square_sum[b, i], total[b, i], count[b])
                if f <= fX[b, i]:
                    fX[b, i] = f
                    for j in range(n):
                        X[b, i, j] = U[b, i, j]
                    angles[b, i] = trial_angles[b, i]


def reflect_gather_terms(X, lower, upper, active, seg_x, seg_y_add):
    """Reference: Eq. 5 on X and the turning terms of the active individuals it moved, gathered per problem.

    Returns
    -------
    Xr : (B, N, n) reflected X
    order : (B, K) int64  per problem the moved rows first, then the others (both ascending: a
        stable argsort of ~moved), K = the largest number moved
    counts : (B,) int64  rows moved
    cross, dot : (B, K, n + 2) turning terms of Xr[b, order[b]]
    """
    Xr, moved = K.reflect_moved(X, lower, upper)
    B, N, n = X.shape
    counts = np.zeros(B, np.int64)
    for b in range(B):
        for i in range(N):
            moved[b, i] = moved[b, i] and active[b, i]
            if moved[b, i]:
                counts[b] += 1
    order, G = K._gather_moved(Xr, moved, counts)
    cross, dot = K.turning_terms(G, seg_x, seg_y_add)
    return Xr, order, counts, cross, dot


def test_reflect_moved_equals_numpy():
    rng = np.random.default_rng(1)
    X, lower, upper = _problem(rng)
    X[0, 0, 0] = -0.0
    out, moved = K.reflect_moved(X, lower, upper)
    ref = reflect_into_bounds(X, lower, upper)
    assert out.tobytes() == ref.tobytes()
    assert np.array_equal(moved, np.any(ref != X, axis=2))


def test_trial_vectors_and_select_equal_numpy():
    rng = np.random.default_rng(2)
    X, _, _ = _problem(rng)
    B, N, n = X.shape
    r1, r2, r3 = (rng.integers(0, N, (B, N)) for _ in range(3))
    u = rng.random((B, N, n))
    rn = rng.integers(0, n, (B, N))
    F, CR = 0.8, 0.3
    rows = np.arange(B)[:, None]
    V = X[rows, r1] + F * (X[rows, r2] - X[rows, r3])
    take = (u <= CR) | (np.arange(n)[None, None, :] == rn[..., None])
    U_ref = np.where(take, V, X)
    U = K.trial_vectors(X, r1, r2, r3, u, rn, F, CR)
    assert U.tobytes() == U_ref.tobytes()
    fX, fU = rng.random((B, N)), rng.random((B, N))
    fU[0, 0] = fX[0, 0]  # ties select the trial
    active = rng.random((B, N)) < 0.8
    better = (fU <= fX) & active
    X_ref, f_ref = np.where(better[..., None], U, X), np.where(better, fU, fX)
    K.select(X, fX, U, fU, active)
    assert X.tobytes() == X_ref.tobytes() and fX.tobytes() == f_ref.tobytes()


def test_turning_terms_equal_numpy():
    rng = np.random.default_rng(3)
    p, N, m = 4, 6, 5
    Y = rng.normal(size=(p, N, m))
    seg_x = rng.normal(size=(p, m + 3))
    seg_y_add = np.zeros((p, m + 3))
    seg_y_add[:, 0], seg_y_add[:, m + 2] = rng.normal(size=p), rng.normal(size=p)
    # the numpy expression turning_angles used before the kernel
    dy = np.diff(Y, axis=2, prepend=0.0, append=0.0)
    sy = np.concatenate([np.zeros((p, N, 1)), dy, np.zeros((p, N, 1))], axis=2) + seg_y_add[:, None, :]
    sx = seg_x[:, None, :]
    cross_ref = sx[..., :-1] * sy[..., 1:] - sy[..., :-1] * sx[..., 1:]
    dot_ref = sx[..., :-1] * sx[..., 1:] + sy[..., :-1] * sy[..., 1:]
    cross, dot = K.turning_terms(Y, seg_x, seg_y_add)
    assert cross.tobytes() == cross_ref.tobytes() and dot.tobytes() == dot_ref.tobytes()


def _sized_batch(rng):
    """(X, pop, dims) of four problems of different population sizes and used components (one of dimension 1)."""
    X, _, _ = _problem(rng, B=4, N=9, n=6)
    return X, np.array([9, 3, 5, 8], np.int64), np.array([6, 1, 4, 6], np.int64)


def _generation_draws(rng, shape):
    """u_index (3, B, N), u_rn (B, N), u_take (B, N, n): one generation's uniforms, in _Uniforms' order."""
    B, N, n = shape
    return rng.random((3, B, N)), rng.random((B, N)), rng.random((B, N, n))


def test_mutate_crossover_equals_distinct_triples_and_numpy_trial():
    from meshlab_holefill.algorithms.xie_zou2013.de_rand_1_bin import _distinct_triples

    X, pop, dims = _sized_batch(np.random.default_rng(4))
    B, N, n = X.shape
    F, CR = 0.8, 0.05
    u_index, u_rn, u_take = _generation_draws(np.random.default_rng(7), X.shape)
    r1, r2, r3 = _distinct_triples(np.random.default_rng(7), pop, (B, N))  # the same first 3 B N numbers
    assert np.all((r1 != r2) & (r2 != r3) & (r1 != r3))
    assert np.all((r1 < pop[:, None]) & (r2 < pop[:, None]) & (r3 < pop[:, None]))
    rn = np.floor(u_rn * dims[:, None]).astype(np.int64)
    rows = np.arange(B)[:, None]
    V = X[rows, r1] + F * (X[rows, r2] - X[rows, r3])
    take = (u_take <= CR) | (np.arange(n)[None, None, :] == rn[..., None])
    U = K.mutate_crossover(X, u_index, u_rn, u_take, pop, dims, F, CR)
    assert U.tobytes() == np.where(take, V, X).tobytes()


def _chained_batch(rng):
    """A sized batch (:func:`_sized_batch`) with the chain segments of its turning terms: seg_x, seg_y_add (B, n + 3)."""
    X, pop, dims = _sized_batch(rng)
    B, _, n = X.shape
    return X, pop, dims, rng.normal(size=(B, n + 3)), rng.normal(size=(B, n + 3))


def test_trial_changed_terms_are_the_trial_terms_that_differ_from_the_parents():
    # Only the terms next to crossover components are computed; every other term of the trial
    # is its parent's, bit for bit, so the DE run can keep the parent's angle there.
    rng = np.random.default_rng(14)
    X, pop, dims, seg_x, seg_y_add = _chained_batch(rng)
    u_index, u_rn, u_take = _generation_draws(rng, X.shape)
    U, changed, cross, dot = K.trial_changed_terms(X, u_index, u_rn, u_take, pop, dims, 0.8, 0.05, seg_x, seg_y_add)
    # the padding rows, which no selection takes, keep their parents
    active = (np.arange(X.shape[1])[None, :] < pop[:, None])[..., None]
    want = np.where(active, K.mutate_crossover(X, u_index, u_rn, u_take, pop, dims, 0.8, 0.05), X)
    assert U.tobytes() == want.tobytes()
    cross_U, dot_U = K.turning_terms(U, seg_x, seg_y_add)
    cross_X, dot_X = K.turning_terms(X, seg_x, seg_y_add)
    assert np.all(np.diff(changed) > 0) and 0 < len(changed) < cross_U.size
    assert cross.tobytes() == cross_U.ravel()[changed].tobytes() and dot.tobytes() == dot_U.ravel()[changed].tobytes()
    rest = np.setdiff1d(np.arange(cross_U.size), changed)
    assert cross_U.ravel()[rest].tobytes() == cross_X.ravel()[rest].tobytes()
    assert dot_U.ravel()[rest].tobytes() == dot_X.ravel()[rest].tobytes()


def test_trial_changed_terms_into_reused_arrays_gives_the_fresh_result():
    # The DE run hands the same arrays to every generation: what an earlier generation left
    # in them must not show through.
    rng = np.random.default_rng(15)
    X, pop, dims, seg_x, seg_y_add = _chained_batch(rng)
    B, N, n = X.shape
    size = B * N * (n + 2)
    U, changed, cross, dot = np.full_like(X, np.nan), np.full(size, -7, np.int64), np.full(size, np.nan), \
        np.full(size, np.nan)
    for _ in range(2):
        draws = _generation_draws(rng, X.shape)
        fresh = K.trial_changed_terms(X, *draws, pop, dims, 0.8, 0.05, seg_x, seg_y_add)
        c = K.trial_changed_terms_into(X, *draws, pop, dims, 0.8, 0.05, seg_x, seg_y_add, U, changed, cross, dot)
        assert c == len(fresh[1])
        active = np.arange(N)[None, :] < pop[:, None]
        assert U[active].tobytes() == fresh[0][active].tobytes() and np.isnan(U[~active]).all()
        assert changed[:c].tobytes() == fresh[1].tobytes()
        assert cross[:c].tobytes() == fresh[2].tobytes() and dot[:c].tobytes() == fresh[3].tobytes()


def test_uniform_blocks_equal_per_generation_draws():
    import importlib

    D = importlib.import_module("meshlab_holefill.algorithms.xie_zou2013.de_rand_1_bin")
    shape, generations = (3, 5, 4), 7
    blocked = D._Uniforms(np.random.default_rng(9), shape, generations)
    old_block = D.BLOCK_DOUBLES
    try:
        D.BLOCK_DOUBLES = 3 * blocked.ends[2]  # blocks of 3 generations: 3 + 3 + 1
        blocked = D._Uniforms(np.random.default_rng(9), shape, generations)
        reference = np.random.default_rng(9)
        for _ in range(generations):
            got = blocked.next()
            want = (reference.random((3, 3, 5)), reference.random((3, 5)), reference.random((3, 5, 4)))
            assert all(a.tobytes() == b.tobytes() for a, b in zip(got, want))
        assert blocked.rng.random() == reference.random()  # no number drawn beyond the last generation
    finally:
        D.BLOCK_DOUBLES = old_block


def test_patch_lowest_frequency_matches_dense_spectrum():
    import pymeshlab

    from meshlab_holefill.algorithms.xie_zou2013 import smoothing
    from meshlab_holefill.geometry.laplacian import adjacency_matrix, lowest_dirichlet_frequency

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=4)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    A = adjacency_matrix(F, len(V))
    for height in (0.3, 0.7, 0.9, 0.97):  # caps of 900 down to 37 free vertices, loop fixed
        free = V[:, 2] > height
        got = smoothing.patch_lowest_frequency(F, len(V), free, A)
        want = lowest_dirichlet_frequency(F, len(V), free, adjacency=A)
        assert 0.0 < got <= 1.0
        assert abs(got - want) <= 1e-10 * want
        if free.sum() <= smoothing.DENSE_SPECTRUM_MAX:
            assert got == want


def test_independent_link_edges_equal_sparse_expression():
    import importlib

    import pymeshlab
    import scipy.sparse as sp

    from meshlab_holefill.geometry.quality import unique_edges

    O = importlib.import_module("meshlab_holefill.algorithms.xie_zou2013.optimisation")
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix().astype(np.int64)
    F = F[V[F].mean(axis=1)[:, 2] > -0.3]  # an open cap: border edges fail the link condition
    n = len(V)
    E, A = O.adjacency(F, n)
    assert np.array_equal(E, unique_edges(F))
    R = (A + sp.identity(n, dtype=np.int8, format="csr")).tocsr()
    rng = np.random.default_rng(0)
    for _ in range(20):
        c = rng.choice(len(E), size=int(rng.integers(1, len(E))), replace=False)
        a, b = E[c, 0], E[c, 1]
        # the sparse-matrix expression the kernel replaces
        M = (R[a] + R[b]).tocoo()
        rank = np.arange(len(a))
        claim = np.full(n, len(a))
        np.minimum.at(claim, M.col, rank[M.row])
        lost = np.zeros(len(a), bool)
        np.logical_or.at(lost, M.row, claim[M.col] != rank[M.row])
        common = np.asarray(A[a].multiply(A[b]).sum(axis=1)).ravel()
        want = ~lost & (common == 2)
        got = O._independent_edges(A, a, b, n)
        assert np.array_equal(got, want) and want.any()


def _section_batch(rng, m):
    """Section problems of Sec. 4.5 with m prediction points each (random chords and end tangents)."""
    from meshlab_holefill.algorithms.xie_zou2013 import prediction

    p = len(m)
    L = rng.uniform(1.0, 4.0, p)
    a1, a2 = rng.uniform(0.05, 1.2, p), rng.uniform(0.05, 1.2, p)
    tv1 = np.stack([np.cos(a1), np.sin(a1), np.zeros(p)], axis=1)
    tv2 = np.stack([np.cos(-a2), np.sin(-a2), np.zeros(p)], axis=1)
    P2 = np.stack([L, np.zeros(p), np.zeros(p)], axis=1)
    normal = np.tile([0.0, 0.0, 1.0], (p, 1))
    problem, _ = prediction.section_problems(np.zeros((p, 3)), P2, tv1, tv2, normal, np.asarray(m, np.int64))
    return problem


def test_fused_turning_generation_equals_generic_objective():
    rng = np.random.default_rng(11)
    problem = _section_batch(rng, [1, 3, 5, 9, 6, 2])
    _assert_fused_equals_generic(problem)
    _assert_fused_equals_generic(_section_batch(rng, [127, 130]))  # rows longer than one pairwise block


def _assert_fused_equals_generic(problem):
    from meshlab_holefill.algorithms.xie_zou2013 import prediction
    from meshlab_holefill.algorithms.xie_zou2013.de_rand_1_bin import de_rand_1_bin

    pop = np.maximum(3 * problem.m, 3)
    init = prediction.initial_population(problem, pop, np.random.default_rng(5), spread=2.0)  # many reflections
    objective = prediction.AngleVariation(problem)
    assert objective(init).tobytes() == prediction.angle_variation(problem, init).tobytes()
    for generations in (1, 40):
        generic = de_rand_1_bin(lambda Y: prediction.angle_variation(problem, Y), problem.lower, problem.upper,
                                pop_size=pop, dims=problem.m, generations=generations, seed=3, init=init)
        fused = de_rand_1_bin(objective, problem.lower, problem.upper, pop_size=pop, dims=problem.m,
                              generations=generations, seed=3, init=init)
        assert generic[0].tobytes() == fused[0].tobytes() and generic[1].tobytes() == fused[1].tobytes()


def test_the_reference_reflection_orders_moved_rows_first():
    rng = np.random.default_rng(12)
    X, lower, upper = _problem(rng, B=3, N=8, n=4)
    active = np.ones((3, 8), bool)
    active[2, 5:] = False
    seg_x = rng.normal(size=(3, 7))
    seg_y_add = rng.normal(size=(3, 7))
    Xr, order, counts, cross, dot = reflect_gather_terms(X, lower, upper, active, seg_x, seg_y_add)
    ref = reflect_into_bounds(X, lower, upper)
    moved = np.any(ref != X, axis=2) & active
    assert Xr.tobytes() == ref.tobytes() and np.array_equal(counts, moved.sum(axis=1))
    want = np.argsort(~moved, axis=1, kind="stable")[:, :counts.max()]
    assert np.array_equal(order, want)
    cross_ref, dot_ref = K.turning_terms(np.ascontiguousarray(ref[np.arange(3)[:, None], want]), seg_x, seg_y_add)
    assert cross.tobytes() == cross_ref.tobytes() and dot.tobytes() == dot_ref.tobytes()


def test_masked_row_sums_equal_numpy_sum():
    rng = np.random.default_rng(13)
    for shape in [(1, 1, 1), (1, 3, 7), (2, 5, 8), (3, 4, 9), (6, 11, 17), (2, 3, 64), (2, 2, 127), (1, 2, 128)]:
        beta = rng.normal(size=shape) * 10.0 ** rng.integers(-8, 8, size=shape)
        beta[beta > 5] = -0.0
        valid = (rng.random((shape[0], shape[2])) < 0.8).astype(np.float64)
        ref = beta * valid[:, None, :]
        got = beta.copy()
        total = K.masked_row_sums(got, valid)
        assert got.tobytes() == ref.tobytes() and total.tobytes() == ref.sum(axis=2).tobytes()


def test_select_reflect_terms_equal_select_then_reflect_gather():
    # X inside its bounds (as after every generation), trials partly outside: the in-place
    # reflection of the taken rows gives what selecting and then reflecting everything gives.
    rng = np.random.default_rng(16)
    X0, lower, upper = _problem(rng, B=3, N=8, n=4)
    X0 = reflect_into_bounds(X0, lower, upper)
    U, _, _ = _problem(rng, B=3, N=8, n=4)
    U[0, 1, 0] = -0.0
    active = np.ones((3, 8), bool)
    active[2, 5:] = False
    seg_x, seg_y_add = rng.normal(size=(3, 7)), rng.normal(size=(3, 7))
    square_sum, total = rng.random((3, 8)) * 4.0, rng.normal(size=(3, 8))
    count = np.array([6, 5, 6], np.int64)
    fX0 = rng.random((3, 8))
    fX0[1, 2] = K._variation(square_sum[1, 2], total[1, 2], count[1])  # ties select the trial
    angles0, trial_angles = rng.normal(size=(3, 8, 6)), rng.normal(size=(3, 8, 6))
    X, fX, angles = X0.copy(), fX0.copy(), angles0.copy()
    select_variation(X, fX, U, square_sum, total, count, active, angles, trial_angles)
    Xr, *want = reflect_gather_terms(X, lower, upper, active, seg_x, seg_y_add)
    X, fX, angles = X0.copy(), fX0.copy(), angles0.copy()
    got = K.select_reflect_terms(X, fX, U, square_sum, total, count, active, angles, trial_angles, lower, upper,
                                 seg_x, seg_y_add)
    assert 0 < got[1].sum() < active.sum()
    assert X.tobytes() == Xr.tobytes() and all(g.tobytes() == w.tobytes() for g, w in zip(got, want))
    select_variation(X0, fX0, U, square_sum, total, count, active, angles0, trial_angles)
    assert fX.tobytes() == fX0.tobytes() and angles.tobytes() == angles0.tobytes()


def test_changed_masked_row_sums_equal_numpy_scatter_and_sum():
    rng = np.random.default_rng(17)
    for shape in [(1, 1, 1), (2, 5, 8), (3, 4, 9), (2, 3, 64), (1, 2, 128)]:
        valid = (rng.random((shape[0], shape[2])) < 0.8).astype(np.float64)
        parent = rng.normal(size=shape) * valid[:, None, :]
        changed = np.flatnonzero(rng.random(parent.size) < 0.2)
        beta = rng.normal(size=len(changed)) * 10.0 ** rng.integers(-8, 8, size=len(changed))
        ref = parent.copy()
        ref.ravel()[changed] = beta
        ref *= valid[:, None, :]
        out = np.full_like(parent, np.nan)
        total = K.changed_masked_row_sums(parent, changed, beta, valid, out)
        assert out.tobytes() == ref.tobytes() and total.tobytes() == ref.sum(axis=2).tobytes()


def test_umbrella_passes_equal_the_sparse_expression():
    import pymeshlab
    import scipy.sparse as sp

    from meshlab_holefill.algorithms.xie_zou2013._smoothing_kernels import umbrella_passes
    from meshlab_holefill.geometry.laplacian import adjacency_matrix

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V0, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix().astype(np.int64)
    V0 = V0 + np.random.default_rng(14).normal(scale=0.02, size=V0.shape)
    free = V0[:, 2] > -0.2
    A = adjacency_matrix(F, len(V0))
    W = sp.diags(1.0 / np.maximum(np.asarray(A.sum(axis=1)).ravel(), 1)) @ A
    Wf = W[free].tocsr()
    ref = V0.copy()
    for _ in range(7):
        for factor in (0.33, -0.41):
            ref[free] += factor * (Wf @ ref - ref[free])
    got = V0.copy()
    umbrella_passes(got, np.flatnonzero(free).astype(np.int64), Wf.indptr.astype(np.int64),
                    Wf.indices.astype(np.int64), Wf.data, np.array([0.33, -0.41]), 7)
    assert got.tobytes() == ref.tobytes()


def test_edge_adjacency_equals_sorted_edges_and_scipy_csr():
    import importlib

    import pymeshlab
    import scipy.sparse as sp

    O = importlib.import_module("meshlab_holefill.algorithms.xie_zou2013.optimisation")
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    F = ms.current_mesh().face_matrix().astype(np.int64)
    F = F[np.random.default_rng(15).permutation(len(F))][: len(F) // 2]  # an irregular open piece
    n = int(F.max()) + 3  # vertices without faces too
    E, indptr, indices = KO.edge_adjacency(F, n)
    E_ref = O.sorted_edges(F, n)
    A_ref = sp.coo_matrix((np.ones(2 * len(E_ref), np.int8), (np.r_[E_ref[:, 0], E_ref[:, 1]],
                                                             np.r_[E_ref[:, 1], E_ref[:, 0]])), shape=(n, n)).tocsr()
    assert np.array_equal(E, E_ref)
    assert np.array_equal(indptr, A_ref.indptr) and np.array_equal(indices, A_ref.indices)
    _, A = O.adjacency(F, n)
    assert (A != A_ref).nnz == 0 and A.dtype == np.int8
    # any face list: repeated and reversed faces, many faces on a vertex, a vertex twice in a face
    F = np.random.default_rng(16).integers(0, 40, size=(300, 3))
    F[::9] = F[1::9][: len(F[::9])][:, ::-1]
    E, indptr, indices = KO.edge_adjacency(F, 45)
    assert np.array_equal(E, O.sorted_edges(F, 45))
    assert np.array_equal(indptr[1:] - indptr[:-1], np.bincount(E.ravel(), minlength=45))



def test_faces_around_edges_equal_the_incidence_matrix_expression():
    import pymeshlab
    import scipy.sparse as sp

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    F = ms.current_mesh().face_matrix().astype(np.int64)
    n = int(F.max()) + 1
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]]]), axis=1), axis=0)
    pick = np.random.default_rng(16).choice(len(E), 40, replace=False)
    a, b = E[pick, 0], E[pick, 1]
    a[:3] = b[3:6]  # edges sharing vertices
    VF = sp.csr_matrix((np.ones(3 * len(F), np.int8), (F.ravel(), np.repeat(np.arange(len(F)), 3))), shape=(n, len(F)))
    around = (VF[a] + VF[b]).tocoo()
    on_edge = around.data > 1
    rows, faces = KO.faces_around_edges(F, n, a, b)
    assert np.array_equal(rows, around.row[~on_edge]) and np.array_equal(faces, around.col[~on_edge])


def test_patch_lowest_frequency_is_the_same_in_every_call():
    import pymeshlab

    from meshlab_holefill.algorithms.xie_zou2013 import smoothing
    from meshlab_holefill.geometry.laplacian import adjacency_matrix

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=4)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    A = adjacency_matrix(F, len(V))
    free = V[:, 2] > 0.3
    assert free.sum() > smoothing.DENSE_SPECTRUM_MAX  # the sparse solve
    values = {smoothing.patch_lowest_frequency(F, len(V), free, A).hex() for _ in range(4)}
    assert len(values) == 1
