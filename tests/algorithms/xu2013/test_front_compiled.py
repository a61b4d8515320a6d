"""The advancing front's compiled step tests (xu2013._front_kernels) give the decisions of the Python predicates.

Each kernel is compared with a plain-Python/numpy oracle built from :mod:`._front_predicates`
(themselves tested against exact references in test_front_predicates.py): equal booleans,
equal merge targets, and bit-equal angles, on random inputs including degenerate ones.
"""
import math

import numpy as np
from hypothesis import given, settings, strategies as st

from meshlab_holefill.algorithms.xu2013 import _front_kernels as K
from meshlab_holefill.algorithms.xu2013._front_obstacles import FrontObstacles
from meshlab_holefill.algorithms.xu2013._front_predicates import (cross, direction_angle, dot, norm, segments_cross,
                                                                  segments_hit_triangles, sub, unit)

TWO = 2.0
small = st.integers(-4, 4).map(lambda i: 0.25 * i)  # coarse values: collinear and touching cases are frequent
coord = st.one_of(small, st.floats(-3, 3, allow_nan=False))
point2 = st.tuples(coord, coord)
point3 = st.tuples(coord, coord, coord)


@settings(max_examples=300, deadline=None)
@given(point2, point2, point2, point2)
def test_segments_cross_2d_equals_python(a0, a1, b0, b1):
    assert K.segments_cross_2d(*a0, *a1, *b0, *b1) is segments_cross(a0, a1, b0, b1)


@settings(max_examples=300, deadline=None)
@given(point3, point3, point3, point3, point3)
def test_segment_hits_triangle_equals_numpy(p0, p1, a, b, c):
    P0, P1, A, B, C = (np.array(x, np.float64) for x in (p0, p1, a, b, c))
    ref = bool(segments_hit_triangles(P0[None], P1[None], np.array([[a, b, c]], np.float64), 1e-9)[0])
    assert K.segment_hits_triangle(P0, P1, A, B, C, 1e-9) is ref


@settings(max_examples=200, deadline=None)
@given(point3, point3, point3)
def test_direction_angle_is_bit_equal(r, d, m):
    m = unit(m)
    assert K._direction_angle(*r, *d, np.array(m)) == direction_angle(r, d, m)


def _random_front(rng, n=40, labels=2):
    """Positions, and nodes (vertex, next, front label) of a few random cycles, some nodes dead."""
    P = rng.normal(size=(n + 10, 3))
    P[5] = P[6]  # coincident vertices
    P[7] = P[8] + np.array([1e-300, 0.0, 0.0])
    node_vertex = rng.permutation(n + 10)[:n]
    node_front = rng.integers(0, labels, n)
    node_next = np.empty(n, np.int64)
    for label in range(labels):
        ids = np.flatnonzero(node_front == label)
        node_next[ids] = np.roll(ids, -1)
    alive = rng.permutation(n)[: n - 5]  # five dead nodes
    return P, node_vertex.astype(np.int64), node_next, node_front.astype(np.int64), alive.astype(np.int64)


def _near_python(P, verts, pos, radius, cell):
    """FrontState._near: grid cells of the box pos +- radius, then the exact squared distance."""
    key = lambda x: tuple(math.floor(x[i] / cell) for i in range(3))  # noqa: E731
    lo, hi = key([pos[i] - radius for i in range(3)]), key([pos[i] + radius for i in range(3)])
    out = []
    for u in set(verts):
        X = tuple(P[u])
        if all(lo[i] <= key(X)[i] <= hi[i] for i in range(3)):
            d = (X[0] - pos[0]) ** 2 + (X[1] - pos[1]) ** 2 + (X[2] - pos[2]) ** 2
            if d <= radius * radius:
                out.append((d, u))
    return out


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.05, 3.0), st.floats(0.1, 2.0))
def test_merge_target_is_the_first_of_the_sorted_neighbours(seed, radius, cell):
    rng = np.random.default_rng(seed)
    P, nv, nn, nf, alive = _random_front(rng)
    pos = tuple(P[nv[alive[0]]] + rng.normal(size=3) * 0.3)
    v, p, q = (int(nv[alive[i]]) for i in (1, 2, 3))
    for label in (0, 1):
        on_front = {int(nv[i]) for i in alive if nf[i] == label}
        ref = next((u for _, u in sorted(_near_python(P, [int(nv[i]) for i in alive], pos, radius, cell))
                    if u not in (v, p, q) and u in on_front), -1)
        got = K.merge_target(np.array(pos), radius, v, p, q, label, P, nv, nf, alive, len(alive), cell, TWO)
        assert got == ref


