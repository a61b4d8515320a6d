"""Edge relaxation by swaps (geometry.flips): the circumsphere, angle and scored tests."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.flips import circumcenters, folds, min_angle_scores, relax_edges
from meshlab_holefill.geometry.quality import corner_angles
from meshlab_holefill.geometry.topology import interior_edges, vertex_face_runs


@settings(max_examples=60, deadline=None)
@given(st.floats(-1.0, 3.0), st.floats(0.05, 1.5), st.floats(-1.0, 3.0), st.floats(0.05, 1.5), st.floats(-0.3, 0.3))
def test_min_angle_criterion_swaps_exactly_when_the_minimum_angle_rises(cx, cy, dx, dy, dz):
    """Xie and Zou Sec. 4.7: edge (a, b) becomes (c, d) iff that raises the pair's smallest angle."""
    V = np.array([[0, 0, 0], [2, 0, 0], [cx, cy, 0], [dx, -dy, dz]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    new = np.array([[0, 3, 2], [1, 2, 3]])
    before = corner_angles(V, F).min()
    after = corner_angles(V, new).min()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]).sum(axis=0)
    M = np.cross(V[new[:, 1]] - V[new[:, 0]], V[new[:, 2]] - V[new[:, 0]])
    folds = np.any(M @ N <= 0)  # the quad is not convex: the other diagonal folds the pair
    F2, swaps = relax_edges(V, F, criterion="min_angle")
    if folds:
        assert swaps == 0
    else:
        assert swaps == (1 if after > before + 1e-9 else 0)
        assert corner_angles(V, F2).min() == pytest.approx(max(before, after) if swaps else before)
    o, n = min_angle_scores(V, F[:1], F[1:], new[:1], new[1:])
    assert o[0] == pytest.approx(before) and n[0] == pytest.approx(after)


def test_min_angle_criterion_never_lowers_the_smallest_angle_and_converges():
    rng = np.random.default_rng(5)
    P = rng.uniform(-1, 1, (80, 2))
    P[:, 0] *= 4  # stretched: the Delaunay triangulation of the stretched points is poor here
    from scipy.spatial import Delaunay
    F = Delaunay(P * [0.25, 1]).simplices
    V = np.c_[P, 0.05 * np.sin(P[:, 0])]
    up = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2] < 0
    F[up] = F[up][:, [0, 2, 1]]
    F2, swaps = relax_edges(V, F, criterion="min_angle")
    assert swaps > 0
    assert corner_angles(V, F2).min() >= corner_angles(V, F).min() - 1e-12
    assert np.sort(corner_angles(V, F2).min(axis=1))[:10].sum() > np.sort(corner_angles(V, F).min(axis=1))[:10].sum()
    assert relax_edges(V, F2, criterion="min_angle")[1] == 0  # no swap left that raises an angle
    # A callable scorer with the same scores gives the same faces; one that rules all out none.
    F3, swaps3 = relax_edges(V, F, criterion=min_angle_scores)
    assert np.array_equal(F3, F2) and swaps3 == swaps
    veto = lambda V, o1, o2, n1, n2: (np.zeros(len(o1)), np.full(len(o1), -np.inf))  # noqa: E731
    assert relax_edges(V, F, criterion=veto)[1] == 0


