"""HPDE folds: the loop-only triangulation (least largest dihedral angle), fold repair and the loop's own ears."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xie_zou2013 import folds as hpde_folds
from meshlab_holefill.core.patch import validate_patch

from hpde_cases import _cyclic


# ----------------------------------------------------------------- direct tests of building blocks

@settings(max_examples=30, deadline=None)
@given(k=st.integers(4, 12), data=st.data())
def test_loop_triangulation_of_a_planar_polygon_is_flat_valid_and_avoids_forbidden_chords(k, data):
    from meshlab_holefill.geometry.quality import face_areas
    from meshlab_holefill.core.patch import Patch

    t = 2 * np.pi * np.arange(k) / k
    P = np.stack([np.cos(t), np.sin(t), np.zeros(k)], axis=1)  # counter-clockwise: patch normal +z
    i = data.draw(st.integers(0, k - 3))
    j = data.draw(st.integers(i + 2, k - 1 if i > 0 else k - 2))  # a chord, not a loop edge
    up = np.tile([0.0, 0.0, 1.0], (k, 1))
    F, worst = hpde_folds.loop_triangulation(P, up, forbidden_edges=[[i, j]])
    # k - 2 triangles on the loop alone, each loop edge once in loop direction, the chord unused.
    assert F.shape == (k - 2, 3)
    validate_patch(Patch(np.zeros((0, 3)), F), P, forbidden_edges=[[i, j]])
    assert worst == pytest.approx(0.0, abs=1e-6)  # a flat fill bends nowhere, not even against the mesh
    assert face_areas(P, F).sum() == pytest.approx(0.5 * k * np.sin(2 * np.pi / k))  # covers the polygon once


def test_loop_triangulation_minimises_the_largest_dihedral_angle_exactly():
    # Unit square with corner 2 lifted by h. Diagonal (1, 3) bends by arccos(1 / sqrt(1 + 2h^2)),
    # diagonal (0, 2) by arccos(1 / (1 + h^2)), which is larger: Liepa's weight takes (1, 3).
    h = 0.5
    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, h], [0, 1, 0.0]])
    unknown = np.zeros((4, 3))  # no mesh face across the loop edges: only the inner dihedral counts
    F, worst = hpde_folds.loop_triangulation(P, unknown)
    assert {_cyclic(f) for f in F} == {(0, 1, 3), (1, 2, 3)}
    assert worst == pytest.approx(np.arccos(1 / np.sqrt(1 + 2 * h * h)), rel=1e-12)
    # The closing loop edge (3, 0) counts too: a mesh face there facing -z makes face (0, 1, 3)
    # fold by pi, so (0, 2) is taken and its worst angle is the one against that mesh face.
    across = unknown.copy()
    across[3] = [0.0, 0.0, -1.0]
    F, worst = hpde_folds.loop_triangulation(P, across)
    assert {_cyclic(f) for f in F} == {(0, 1, 2), (0, 2, 3)}
    assert worst == pytest.approx(np.arccos(-1 / np.sqrt(1 + h * h)), rel=1e-12)
    # A blocked triangle is never used, whatever its weight.
    F, _ = hpde_folds.loop_triangulation(P, unknown, blocked={(0, 1, 3)})
    assert {_cyclic(f) for f in F} == {(0, 1, 2), (0, 2, 3)}
    # Both diagonals blocked: impossible.
    F, worst = hpde_folds.loop_triangulation(P, unknown, blocked={(0, 1, 3), (0, 1, 2)})
    assert F is None and worst == np.inf


@settings(max_examples=40, deadline=None)
@given(k=st.integers(3, 24), seed=st.integers(0, 2**31), bumpy=st.floats(0.0, 1.0), data=st.data())
def test_loop_triangulation_is_the_plain_python_programme(k, seed, bumpy, data):
    """The compiled programme gives the plain-Python one's triangles, in its order, and its largest angle:
    on wavy loops, with unknown border normals (zero rows), forbidden chords and blocked triangles."""
    from hpde_loop_dp_oracle import loop_triangulation_python

    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    r = rng.uniform(0.6, 1.0, k)
    P = np.c_[r * np.cos(t), r * np.sin(t), bumpy * rng.standard_normal(k)]
    B = np.c_[0.5 * rng.standard_normal((k, 2)), np.ones(k)]
    B /= np.linalg.norm(B, axis=1, keepdims=True)
    B[rng.random(k) < data.draw(st.floats(0.0, 0.5))] = 0.0
    triples = [(i, m, j) for i in range(k) for m in range(i + 1, k) for j in range(m + 1, k)]
    blocked = {triples[x] for x in rng.choice(len(triples), size=min(len(triples), data.draw(st.integers(0, 6))),
                                             replace=False)}
    forbidden = [(i, j) for i, j in [(0, k // 2)] if 1 < j - i < k - 1] if data.draw(st.booleans()) else []
    F, worst = hpde_folds.loop_triangulation(P, B, forbidden, blocked=blocked)
    F0, worst0 = loop_triangulation_python(P, B, forbidden, blocked=blocked)
    if F0 is None:
        assert F is None and worst == np.inf
        return
    assert F.tolist() == F0.tolist()
    assert worst == pytest.approx(worst0, rel=1e-9, abs=1e-7)


def test_loop_triangulation_refuses_a_loop_above_its_size():
    P = np.c_[np.cos(np.arange(8)), np.sin(np.arange(8)), np.zeros(8)]
    assert hpde_folds.loop_triangulation(P, np.zeros((8, 3)), max_size=7) == (None, np.inf)


@settings(max_examples=20, deadline=None)
@given(k=st.integers(6, 14), points=st.integers(4, 24), seed=st.integers(0, 10_000), drag=st.floats(1.2, 2.5))
def test_repair_folds_unfolds_a_dragged_vertex_and_keeps_the_loop(k, points, seed, drag):
    from meshlab_holefill.geometry.quality import face_areas, face_normals
    from meshlab_holefill.core.patch import Patch

    from conftest import random_planar_patch

    X, F = random_planar_patch(k, points, seed)
    # Drag the free vertex of highest valence past its farthest neighbour, within the plane:
    # its star turns over (faces facing -z next to faces facing +z).
    deg = np.bincount(F.ravel(), minlength=len(X))
    v = k + int(np.argmax(deg[k:]))
    ring = np.setdiff1d(np.unique(F[np.any(F == v, axis=1)]), [v])
    far = ring[np.argmax(np.linalg.norm(X[ring] - X[v], axis=1))]
    W = X.copy()
    W[v] += drag * (X[far] - X[v])
    assert hpde_folds.local_folds(W, F).any()
    V2, F2, repairs = hpde_folds.repair_folds(W, F, k)
    assert repairs > 0
    assert np.array_equal(V2[:k], X[:k])  # loop vertices are fixed, bit-exact
    assert not hpde_folds.local_folds(V2, F2).any()
    assert np.all(face_normals(V2, F2)[:, 2] > 0) and np.abs(V2[:, 2]).max() == 0.0
    validate_patch(Patch(V2[k:], F2), X[:k])
    assert face_areas(V2, F2).sum() == pytest.approx(face_areas(X, F).sum())  # the disc covered once
    # Nothing folded: nothing to do, the input comes back unchanged.
    V3, F3, repairs = hpde_folds.repair_folds(X, F, k)
    assert repairs == 0 and np.array_equal(V3, X) and np.array_equal(F3, F)


def test_triangles_closing_a_short_notch_of_the_loop_count_as_the_loop_s_own():
    from meshlab_holefill.algorithms.xie_zou2013.folds import boundary_ears

    k = 20
    F = np.array([[0, 1, 2],  # an ear
                  [19, 0, 1],  # an ear across the loop's start
                  [0, 2, 4],  # a notch of 4 loop edges
                  [17, 1, 3],  # across the start: 6 edges
                  [0, 5, 10],  # a chord across 10 edges
                  [0, 1, 20]])  # a new vertex
    assert boundary_ears(F, k).tolist() == [True, True, False, False, False, False]
    assert boundary_ears(F, k, 8).tolist() == [True, True, True, True, False, False]
