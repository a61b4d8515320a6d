"""geometry.dihedral_triangulation: the loop triangulated by least largest bend, then least area (Liepa's weight)."""
import doctest

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.errors import HoleFillError
from meshlab_holefill.geometry import dihedral_triangulation as module
from meshlab_holefill.geometry.dihedral_triangulation import dihedral_triangulation


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def loop(k, seed, bumpy=0.3):
    """A star-shaped loop of k points around the z axis, wavy in z, and tilted border normals."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    r = rng.uniform(0.6, 1.0, k)
    P = np.c_[r * np.cos(t), r * np.sin(t), bumpy * rng.standard_normal(k)]
    B = unit(np.c_[0.5 * rng.standard_normal((k, 2)), np.ones(k)])
    return P, B


def is_triangulation(F, k):
    """k - 2 triangles (i < m < j) using each loop edge once and each chord twice."""
    from collections import Counter

    edges = Counter(tuple(e) for i, m, j in F.tolist() for e in ((i, m), (m, j), (i, j)))
    loop_edges = {(i, i + 1) for i in range(k - 1)} | {(0, k - 1)}
    return (len(F) == k - 2 and bool(np.all((F[:, 0] < F[:, 1]) & (F[:, 1] < F[:, 2])))
            and all(edges[e] == 1 for e in loop_edges)
            and all(n == 2 for e, n in edges.items() if e not in loop_edges))


def test_a_zero_border_normal_bends_nothing():
    """A loop edge whose mesh face has no usable normal (a zero row) puts no bend on the triangles there."""
    P, B = loop(9, 3, bumpy=0.6)
    free = B.copy()
    free[4] = 0.0
    _, worst = module.least_bend_splits(P, free)
    _, constrained = module.least_bend_splits(P, B)
    assert worst <= constrained  # one constraint fewer: the optimum cannot bend more
    F = dihedral_triangulation(P, free)
    assert is_triangulation(F, 9)


@settings(max_examples=20, deadline=None)
@given(k=st.integers(5, 40), seed=st.integers(0, 2**31))
def test_forbidden_edges_and_banned_triangles_are_not_used(k, seed):
    P, B = loop(k, seed)
    first = dihedral_triangulation(P, B)
    chord = next((i, j) for i, m, j in first.tolist() if j - i > 1 and (i, j) != (0, k - 1))
    without = dihedral_triangulation(P, B, forbidden_edges=[chord[::-1]])
    assert is_triangulation(without, k)
    assert chord not in {e for i, m, j in without.tolist() for e in ((i, m), (m, j), (i, j))}
    banned = first[:2]
    other = dihedral_triangulation(P, B, banned=banned[:, ::-1])  # any corner order
    assert is_triangulation(other, k)
    assert not set(map(tuple, banned.tolist())) & set(map(tuple, other.tolist()))


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), lean=st.floats(-3.0, 3.0))
def test_of_a_quadrilaterals_two_triangulations_the_one_bending_least_is_taken(seed, lean):
    """Four loop points: the programme has no sub-choice to make, so its answer is the exact optimum."""
    P, B = loop(4, seed, bumpy=1.0)
    B[1] = unit(B[1] + [lean, 0.0, 0.0])  # the mesh face on edge (1, 2) leaning in or out
    chosen = dihedral_triangulation(P, B)
    both = [np.array([[0, 1, 2], [0, 2, 3]]), np.array([[0, 1, 3], [1, 2, 3]])]
    scores = [largest_bend(P, B, F) for F in both]
    assert largest_bend(P, B, chosen) == min(scores)


def largest_bend(P, B, F):
    """Largest 1 - cos between the two triangles' normals and between each and the mesh face on its loop edges."""
    N = unit(np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]))
    bends = [1.0 - N[0] @ N[1]]
    for t, (i, m, j) in enumerate(F.tolist()):
        for a, b in ((i, m), (m, j), (i, j)):
            if b == a + 1:
                bends.append(1.0 - N[t] @ B[a])
            elif (a, b) == (0, 3):
                bends.append(1.0 - N[t] @ B[3])
    return max(bends)


def test_no_triangulation_is_refused_by_name():
    P, B = loop(4, 0)
    with pytest.raises(HoleFillError, match="no triangulation of the loop avoids"):
        dihedral_triangulation(P, B, forbidden_edges=[(0, 2), (1, 3)])
    with pytest.raises(HoleFillError, match="fewer than 3 vertices"):
        dihedral_triangulation(P[:2], B[:2])
    with pytest.raises(ValueError, match=r"border_normals must be \(4, 3\), got \(4, 3\) and \(3, 3\)"):
        dihedral_triangulation(P, B[:3])


def test_the_examples_run():
    assert doctest.testmod(module).failed == 0