def test_normal_cos_refuses_swaps_that_turn_a_triangle_too_far():
    # A pair bent by 108 degrees along (a, b), d above b: the swap to (c, d) raises the smallest
    # angle (0.337 -> 0.449 rad) but the new triangle (b, c, d) turns by about 73 degrees from
    # the mean normal of the old pair (cosine 0.298).
    th = np.radians(108.0)
    V = np.array([[0, 0, 0], [2, 0, 0], [0.8, 1.0, 0], [2.0, -0.7 * np.cos(th), 0.7 * np.sin(th)]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    o, n = min_angle_scores(V, F[:1], F[1:], np.array([[0, 3, 2]]), np.array([[1, 2, 3]]))
    assert n[0] > o[0] + 0.1
    assert relax_edges(V, F, criterion="min_angle", normal_cos=0.0)[1] == 1
    assert relax_edges(V, F, criterion="min_angle", normal_cos=0.5)[1] == 0
    assert relax_edges(V, F, criterion="min_angle", normal_cos=None)[1] == 1


def test_relax_edges_makes_a_planar_triangulation_delaunay():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 2 * np.pi, 30))
    P = np.stack([3 * np.cos(t), np.sin(t), np.zeros(30)], 1)  # convex, not cocircular
    F = np.array([[0, i, i + 1] for i in range(1, 29)])  # a fan: far from Delaunay
    k = 30
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    F2, swaps = relax_edges(P, F, fixed_edges=loop)
    assert swaps > 0 and len(F2) == len(F)
    E, f1, c1, f2, c2 = interior_edges(F2, k)
    d = F2[f2, (c2 + 2) % 3]
    cc, r = circumcenters(P, F2[f1])
    assert np.all(np.linalg.norm(P[d] - cc, axis=1) >= r * (1 - 1e-6))
    # orientation kept: all normals still +z
    assert np.all(np.cross(P[F2[:, 1]] - P[F2[:, 0]], P[F2[:, 2]] - P[F2[:, 0]])[:, 2] > 0)


def _assert_oriented_manifold(F, closed=False):
    """No directed edge twice (consistent orientation, no duplicate face), no undirected edge in
    more than two faces (exactly two when ``closed``), no face with a repeated vertex."""
    F = np.asarray(F)
    assert np.all((F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0]))
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "a directed edge is used twice"
    _, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert count.max() <= 2, "an edge is shared by more than two faces"
    if closed:
        assert np.all(count == 2)


def _bipyramid(k, h):
    """Closed bipyramid: equator 0..k-1 on the unit circle, apexes k = (0, 0, h), k+1 = (0, 0, -h).

    For k = 3, flat enough, every equator edge fails the swap tests (its opposite angles at the
    apexes are obtuse), and every one of them would be swapped to the same edge (k, k+1).
    """
    t = 2 * np.pi * np.arange(k) / k
    V = np.r_[np.c_[np.cos(t), np.sin(t), np.zeros(k)], [[0, 0, h], [0, 0, -h]]]
    i = np.arange(k)
    F = np.r_[np.c_[i, (i + 1) % k, np.full(k, k)], np.c_[(i + 1) % k, i, np.full(k, k + 1)]]
    return V, F


@pytest.mark.parametrize("criterion", ["sphere", "angles"])
def test_relax_edges_refuses_a_swap_that_recreates_an_existing_edge(criterion):
    """Next to valence-3 vertices: edges (1, 2) and (2, 0) fail the test, but their swap would
    create the pole-to-pole edge (3, 4), which already exists. Doing it would put (3, 4) in four
    faces (non-manifold), so nothing may change."""
    V, _ = _bipyramid(3, 0.3)
    # The triangular bipyramid after swapping its equator edge (0, 1) into (3, 4): vertices 0
    # and 1 now have valence 3 (each with neighbours 2, 3, 4: a tetrahedron-like corner).
    F = np.array([[0, 4, 3], [1, 3, 4], [1, 2, 3], [2, 1, 4], [2, 0, 3], [0, 2, 4]])
    _assert_oriented_manifold(F, closed=True)
    for max_rounds in (1, 200):
        F2, swaps = relax_edges(V, F, criterion=criterion, max_rounds=max_rounds)
        _assert_oriented_manifold(F2, closed=True)
        assert swaps == 0 and np.array_equal(F2, F)


@pytest.mark.parametrize("criterion", ["sphere", "angles"])
@pytest.mark.parametrize("h", [0.1, 0.3, 0.5])
def test_relax_edges_makes_only_one_of_two_swaps_that_create_the_same_edge(criterion, h):
    """The three equator edges of a flat triangular bipyramid share no face (their opposite angles
    at the apexes are ~120 degrees) and all would become the edge between the apexes: in one
    round only one of them may be swapped."""
    k = 3
    V, F = _bipyramid(k, h)
    F2, swaps = relax_edges(V, F, criterion=criterion, max_rounds=1)
    assert swaps == 1
    _assert_oriented_manifold(F2, closed=True)
    assert {k, k + 1} in [set(e) for e in np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]]]).tolist()]
    F3, _ = relax_edges(V, F, criterion=criterion)
    _assert_oriented_manifold(F3, closed=True)


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 6), st.floats(0.05, 1.0), st.sampled_from(["sphere", "angles", "min_angle"]),
       st.integers(0, 2 ** 32 - 1))