def _no_crossing_python(edge_ids, segs, V, m, longest_edge, P, front_edges, verts, cell):
    """The Python _no_crossing: new edges against the front edges near V, in m's plane."""
    reach = max(max(norm(sub(s0, V)), norm(sub(s1, V))) for s0, s1 in segs) + longest_edge
    e1 = unit(cross(m, (1.0, 0.0, 0.0) if abs(m[0]) < 0.9 else (0.0, 1.0, 0.0)))
    e2 = cross(m, e1)
    flat = lambda x: (dot(x, e1), dot(x, e2))  # noqa: E731
    near = {u for _, u in _near_python(P, verts, V, reach, cell)}
    for x, y in front_edges:
        if x not in near:
            continue
        for (a, b), (s0, s1) in zip(edge_ids, segs):
            if a in (x, y) or b in (x, y):
                continue
            if segments_cross(flat(s0), flat(s1), flat(tuple(P[x])), flat(tuple(P[y]))):
                return False
    return True


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 1.0), st.sampled_from([(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), None]))
def test_front_edges_crossed_equals_python(seed, longest_edge, m):
    rng = np.random.default_rng(seed)
    P, nv, nn, nf, alive = _random_front(rng)
    m = unit(tuple(rng.normal(size=3))) if m is None else m
    V = P[nv[alive[0]]]
    ids = [(int(nv[alive[0]]), -1), (-1, int(nv[alive[1]]))]
    new = tuple(V + 0.5 * rng.normal(size=3))
    segs = [(tuple(V), new), (new, tuple(P[ids[1][1]]))]
    front_edges = {(int(nv[i]), int(nv[nn[i]])) for i in alive}
    ref = _no_crossing_python(ids, segs, tuple(V), m, longest_edge, P, front_edges, [int(nv[i]) for i in alive], 1.0)
    got = K.front_edges_crossed(np.array(ids, np.int64), np.array(segs), V, np.array(m), longest_edge, P, nv, nn,
                                alive, len(alive), 1.0, TWO)
    assert got is (not ref)


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.01, 4.0))
def test_near_any_equals_python(seed, r):
    rng = np.random.default_rng(seed)
    P, nv, nn, nf, alive = _random_front(rng)
    blocked = rng.integers(0, len(nv), 12)
    points = P[rng.integers(0, len(P), 3)] + rng.normal(size=(3, 3))
    for b in blocked.tolist():
        X = P[nv[b]]
        ref = any((X[0] - Y[0]) ** 2 + (X[1] - Y[1]) ** 2 + (X[2] - Y[2]) ** 2 <= r * r for Y in points.tolist())
        assert K.near_any(X[0], X[1], X[2], points, r * r, TWO) is ref


