"""The compiled triangle-triangle query gives exactly the answers of the numpy code it replaced.

The reference is that numpy code, kept verbatim in tests/intersections_numpy.py: the same
candidate pairs from the broad phase, the same narrow-phase verdicts pair by pair, and the same
result from `intersecting_pairs`, on random soups built to hit the predicates' special cases:
shared vertices and edges (by index and, for welding, by coordinates), duplicate faces, repeated
indices, coplanar and collinear faces from integer grids, near touches at the tolerance, and faces
of very different sizes (several radius bins).
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import intersections_numpy as R
from meshlab_holefill.geometry import _broad_phase_kernels as broad
from meshlab_holefill.geometry import _narrow_phase_kernels as narrow
from meshlab_holefill.geometry import intersections as I


@st.composite
def soups(draw):
    """(V, F): a few points, some copied (unwelded twins), and faces over them."""
    n = draw(st.integers(3, 9))
    kind = draw(st.sampled_from(["grid", "planar", "float", "near", "sizes"]))
    if kind in ("grid", "planar", "near"):
        P = np.array(draw(st.lists(st.lists(st.integers(-2, 2), min_size=3, max_size=3), min_size=n, max_size=n)),
                     float)
        if kind == "planar":
            P[:, 2] = 0.0
        if kind == "near":  # offsets around the default tolerance (1e-9 of the diagonal)
            e = draw(st.lists(st.sampled_from([0.0, 1e-9, -1e-9, 3e-9, -3e-9, 1e-8, 2e-10]), min_size=3 * n,
                              max_size=3 * n))
            P += np.reshape(e, (n, 3))
    else:
        P = np.array(draw(st.lists(st.lists(st.floats(-3, 3), min_size=3, max_size=3), min_size=n, max_size=n)))
        if kind == "sizes":
            P *= np.array(draw(st.lists(st.sampled_from([1.0, 1e-2, 1e-4, 30.0]), min_size=n, max_size=n)))[:, None]
    if draw(st.booleans()):  # rotate and scale: coplanar faces off the axes, rounding in play
        quat = draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1))
        P = Rotation.from_quat(quat).apply(P) * draw(st.sampled_from([1.0, 1e-3, 7.0, 1e4])) + draw(
            st.sampled_from([0.0, 1.0, -1e3]))
    twins = draw(st.lists(st.integers(0, n - 1), max_size=3))
    P = np.vstack([P, P[twins]]) if twins else P
    nv = len(P)
    idx = st.integers(0, nv - 1)
    faces = draw(st.lists(st.tuples(idx, idx, idx), min_size=1, max_size=10))
    # faces across an edge of an earlier face (shared edges, folds, duplicates)
    for f, w, flip in draw(st.lists(st.tuples(st.integers(0, 99), idx, st.booleans()), max_size=6)):
        a, b, _ = faces[f % len(faces)]
        faces.append((b, a, w) if flip else (a, b, w))
    return P, np.array(faces, np.int64)


@st.composite
def queries(draw):
    V, F = draw(soups())
    m = len(F)
    sub = st.lists(st.integers(0, m - 1), min_size=1, max_size=m)
    q = draw(st.one_of(st.just(list(range(m))), sub))
    a = draw(st.one_of(st.just(list(range(m))), sub))
    tol = draw(st.sampled_from([None, None, 0.0, 1e-6, 0.1]))
    fold = draw(st.sampled_from([I.FOLD_ANGLE, I.FOLD_ANGLE, 0.3]))
    weld = draw(st.booleans())
    return V, F, q, a, tol, fold, weld


@settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(queries())
def test_intersecting_pairs_equal_numpy(case):
    V, F, q, a, tol, fold, weld = case
    got = I.intersecting_pairs(V, F, q, a, tol, fold_angle=fold, weld=weld)
    ref = R.intersecting_pairs(V, F, q, a, tol, fold_angle=fold, weld=weld)
    assert got.dtype == ref.dtype and np.array_equal(got, ref)
    assert np.array_equal(I.faces_intersecting(V, F, q, a, tol, fold_angle=fold, weld=weld),
                          R.faces_intersecting(V, F, q, a, tol, fold_angle=fold, weld=weld))


def _reference_codes(V, F, canon, i, j, in_q, in_a, tol, fold):
    """The numpy pipeline of one candidate chunk (as intersections_numpy.intersecting_pairs runs it)."""
    keep = (i != j) & ~((i > j) & in_q[j] & in_a[i])
    out = np.zeros(len(i), bool)
    idx = np.flatnonzero(keep)
    T1, T2 = V[F[i[idx]]], V[F[j[idx]]]
    maybe = ~(R._beyond_plane(T1, T2, tol) | R._beyond_plane(T2, T1, tol))
    idx = idx[maybe]
    out[idx] = R._narrow(T1[maybe], T2[maybe], canon[F[i[idx]]], canon[F[j[idx]]], tol, fold)
    return out


def _kernel_hits(V, F, canon, i, j, in_q, in_a, tol, fold):
    code, fy, fx = narrow.narrow_codes(V, F, canon, i, j, in_q, in_a, tol)
    hit = code == narrow.HIT
    f = code == narrow.FOLD
    hit[f] = np.arctan2(fy[f], fx[f]) < fold
    return hit


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), scale=st.sampled_from([1.0, 1e-6, 1e5]),
       grid=st.booleans(), tol=st.sampled_from([1e-9, 1e-3, 0.05, 0.0]), fold=st.sampled_from([1e-3, 0.5]))
def test_narrow_phase_equals_numpy_pair_by_pair(seed, scale, grid, tol, fold):
    """Thousands of pairs per example, many sharing a vertex or an edge, from a small point set."""
    rng = np.random.default_rng(seed)
    n = 12
    P = rng.integers(-2, 3, (n, 3)).astype(float) if grid else rng.normal(size=(n, 3))
    if grid and rng.random() < 0.5:
        P[:, rng.integers(3)] = 0.0  # all coplanar
    P = P * scale
    F = rng.integers(0, n, (400, 3))
    F[:50, 2] = F[:50, 1]  # repeated indices: degenerate faces
    i, j = rng.integers(0, 400, 3000), rng.integers(0, 400, 3000)
    in_q, in_a = rng.random(400) < 0.7, rng.random(400) < 0.7
    canon = np.arange(n)
    t = tol * scale
    ref = _reference_codes(P, F, canon, i, j, in_q, in_a, t, fold)
    assert np.array_equal(_kernel_hits(P, F, canon, i, j, in_q, in_a, t, fold), ref)
    assert ref.any() and not ref.all()


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(1, 300), m=st.integers(1, 300),
       spread=st.sampled_from([0.0, 1e-3, 1.0]), flat=st.booleans())
def test_broad_phase_equals_kdtree_search(seed, n, m, spread, flat):
    """The sweep keeps exactly the pairs the radius-binned cKDTree search and box test kept."""
    rng = np.random.default_rng(seed)
    sizes = 10.0 ** rng.integers(-4, 1, (n + m, 1, 1))  # faces of very different sizes
    T = rng.uniform(0, 3, (n + m, 1, 3)) + rng.normal(0, 1, (n + m, 3, 3)) * sizes * (spread + 0.05)
    if flat:
        T[..., 0] = 1.5  # a planar set: the sweep must not run along the flat axis
    Tq, Ta = T[:n], T[n:]
    tol = 1e-9 * 3
    blocks = list(R._candidates(Tq, Ta, tol))
    ref = {(int(x), int(y)) for b in blocks for x, y in zip(*b)}
    # disjoint sets: no pair is a self or mirrored pair
    i, j, in_q, in_a = I._candidates(_bounds(Tq), _bounds(Ta), tol, np.arange(n), np.arange(n, n + m), n + m)
    assert np.flatnonzero(in_q).tolist() == list(range(n)) and np.flatnonzero(in_a).tolist() == list(range(n, n + m))
    got = list(zip(i.tolist(), (j - n).tolist()))
    assert len(got) == len(set(got))
    assert set(got) == ref


def _bounds(T):
    """broad.face_bounds of the triangles T (n, 3, 3), as a soup of their own vertices."""
    return broad.face_bounds(T.reshape(-1, 3), np.arange(3 * len(T)).reshape(-1, 3), np.arange(len(T)))


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), offset=st.sampled_from([0.0, 1e3, -7.0]))
def test_face_bounds_equal_numpy(seed, offset):
    """Boxes, centroids and radii as the numpy expressions on V[F[faces]] compute them."""
    rng = np.random.default_rng(seed)
    V = rng.normal(size=(60, 3)) * np.exp(3 * rng.normal(size=(60, 1))) + offset
    V[:10] *= rng.integers(0, 2, (10, 3))  # zeros, repeated coordinates
    F = rng.integers(0, 60, (200, 3))
    faces = rng.integers(0, 200, 150)
    T = V[F[faces]]
    c = T.mean(1)
    ref = (T.min(1), T.max(1), c, np.linalg.norm(T - c[:, None], axis=2).max(1))
    for got, want in zip(broad.face_bounds(V, F, faces), ref):
        assert got.shape == want.shape and np.array_equal(got, want)


def test_real_patch_queries_equal_numpy():
    """A closed sphere with pushed vertices, against itself: many shared edges and vertices."""
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = ms.current_mesh().vertex_matrix().copy(), ms.current_mesh().face_matrix().astype(np.int64)
    rng = np.random.default_rng(0)
    for push in (0.0, 0.3, 1.2):
        W = V.copy()
        W[rng.integers(0, len(V), 20)] *= 1 - push
        allf = np.arange(len(F))
        for weld in (True, False):
            got = I.intersecting_pairs(W, F, allf[:200], allf, weld=weld)
            assert np.array_equal(got, R.intersecting_pairs(W, F, allf[:200], allf, weld=weld))
    assert len(got) > 0


def test_boxes_meeting_the_query_box_equal_numpy():
    """The faces kept for the candidate search: boxes meeting the query faces' common box grown by tol."""
    rng = np.random.default_rng(4)
    for t in range(50):
        lo_q, lo_a = rng.uniform(0, 3, (int(rng.integers(1, 20)), 3)), rng.uniform(-2, 6, (200, 3))
        hi_q, hi_a = lo_q + rng.uniform(0, 0.5, lo_q.shape), lo_a + rng.uniform(0, 0.5, lo_a.shape)
        if t % 5 == 0:
            lo_a[rng.integers(0, 200, 10), rng.integers(0, 3, 10)] = np.nan
        lo, hi = lo_q.min(0) - 1e-3, hi_q.max(0) + 1e-3
        want = np.flatnonzero(np.all(hi_a >= lo, axis=1) & np.all(lo_a <= hi, axis=1))
        assert np.array_equal(broad.boxes_meeting(lo_q, hi_q, lo_a, hi_a, 1e-3), want)
    lo_q[0, 1] = np.nan  # a query face that is not a number meets nothing
    assert len(broad.boxes_meeting(lo_q, hi_q, lo_a, hi_a, 1e-3)) == 0


