"""The compiled fold agreement (_fold_kernels) against the numpy code it replaces, bit for bit."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
import pytest

from meshlab_holefill.algorithms.xie_zou2013._fold_kernels import folded_faces, pair_agreements
from meshlab_holefill.geometry.quality import face_normals


def _border_agreement(F, N, border_normals):
    """Smallest dot of each face normal with the mesh normals across its loop edges (1 if none), (m,)."""
    out = np.ones(len(F))
    if border_normals is None or len(F) == 0:
        return out
    k = len(border_normals)
    for c in range(3):
        u, v = F[:, c], F[:, (c + 1) % 3]
        on = (u < k) & (v == (u + 1) % k)
        out[on] = np.minimum(out[on], np.einsum("ij,ij->i", N[on], border_normals[u[on]]))
    return out


def _pair_agreement(V, A, B, border_normals):
    """The numpy oracle: fold agreement of the face pairs A[i], B[i] and whether both are non-degenerate."""
    NA, NB = face_normals(V, A), face_normals(V, B)
    agreement = np.minimum(np.einsum("ij,ij->i", NA, NB),
                           np.minimum(_border_agreement(A, NA, border_normals),
                                      _border_agreement(B, NB, border_normals)))
    return agreement, np.any(NA != 0, axis=1) & np.any(NB != 0, axis=1)


def _faces(rng, n, k, s):
    """s random faces on n vertices, a third of them on a loop edge (i, i + 1 mod k), some degenerate."""
    F = rng.integers(0, n, size=(s, 3))
    on_loop = rng.random(s) < 0.35
    i = rng.integers(0, k, size=s)
    F[on_loop, 0], F[on_loop, 1] = i[on_loop], (i[on_loop] + 1) % k
    F[::7, 2] = F[::7, 0]  # repeated vertex: zero normal
    return np.roll(F, rng.integers(0, 3), axis=1)


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")  # inf - inf in the poisoned rows
@pytest.mark.parametrize("poison", [None, np.nan, np.inf])
def test_pair_agreements_equal_the_numpy_agreement_bit_for_bit(poison):
    rng = np.random.default_rng(11)
    for trial in range(50):
        n, k, s = 14, int(rng.integers(3, 9)), int(rng.integers(0, 40))
        V = rng.normal(size=(n, 3))
        V[rng.integers(n)] = V[rng.integers(n)]  # coincident vertices
        if poison is not None:
            V[rng.integers(n)] = poison
        border = rng.normal(size=(k, 3))
        border /= np.linalg.norm(border, axis=1, keepdims=True)
        faces = np.stack([_faces(rng, n, k, s) for _ in range(4)])
        for normals, known in ((border, border), (None, np.zeros((0, 3)))):
            agreement, proper = pair_agreements(V, faces, known)
            for t in range(2):
                want_a, want_p = _pair_agreement(V, faces[2 * t], faces[2 * t + 1], normals)
                np.testing.assert_array_equal(agreement[t], want_a)
                np.testing.assert_array_equal(proper[t], want_p)


@pytest.mark.filterwarnings("ignore:invalid value:RuntimeWarning")
@pytest.mark.parametrize("poison", [None, np.nan, np.inf])
def test_fold_swap_scores_are_the_agreements_of_the_folded_edges(poison):
    from meshlab_holefill.algorithms.xie_zou2013._fold_kernels import fold_swap_scores

    rng = np.random.default_rng(12)
    for trial in range(50):
        n, k, s = 14, int(rng.integers(3, 9)), int(rng.integers(0, 40))
        V = rng.normal(size=(n, 3))
        V[rng.integers(n)] = V[rng.integers(n)]
        if poison is not None:
            V[rng.integers(n)] = poison
        border = rng.normal(size=(k, 3))
        border /= np.linalg.norm(border, axis=1, keepdims=True)
        faces = np.stack([_faces(rng, n, k, s) for _ in range(4)])
        for known in (border, np.zeros((0, 3))):
            agreement, proper = pair_agreements(V, faces, known)
            old, new = fold_swap_scores(V, *faces, known)
            np.testing.assert_array_equal(old, agreement[0])
            np.testing.assert_array_equal(new, np.where((agreement[0] < 0.0) & proper[1], agreement[1], -np.inf))


def _folded_grid(rng, n=7, fold=1.5):
    """An n x n grid of triangles, its vertices moved up and down (folds where neighbours disagree),
    some quads flipped the other way; the first 4 (n - 1) vertices, its border in order, are the loop."""
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    V = np.c_[x.ravel(), y.ravel(), fold * rng.normal(size=n * n)]
    V[:, :2] += 0.3 * rng.normal(size=(n * n, 2))
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    flip = rng.random(len(i)) < 0.5
    F = np.concatenate([np.where(flip[:, None], np.c_[i, i + 1, i + n], np.c_[i, i + 1, i + n + 1]),
                        np.where(flip[:, None], np.c_[i + 1, i + n + 1, i + n], np.c_[i, i + n + 1, i + n])])
    ring = ([r for r in range(n)] + [c * n + n - 1 for c in range(1, n)] + [n * n - 1 - r for r in range(1, n)]
            + [(n - 1 - c) * n for c in range(1, n - 1)])
    order = np.r_[ring, np.setdiff1d(np.arange(n * n), ring)]
    relabel = np.empty(n * n, np.int64)
    relabel[order] = np.arange(n * n)
    return V[order], relabel[F], len(ring)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10 ** 6), fold=st.sampled_from([0.3, 1.5, 4.0]), forbidden=st.booleans(),
       border=st.booleans(), repeat=st.booleans(), rounds=st.integers(1, 20))
def test_compiled_fold_swap_rounds_make_the_numpy_rounds_swaps(seed, fold, forbidden, border, repeat, rounds):
    from meshlab_holefill.algorithms.xie_zou2013.folds import unfold_by_swaps, unfold_by_swaps_numpy

    rng = np.random.default_rng(seed)
    V, F, k = _folded_grid(rng, fold=fold)
    if repeat:  # a directed edge twice: the compiled rounds hand over to numpy
        F = np.vstack([F, F[rng.integers(len(F))]])
    chords = rng.integers(0, k, size=(6, 2)) if forbidden else ()
    normals = None
    if border:
        normals = rng.normal(size=(k, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    got, got_swaps = unfold_by_swaps(V, F, chords, normals, max_rounds=rounds)
    want, want_swaps = unfold_by_swaps_numpy(V, F, chords, normals, max_rounds=rounds)
    np.testing.assert_array_equal(got, want)
    assert got_swaps == want_swaps


def _crumpled_disc(seed, k, inner, crumple):
    """A Delaunay disc, k loop vertices first, lifted by random heights of amplitude ``crumple`` (folds where large)."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    XY = np.concatenate([np.stack([np.cos(t), np.sin(t)], axis=1),
                         0.9 * np.sqrt(rng.random((inner, 1))) * np.exp(1j * 2 * np.pi * rng.random((inner, 1)))
                         .view(np.float64).reshape(inner, 2)])
    F = Delaunay(XY).simplices.astype(np.int64)
    V = np.column_stack([XY, crumple * rng.normal(size=len(XY))])
    return V, F, rng


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), k=st.integers(3, 20), inner=st.integers(0, 40), crumple=st.floats(0.0, 2.0),
       border=st.booleans(), angle=st.sampled_from([90.0, 150.0, 175.0]))
def test_compiled_local_folds_give_the_numpy_answer(seed, k, inner, crumple, border, angle):
    from meshlab_holefill.algorithms.xie_zou2013.folds import local_folds, local_folds_numpy

    V, F, rng = _crumpled_disc(seed, k, inner, crumple)
    F[::5] = F[::5, ::-1]  # some faces turned over
    normals = None
    if border:
        normals = rng.normal(size=(k, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    ref = local_folds_numpy(V, F, normals, np.radians(angle))
    np.testing.assert_array_equal(local_folds(V, F, normals, np.radians(angle)), ref)


def test_local_folds_of_a_face_list_with_a_repeated_directed_edge_are_the_numpy_ones():
    from meshlab_holefill.algorithms.xie_zou2013.folds import local_folds, local_folds_numpy

    V, F, _ = _crumpled_disc(1, 8, 10, 0.5)
    F = np.concatenate([F, F[:1]])  # a face stored twice: its directed edges repeat
    assert not folded_faces(V, F, np.zeros((0, 3)), -0.5)[1]  # the compiled table refuses it
    np.testing.assert_array_equal(local_folds(V, F), local_folds_numpy(V, F))