def _obstacle_crossed_python(obstacles, faces, corners, cand):
    """The numpy crossing test of the new triangles against the faces cand (pairs, then one batch)."""
    k, segs_a, segs_b, tris = obstacles.k, [], [], []
    for f, T in zip(faces, corners):
        for o in obstacles.F[cand].tolist():
            shared = [x for x in f if 0 <= x < k and x in o]
            O = [tuple(obstacles.V[x]) for x in o]
            if len(shared) >= 2:
                continue
            if len(shared) == 1:
                ta = [T[j] for j in range(3) if f[j] != shared[0]]
                ob = [O[j] for j in range(3) if o[j] != shared[0]]
                segs_a += [ta[0], ob[0]]
                segs_b += [ta[1], ob[1]]
                tris += [O, T]
            else:
                for j in range(3):
                    segs_a += [T[j], O[j]]
                    segs_b += [T[(j + 1) % 3], O[(j + 1) % 3]]
                    tris += [O, T]
    return bool(tris) and bool(segments_hit_triangles(np.asarray(segs_a), np.asarray(segs_b), np.asarray(tris),
                                                      1e-9 * obstacles.cell).any())


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.2, 2.0))
def test_obstacle_candidates_and_crossing_equal_python(seed, cell):
    rng = np.random.default_rng(seed)
    k = 6
    V = rng.normal(size=(30, 3))
    F = np.array([rng.choice(30, 3, replace=False) for _ in range(40)])  # mesh faces: three distinct vertices
    F[:4] = [[0, 1, 10], [1, 2, 11], [2, 3, 12], [3, 4, 13]]  # faces sharing boundary vertices with the new triangles
    obstacles = FrontObstacles(V, F, cell, k)
    lo, hi = np.sort(rng.normal(size=(2, 3)), axis=0)
    expected = np.flatnonzero(np.all(obstacles.hi >= lo - 1e-9 * cell, axis=1)
                              & np.all(obstacles.lo <= hi + 1e-9 * cell, axis=1))
    assert sorted(obstacles.candidates(lo, hi).tolist()) == expected.tolist()
    faces = [(0, 1, -1), (1, 2, 40), (-1, -2, 41)]
    positions = {0: V[0], 1: V[1], 2: V[2], -1: rng.normal(size=3), -2: rng.normal(size=3), 40: rng.normal(size=3),
                 41: rng.normal(size=3)}
    corners = [[tuple(positions[x]) for x in f] for f in faces]
    for use in ([0], [1], [2], [0, 1, 2]):
        fs, cs = [faces[i] for i in use], [corners[i] for i in use]
        T = np.asarray(cs).reshape(-1, 3, 3)
        cand = obstacles.candidates(T.min(axis=(0, 1)), T.max(axis=(0, 1))).copy()
        ref = len(cand) > 0 and _obstacle_crossed_python(obstacles, fs, cs, cand)
        assert obstacles.crossed(fs, cs) is ref


def test_obstacle_grid_lists_every_face_in_every_cell_it_meets():
    """A face spanning many cells is found from a query box touching any one of them."""
    V = np.array([[0.0, 0, 0], [5, 0, 0], [0, 5, 0], [10, 10, 10], [10.5, 10, 10], [10, 10.5, 10]])
    obstacles = FrontObstacles(V, np.array([[0, 1, 2], [3, 4, 5]]), 1.0, 0)
    assert obstacles.candidates([3.5, 0.5, -0.1], [3.6, 0.6, 0.1]).tolist() == [0]
    assert obstacles.candidates([10.2, 10.2, 9.9], [10.3, 10.3, 10.1]).tolist() == [1]
    assert obstacles.candidates([20.0, 20, 20], [21.0, 21, 21]).tolist() == []
    assert obstacles.candidates([-50.0, -50, -50], [50.0, 50, 50]).tolist() == [0, 1]


def test_warm_up_loads_every_kernel_the_front_calls():
    # The per-step kernels are linked into the compiled loop: its two entry points are all a
    # worker needs loaded.
    from meshlab_holefill.algorithms.xu2013 import _front_loop
    from meshlab_holefill.algorithms.xu2013.advancing_front import warm_up
    warm_up()
    for name in ("initial_state", "run_front"):
        assert len(getattr(_front_loop, name).signatures) >= 1, name


def test_the_filter_warm_up_also_loads_the_edge_relaxation_rounds():
    from meshlab_holefill.algorithms.xu2013 import _front_loop, lssvm_poisson
    from meshlab_holefill.geometry import _flip_kernels

    lssvm_poisson.WARM_UP()
    assert _front_loop.run_front.signatures
    assert _flip_kernels.swap_candidates.signatures and _flip_kernels.apply_swaps.signatures


def test_the_filter_warm_up_loads_the_laplacian_kernels():
    from meshlab_holefill.algorithms.xu2013 import _laplacian_kernels, lssvm_poisson

    lssvm_poisson.WARM_UP()
    for name in _laplacian_kernels.__all__:
        assert getattr(_laplacian_kernels, name).signatures, name