def test_radii_that_are_not_numbers_are_refused():
    T = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 0, 0], [np.inf, 0, 0], [0, 1, 0]]], float)
    with pytest.raises(ValueError, match="not numbers"):
        I._candidates(_bounds(T[:1]), _bounds(T[1:]), 1e-9, np.arange(1), np.arange(1, 2), 2)



def _far_edge_straddles(V, F, i, j, tol):
    """Per pair of faces sharing one vertex: whether the edge of F[i] opposite it has ends on both
    sides of (or within tol of) the plane of F[j], so that the slab alone cannot reject it."""
    A, B = V[F[i]], V[F[j]]
    n = np.cross(B[:, 1] - B[:, 0], B[:, 2] - B[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    h = np.einsum("kij,kj->ki", A - B[:, :1], n)
    far = ~(F[i][:, :, None] == F[j][:, None, :]).any(2)
    h = np.where(far, h, np.nan)
    return ~((np.nan_to_num(h, nan=np.inf) > tol).all(1) | (np.nan_to_num(h, nan=-np.inf) < -tol).all(1))


@pytest.mark.parametrize("jitter", [0.0, 0.05, 0.5])
def test_fan_pairs_sharing_one_vertex_equal_numpy(jitter):
    """Faces of a jittered fan, and of a second fan lifted over it, meet pairwise at the centre; the
    far edge of one face lies wholly to one side of the other's plane (the slab decides) or crosses
    it (the edge constraints decide)."""
    rng = np.random.default_rng(1)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 24))
    rim = np.stack([np.cos(angles), np.sin(angles), jitter * rng.normal(size=24)], axis=1)
    V = np.concatenate([np.zeros((1, 3)), rim, rim[::3] * 0.9 + [0.0, 0.0, 0.2]])
    F = np.array([[0, 1 + t, 1 + (t + 1) % 24] for t in range(24)] + [[0, 25 + t, 26 + t] for t in range(7)])
    i, j = _pairs_sharing_one_vertex(F)
    ref = _kernel_agrees_with_numpy(V, F, i, j)
    straddles = _far_edge_straddles(V, F, i, j, 1e-9)
    assert straddles.any() and not straddles.all()
    assert ref.any() == (jitter == 0.5)