def test_relax_edges_keeps_a_closed_surface_an_oriented_manifold(k, h, criterion, seed):
    """Swapping edges of a closed surface keeps it closed, consistently oriented and manifold
    (a sphere: V - E + F = 2), whatever the criterion, on jittered bipyramids."""
    V, F = _bipyramid(k, h)
    V = V + np.random.default_rng(seed).uniform(-0.05, 0.05, V.shape)
    F2, _ = relax_edges(V, F, criterion=criterion)
    assert len(F2) == len(F)
    _assert_oriented_manifold(F2, closed=True)
    edges = np.unique(np.sort(np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]]), axis=1), axis=0)
    assert len(V) - len(edges) + len(F2) == 2


def _edge_set(F):
    return {tuple(sorted(e)) for e in np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).tolist()}


@pytest.mark.parametrize("criterion", ["sphere", "angles", "min_angle"])
def test_relax_edges_never_creates_or_removes_a_fixed_edge(criterion):
    """A fixed edge is kept when it fails the test, and a fixed edge not in the mesh is never made."""
    # A planar quad whose diagonal (0, 1) is very long: every criterion swaps it to (2, 3).
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.3, 0], [1, -0.3, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    F_free, swaps = relax_edges(V, F, criterion=criterion)
    assert swaps == 1 and (2, 3) in _edge_set(F_free)
    for fixed in ([[0, 1]], [[3, 2]]):  # the current edge, or the one the swap would create
        F2, swaps = relax_edges(V, F, fixed_edges=np.array(fixed), criterion=criterion)
        assert swaps == 0 and np.array_equal(F2, F)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.sampled_from(["sphere", "angles", "min_angle"]))
def test_relax_edges_respects_fixed_edges_of_a_convex_fan(seed, criterion):
    """On a fan over a convex polygon, fix the loop, one fan diagonal, and some of the edges the
    free relaxation creates: the fixed diagonal stays and none of the forbidden edges appears."""
    rng = np.random.default_rng(seed)
    k = 12
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    P = np.stack([3 * np.cos(t), np.sin(t), np.zeros(k)], 1)
    F = np.array([[0, i, i + 1] for i in range(1, k - 1)])
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    free, _ = relax_edges(P, F, fixed_edges=loop, criterion=criterion)
    created = sorted(_edge_set(free) - _edge_set(F))
    forbidden = created[::2]
    kept = (0, int(rng.integers(2, k - 1)))
    F2, _ = relax_edges(P, F, fixed_edges=np.array([*loop.tolist(), kept, *forbidden]).reshape(-1, 2),
                        criterion=criterion)
    edges = _edge_set(F2)
    assert kept in edges
    assert not edges & set(forbidden)
    _assert_oriented_manifold(F2)
    assert np.all(np.cross(P[F2[:, 1]] - P[F2[:, 0]], P[F2[:, 2]] - P[F2[:, 0]])[:, 2] > 0)


def _bumpy_patch(rng, nx=9):
    """A jittered, bumpy grid with random diagonals: many failing edges, folds and near-ties."""
    from conftest import grid

    V, F = grid(nx, nx)
    V = V + np.concatenate([rng.normal(scale=0.3 / nx, size=(len(V), 2)), np.zeros((len(V), 1))], axis=1)
    V[:, 2] = 0.3 * np.sin(3 * V[:, 0]) * rng.uniform(0, 1) + rng.normal(scale=0.02, size=len(V)) * rng.integers(0, 2)
    return V, F


