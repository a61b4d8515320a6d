"""The compiled quality pass gives the numpy pass's results bit for bit, and so do its building blocks."""
import hashlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xie_zou2013 import _quality_pass_kernels as KQ
from meshlab_holefill.algorithms.xie_zou2013 import quality_pass as QP
from meshlab_holefill.algorithms.xie_zou2013._patch_kernels import context as kernel_context
from meshlab_holefill.algorithms.xie_zou2013._quality_pass_numpy import _Patch, _quality
from meshlab_holefill.algorithms.xie_zou2013.folds import local_folds
from meshlab_holefill.geometry.quality import face_normals

from conftest import numpy_products_round_as_the_kernels, random_planar_patch


SAME_GEMV = numpy_products_round_as_the_kernels()
bitwise = pytest.mark.skipif(not SAME_GEMV, reason="numpy's matrix-vector product on this machine rounds in "
                             "another order than the kernels' copy: bit-for-bit comparisons do not apply")


def context(k, border=None, floor=0.4):
    none = np.zeros(0, np.int64)
    return kernel_context(k, floor, QP.GAIN, QP.TURN_COS, QP.BORDER_COS, border, none, none, QP._COS, QP._SIN)


def border_normals(rng, P, k, bend):
    """Unit normals across the loop edges: +z turned about each edge by up to ``bend`` degrees, some rows 0."""
    e = np.roll(P[:k], -1, axis=0) - P[:k]
    e /= np.linalg.norm(e, axis=1)[:, None]
    z = np.array([0.0, 0.0, 1.0])
    side = np.cross(e, z)
    angle = np.radians(rng.uniform(-bend, bend, k))
    N = np.cos(angle)[:, None] * z + np.sin(angle)[:, None] * side
    N[rng.random(k) < 0.1] = 0.0
    return N


def lifted(rng, V, k):
    """The planar patch bent into a bump, its free vertices jittered off it, at a random scale and place."""
    V = V.copy()
    V[:, 2] = rng.uniform(-0.6, 0.6) * (V[:, 0] ** 2 - rng.uniform(0, 1) * V[:, 1] ** 2)
    V[k:, 2] += rng.normal(scale=rng.choice([0.0, 0.01, 0.1]), size=len(V) - k)
    return V * 10.0 ** rng.uniform(-2, 2) + rng.normal(scale=5.0, size=3)


def case(seed):
    """A patch and the pass's options: border normals, forbidden edges, blocked triples, floor, split, a fold test."""
    rng = np.random.default_rng(seed)
    k = int(rng.integers(4, 19))
    points = 0 if rng.random() < 0.25 else int(rng.integers(1, 30))
    V, F = random_planar_patch(k, points, seed)
    if rng.random() < 0.7:
        V = lifted(rng, V, k)
    kw = dict(floor=float(rng.choice([0.3, 0.4, 0.6, 0.8])), split=bool(points == 0 or rng.random() < 0.4))
    if rng.random() < 0.7:
        kw["border_normals"] = border_normals(rng, V, k, rng.choice([20.0, 120.0, 175.0]))
    if rng.random() < 0.5:
        a = rng.integers(0, k, 2 * k)
        b = (a + rng.integers(2, k - 1, 2 * k)) % k
        kw["forbidden_edges"] = np.stack([a, b], axis=1)
    if rng.random() < 0.4:
        kw["blocked"] = {tuple(sorted(t)) for t in rng.integers(0, k, (3 * k, 3)).tolist() if len(set(t)) == 3}
    return V, F, k, kw, rng.choice(["none", "hash", "folds"])


def fold_test(kind, border):
    """A fold count: the real local folds, or a pseudo-random one (a hash of the patch) that refuses many operations."""
    if kind == "hash":
        return lambda V, F: int(hashlib.sha1(V.tobytes() + F.tobytes()).digest()[0] % 3 == 0)
    if kind == "folds":
        return lambda V, F: int(local_folds(V, F, border).sum())
    return None


def both_passes(V, F, k, kw, fold_kind):
    return [run(V, F, k, fold_test=fold_test(fold_kind, kw.get("border_normals")), **kw)
            for run in (QP.raise_min_quality, QP.raise_min_quality_numpy)]