def _pairs_sharing_one_vertex(F):
    """(i, j): every ordered pair of faces of F that share exactly one vertex."""
    i, j = (x.ravel() for x in np.meshgrid(np.arange(len(F)), np.arange(len(F))))
    shared = (F[i][:, :, None] == F[j][:, None, :]).any(2).sum(1)
    return i[shared == 1], j[shared == 1]


def _kernel_agrees_with_numpy(V, F, i, j):
    """The compiled narrow phase's verdicts on pairs (i, j) equal the numpy reference's; those verdicts."""
    in_all = np.ones(len(F), bool)
    canon = np.arange(len(V))
    ref = _reference_codes(V, F, canon, i, j, in_all, in_all, 1e-9, 1e-3)
    assert np.array_equal(_kernel_hits(V, F, canon, i, j, in_all, in_all, 1e-9, 1e-3), ref)
    return ref


def _behind_shared_bisector(V, F, i, j):
    """Per pair (i, j) sharing one vertex: face i's edge opposite it lies wholly behind face j's corner
    bisector there (the constraint the narrow phase tries first for such pairs)."""
    out = np.zeros(len(i), bool)
    for p, (a, b) in enumerate(zip(i, j)):
        s = next(v for v in F[a] if v in F[b])
        far = [v for v in F[a] if v != s]
        c = list(F[b]).index(s)
        e1, e2 = V[F[b][(c + 1) % 3]] - V[s], V[F[b][(c + 2) % 3]] - V[s]
        u = e1 / np.linalg.norm(e1) + e2 / np.linalg.norm(e2)
        out[p] = all((V[v] - V[s]) @ u < 0 for v in far)
    return out