@pytest.mark.parametrize("criterion", ["angles", "sphere"])
def test_compiled_rounds_make_the_numpy_swaps(criterion):
    # The compiled rounds against the numpy rounds: the same faces and swap counts, with and
    # without fixed edges and a veto hook.
    from meshlab_holefill.geometry.topology import interior_edges

    rng = np.random.default_rng(3)
    for trial in range(60):
        V, F = _bumpy_patch(rng, int(rng.integers(3, 12)))
        E = interior_edges(F, len(V))[0]
        fixed = E[rng.random(len(E)) < 0.1]
        veto = rng.random() < 0.5

        def allowed(V, F, A, B, replaced):  # deterministic in the swap, so both runs see the same veto
            return (A.sum(axis=1) + B.sum(axis=1)) % 3 != 0 if veto else np.ones(len(A), bool)

        got = relax_edges(V, F, fixed, allowed=allowed, criterion=criterion)
        want = relax_edges(V, F, fixed, allowed=allowed, criterion=criterion, compiled=False)
        np.testing.assert_array_equal(got[0], want[0])
        assert got[1] == want[1]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10 ** 6), normal_cos=st.sampled_from([0.0, 0.5, -0.2]), fixed=st.booleans(),
       repeat=st.booleans(), rounds=st.integers(1, 30))
def test_compiled_min_angle_rounds_make_the_numpy_swaps(seed, normal_cos, fixed, repeat, rounds):
    # Bumpy patches with many failing edges and near-ties; a repeated directed edge hands the
    # rounds to numpy.
    rng = np.random.default_rng(seed)
    V, F = _bumpy_patch(rng, int(rng.integers(3, 12)))
    E = interior_edges(F, len(V))[0]
    keep = E[rng.random(len(E)) < 0.1] if fixed else None
    if repeat:
        F = np.vstack([F, F[rng.integers(len(F))]])
    got = relax_edges(V, F, keep, max_rounds=rounds, criterion="min_angle", normal_cos=normal_cos)
    want = relax_edges(V, F, keep, max_rounds=rounds, criterion="min_angle", normal_cos=normal_cos, compiled=False)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


@pytest.mark.parametrize("poison", [np.nan, np.inf])
def test_compiled_min_angle_rounds_with_a_corner_at_nan_or_infinity(poison):
    V, F = _bumpy_patch(np.random.default_rng(5), 6)
    V[7] = poison
    with np.errstate(invalid="ignore", over="ignore"):
        got = relax_edges(V, F, criterion="min_angle", normal_cos=0.5)
        want = relax_edges(V, F, criterion="min_angle", normal_cos=0.5, compiled=False)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


def test_compiled_rounds_defer_an_undecided_angle_sum_to_numpy():
    # Edge (a, b) with opposite angles pi / 2 at c and pi / 2 + pi 1e-9 at d: their sum is the
    # test's limit pi (1 + 1e-9) up to rounding, so the round runs in numpy.
    from meshlab_holefill.geometry import _flip_kernels as FK

    t = 1.0 / np.tan(np.pi / 4 + np.pi / 2 * 1e-9)
    V = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, t, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    assert FK.swap_candidates(V, F, np.zeros(0, np.int64), False)[0] == FK.UNSURE
    for move in (0.0, 1e-6, -1e-6):  # and on either side of the limit, decided by the kernel
        W = V + [[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, move, 0]]
        np.testing.assert_array_equal(relax_edges(W, F, criterion="angles")[0],
                                      relax_edges(W, F, criterion="angles", compiled=False)[0])


@pytest.mark.parametrize("poison", [None, np.nan, np.inf])
def test_compiled_circumsphere_rounds_on_degenerate_triangles(poison):
    # A zero-area triangle (infinite circumradius), a nearly flat one, and optionally a corner
    # at NaN or infinity: the compiled rounds still make the numpy rounds' swaps.
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0], [1, -1e-300, 0], [0.5, 0.5, 0]], float)
    F = np.array([[0, 1, 3], [1, 2, 3], [0, 4, 1], [1, 4, 2], [0, 3, 5]])
    if poison is not None:
        V[5] = poison
    got = relax_edges(V, F, criterion="sphere")
    with np.errstate(invalid="ignore", over="ignore"):  # the numpy rounds warn on the poisoned corner
        want = relax_edges(V, F, criterion="sphere", compiled=False)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