def assert_same(got, want):
    (V1, F1, keep1, stats1), (V2, F2, keep2, stats2) = got, want
    assert stats1 == stats2
    assert V1.shape == V2.shape and V1.tobytes() == V2.tobytes()  # the bits, the signs of zeros too
    assert np.array_equal(F1, F2) and np.array_equal(keep1, keep2)


@bitwise
def test_compiled_pass_is_the_numpy_pass_on_varied_patches(monkeypatch):
    restores = []

    def copied_sets(*state):  # the compiled patch's undoing of an operation the fold test refuses
        restores.append(1)
        return copy(*state)

    copy = QP.copied_sets
    monkeypatch.setattr(QP, "copied_sets", copied_sets)
    totals = dict.fromkeys(["swaps", "moves", "collapses", "splits"], 0)
    for seed in range(80):
        V, F, k, kw, fold_kind = case(seed)
        got, want = both_passes(V, F, k, kw, fold_kind)
        assert_same(got, want)
        for key in totals:
            totals[key] += got[3][key]
    # Every operation took part, and operations were undone.
    assert all(count > 20 for count in totals.values()), totals
    assert len(restores) > 20


@bitwise
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(1000, 10**6))
def test_compiled_pass_is_the_numpy_pass_hypothesis(seed):
    V, F, k, kw, fold_kind = case(seed)
    assert_same(*both_passes(V, F, k, kw, fold_kind))


def test_fold_test_refusing_a_move_undoes_it():
    # The warm-up's case: the move is refused, the round again face by face, the square as it was.
    square = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.9, 0.12, 0.0]])
    F = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    V2, F2, keep, stats = QP.raise_min_quality(square, F, 4, fold_test=lambda V, F: int(V[4, 0] != 0.9))
    assert V2.tobytes() == square.tobytes() and np.array_equal(F2, F) and not any(stats.values())
    assert QP.raise_min_quality(square, F, 4)[3]["moves"] == 1


# ----------------------------------------------------------------- building blocks

def test_gemv_row_is_numpy_matmul():
    """Within rounding everywhere; to the bit where numpy's BLAS rounds as the copy (see SAME_GEMV)."""
    rng = np.random.default_rng(0)
    for rows in (1, 2, 3, 5, 8, 13, 40):
        for _ in range(50):
            A = rng.standard_normal((rows, 3)) * 2.0 ** rng.integers(-20, 20, (rows, 3))
            b = rng.standard_normal(3)
            want = A @ b
            got = np.array([KQ.gemv_row(A[i], b, rows) for i in range(rows)])
            scale = np.abs(A) @ np.abs(b)
            assert np.all(np.abs(got - want) <= 4 * np.finfo(float).eps * scale)
            if SAME_GEMV:
                assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("n", [1, 2, 7, 8, 9, 16, 17, 127, 128, 129, 300, 1025, 5000])
def test_pairwise_mean_is_np_mean(n):
    rng = np.random.default_rng(n)
    for _ in range(10):
        a = np.abs(rng.standard_normal(n)) * 2.0 ** rng.integers(-10, 10, n)
        assert KQ.pairwise_mean(a, n) == np.mean(a)


def star(rng, s, k):
    """A free vertex (index k + s) and its fan over s ring vertices, the first k of which are loop vertices in order."""
    ang = np.sort(rng.uniform(0, 2 * np.pi, s))
    ring = np.stack([np.cos(ang), np.sin(ang), rng.normal(scale=0.2, size=s)], axis=1)
    V = np.vstack([ring, [rng.normal(scale=0.2, size=3)]])
    c = len(V) - 1
    T = np.array([[c, i, (i + 1) % s] for i in range(s)], np.int64)
    T = np.array([np.roll(t, rng.integers(3)) for t in T])
    return V, T, c


def test_valid_is_patch_valid():
    rng = np.random.default_rng(1)
    outcomes = set()
    for _ in range(400):
        s = int(rng.integers(3, 9))
        k = int(rng.integers(2, s + 1))
        V, T, c = star(rng, s, k)
        border = border_normals(rng, V, k, 175.0)
        p = _Patch(V, T, k, (), border)
        P = V[T]
        ref = face_normals(V, T) + rng.normal(scale=rng.choice([0.0, 0.5, 2.0]), size=(s, 3))
        ref /= np.linalg.norm(ref, axis=1)[:, None]
        if rng.random() < 0.1:
            P[0, 1] = P[0, 0]  # degenerate
        want = p.valid(T, P, ref)
        q = np.empty(s)
        got = KQ.valid(T, np.ascontiguousarray(P), ref, context(k, border), q)
        assert got == (want is not None)
        if got:
            assert q.tobytes() == want.tobytes()
        outcomes.add(got)
    assert outcomes == {True, False}