@pytest.mark.parametrize("lift", [0.0, 0.3])
def test_shared_corner_bisector_first_equals_numpy(lift):
    """Pairs of a jittered fan sharing only its centre, a second fan's faces reaching across the first:
    the far edge crosses the other face's plane behind the shared corner (the bisector rejects it
    first) or in front of it (the other constraints decide), the same verdicts as the numpy code."""
    rng = np.random.default_rng(7)
    angles = np.sort(rng.uniform(0, 2 * np.pi, 30))
    rim = np.stack([np.cos(angles), np.sin(angles), 0.5 * rng.normal(size=30)], axis=1)
    over = np.stack([np.cos(angles[::2] + 2.0), np.sin(angles[::2] + 2.0), lift + rng.normal(size=15)], axis=1)
    V = np.concatenate([np.zeros((1, 3)), rim, over])
    F = np.array([[0, 1 + t, 1 + (t + 1) % 30] for t in range(30)] + [[0, 31 + t, 32 + t] for t in range(14)])
    i, j = _pairs_sharing_one_vertex(F)
    ref = _kernel_agrees_with_numpy(V, F, i, j)
    straddles = _far_edge_straddles(V, F, i, j, 1e-9)
    behind = _behind_shared_bisector(V, F, i, j)
    assert (straddles & behind).any() and (straddles & ~behind).any() and ref.any()