def _min_angle_scores_numpy(V, old1, old2, new1, new2):
    """The scorer's numpy form (quality.corner_angles per face pair), the oracle of the compiled corners."""
    old = np.minimum(corner_angles(V, old1).min(axis=1), corner_angles(V, old2).min(axis=1))
    new = np.minimum(corner_angles(V, new1).min(axis=1), corner_angles(V, new2).min(axis=1))
    return old, new


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # inf - inf in the poisoned rows
@pytest.mark.parametrize("poison", [None, np.nan, np.inf])
def test_compiled_min_angle_scores_equal_the_corner_angles_bit_for_bit(poison):
    # Random bumpy patches (with degenerate and repeated-vertex faces mixed in): the scores of
    # every interior edge's pair and swapped pair equal the numpy corner angles exactly.
    rng = np.random.default_rng(5)
    for trial in range(40):
        V, F = _bumpy_patch(rng, int(rng.integers(3, 12)))
        if poison is not None:
            V[rng.integers(len(V))] = poison
        E, f1, c1, f2, c2 = interior_edges(F, len(V))
        c, d = F[f1, (c1 + 2) % 3], F[f2, (c2 + 2) % 3]
        new1, new2 = np.stack([E[:, 0], d, c], axis=1), np.stack([E[:, 1], c, d], axis=1)
        new2[::5] = new2[::5, [0, 0, 1]]  # zero-length edges
        got = min_angle_scores(V, F[f1], F[f2], new1, new2)
        want = _min_angle_scores_numpy(V, F[f1], F[f2], new1, new2)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
            assert np.array_equal(np.signbit(g), np.signbit(w))
    empty = np.zeros((0, 3), np.int64)
    assert [len(x) for x in min_angle_scores(V, empty, empty, empty, empty)] == [0, 0]


def test_compiled_interior_edges_equal_the_sorted_keys_edges():
    # The interior edges from the compiled half-edge table: the edges, faces and corners of the
    # numpy reference in its order, also where a directed edge repeats or an index is out of
    # range (then numpy answers).
    from meshlab_holefill.geometry.topology import interior_edges_numpy

    rng = np.random.default_rng(9)
    for trial in range(60):
        V, F = _bumpy_patch(rng, int(rng.integers(3, 12)))
        F = F[rng.permutation(len(F))].astype(np.int64)
        if trial % 4 == 1:
            F = np.concatenate([F, F[:2]])  # repeated faces: repeated directed edges
        if trial % 4 == 2:
            F = F[: int(rng.integers(0, len(F) + 1))]
        n = len(V) if trial % 4 != 3 else int(F.max())  # the last index out of range
        got, want = interior_edges(F, n), interior_edges_numpy(F, n)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


def fan(centre):
    """A unit square's border, fixed, fanned to one free vertex at ``centre``."""
    X = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], centre], np.float64)
    F = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    return X, F, np.arange(5) < 4


@settings(max_examples=30, deadline=None)
@given(dz=st.floats(-0.05, 0.05), dx=st.floats(-0.1, 0.1))
def test_folds_judges_only_the_folds_a_step_made(dz, dx):
    X, F, fixed = fan([0.5, 0.5, 0.0])
    outside = [0.5, -0.2, 0.0]  # past the edge (0, 1): triangle (0, 1, 4) turns over
    Y = X.copy()
    Y[4] = outside
    assert not folds(X, F, fixed) and folds(Y, F, fixed)
    assert folds(Y, F, fixed, before=X)  # the step folded it
    Z = Y.copy()
    Z[4] += [dx, 0.0, dz]
    assert folds(Z, F, fixed) and not folds(Z, F, fixed, before=Y)  # it was folded before the step
    assert folds(Z, F, fixed, before=X)


def test_vertex_face_runs_list_the_faces_of_each_vertex_in_face_order():
    # The incidence lists of the per-hole loops (a repeated corner and an unused vertex included).
    rng = np.random.default_rng(2)
    for n in (1, 5, 40):
        F = rng.integers(0, n, (int(rng.integers(0, 60)), 3))
        incident = [[] for _ in range(n + 2)]
        for f, tri in enumerate(F.tolist()):
            for v in tri:
                incident[v].append(f)
        faces, start = vertex_face_runs(F, n + 2)
        assert start.dtype == faces.dtype == np.int64
        assert [faces[start[v]:start[v + 1]].tolist() for v in range(n + 2)] == incident