@pytest.mark.parametrize("energy", [True, False])
def test_compass_search_is_optimise_position(energy):
    rng = np.random.default_rng(2 + energy)
    found = 0
    for _ in range(150):
        s = int(rng.integers(3, 9))
        k = int(rng.integers(2, s + 1))
        V, T, c = star(rng, s, k)
        border = border_normals(rng, V, k, rng.choice([30.0, 175.0])) if rng.random() < 0.8 else None
        p = _Patch(V, T, k, (), border)
        P = V[T]
        q0, cr = _quality(P)
        ref = cr / np.maximum(np.linalg.norm(cr, axis=1), 1e-300)[:, None]
        nv = cr.sum(axis=0)
        nv /= max(np.linalg.norm(nv), 1e-300)
        mask = T == c
        h = float(rng.uniform(0.01, 0.3))
        floor_min = float(q0.min()) * rng.uniform(0.0, 1.0)
        x0 = V[c] + rng.normal(scale=0.05, size=3)
        want = p.optimise_position(T, P, mask, ref, nv, x0.copy(), h, "energy" if energy else "min", floor_min)
        got = KQ.compass_search(T, P, np.argmax(mask, axis=1), ref, nv, x0, h, energy, floor_min,
                                context(k, border))
        if SAME_GEMV:  # elsewhere the two differ in last bits, and a step taken or not can follow from one
            assert got[0].tobytes() == np.asarray(want[0], np.float64).tobytes()
            assert got[1] == want[1] or (np.isnan(got[1]) and np.isnan(want[1]))
            assert got[2] == want[2] or (np.isnan(got[2]) and np.isnan(want[2]))
        assert not np.isfinite(got[1]) or got[2] >= floor_min  # a position found keeps the minimum above its floor
        found += bool(np.isfinite(got[1]) and not np.array_equal(got[0], x0))
    assert found > 50  # most searches move: positions are compared, not only failures


def test_bent_candidates_are_dropped_in_numpy_argsort_order():
    # Equal values, some not finite: the loop over np.argsort, whatever order it gives to ties.
    rng = np.random.default_rng(4)
    k, s = 3, 3
    T = np.array([[0, 1, 5], [1, 2, 5], [2, 0, 5]], np.int64)
    ties = 0
    for _ in range(3000):
        count = int(rng.choice([1, 8]))
        val = rng.choice([0.5, 0.25, 1.0, np.inf, np.nan], count, p=[0.35, 0.25, 0.2, 0.15, 0.05])
        N = rng.normal(size=(8, s, 3))
        N /= np.linalg.norm(N, axis=2)[..., None]
        border = rng.normal(size=(k, 3))
        p = _Patch(np.zeros((6, 3)), T, k, (), border)
        want = val.copy()
        for j in np.argsort(want):
            if not np.isfinite(want[j]) or p.border_ok(T, N[j]):
                break
            want[j] = np.inf
        got = val.copy()
        KQ._drop_bent_best(got, N, count, T, k, border, QP.BORDER_COS)
        assert got.tobytes() == want.tobytes()
        ties += len(np.unique(val[np.isfinite(val)])) < np.isfinite(val).sum()
    assert ties > 1000


@bitwise
def test_inputs_beyond_the_kernels_keys_run_the_numpy_pass():
    V, F, k, kw, _ = case(3)
    kw["blocked"] = {(0, 1, 1 << 22)}  # a triple index the keys do not hold
    assert_same(QP.raise_min_quality(V, F, k, **kw), QP.raise_min_quality_numpy(V, F, k, **kw))
    with pytest.raises(IndexError):  # too few mesh normals: numpy's error, not a read past the array
        QP.raise_min_quality(V, F, k, border_normals=np.zeros((k - 1, 3)), floor=0.9)
