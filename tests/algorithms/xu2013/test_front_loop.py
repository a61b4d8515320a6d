"""The compiled advancing-front loop (xu2013._front_loop) takes the Python reference's steps, bit for bit.

The reference (xu2013_front_oracle: the heap, linked lists and edge sets in Python around the
same per-step kernels) and the compiled loop run on the same holes: equal new vertices (bit
for bit), equal faces, equal stats, equal failure messages. The state's heap
(xu2013._front_state) pops in the order of Python's heapq; its pair tables behave as a dict.
"""
import heapq

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xu2013 import _front_state as state
from meshlab_holefill.algorithms.xu2013.advancing_front import advancing_front_triangulation
from meshlab_holefill.algorithms.xu2013.poisson_patch import reference_normals
from meshlab_holefill.core import examples, hole_context
from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.core.patch import HoleFillError

from conftest import cut_disks, mesh_arrays
from xu2013_front_oracle import oracle_triangulation


def assert_same_run(*args, **kwargs):
    """Compiled and Python runs give identical patches and stats, or fail with the same message."""
    try:
        ref = oracle_triangulation(*args, **kwargs)
    except HoleFillError as exc:
        with pytest.raises(HoleFillError, match=f"^{exc}$".replace("(", r"\(").replace(")", r"\)")):
            advancing_front_triangulation(*args, **kwargs)
        return None
    got = advancing_front_triangulation(*args, **kwargs)
    assert got[0].dtype == np.float64 and got[1].dtype == np.int64
    assert np.array_equal(got[0], ref[0]) and np.array_equal(got[1], ref[1])
    assert list(got[2].items()) == list(ref[2].items())
    return got


def sphere_contexts(centers, radius, subdiv=4, noise=0.0, seed=0):
    """HoleContexts of the holes cut into a (noisy) unit sphere."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    V, F = mesh_arrays(ms)
    V = V + noise * np.random.default_rng(seed).normal(size=V.shape) / 2 ** subdiv
    V, F, _ = cut_disks(V, F, np.asarray(centers, float), radius)
    return [hole_context(V, F, lp, rings=6) for lp in boundary_loops(F)]


def test_bowl_hole_with_obstacles_is_the_reference_run():
    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=6)
    got = assert_same_run(ctx.points, ctx.forbidden_edges, 0.75, reference_normal=reference_normals(ctx),
                          obstacles=(ctx.vertices, ctx.faces))
    assert got[2]["steps"] > 10 and got[2]["obstacle_tests"] > 0


@pytest.mark.parametrize("noise, radius", [(0.0, 0.6), (0.3, 0.6), (0.6, 0.9), (0.3, 1.3)])
def test_sphere_holes_with_obstacles_are_the_reference_run(noise, radius):
    # Noisy boundaries make the front refuse steps, split and merge; large ones wrap the sphere.
    for ctx in sphere_contexts([(0.0, 0.0, 1.0), (1.0, 0.0, 0.0)], radius, noise=noise):
        assert_same_run(ctx.points, ctx.forbidden_edges, 0.75, reference_normal=reference_normals(ctx),
                        obstacles=(ctx.vertices, ctx.faces))


@settings(max_examples=40, deadline=None)
@given(k=st.integers(3, 70), lobes=st.integers(2, 7), amplitude=st.floats(0.0, 0.6),
       phase=st.floats(0.0, 6.28), tilt=st.floats(-0.8, 0.8), merge=st.sampled_from([0.5, 0.75, 0.9]))
def test_star_shaped_holes_are_the_reference_run(k, lobes, amplitude, phase, tilt, merge):
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    r = 1 + amplitude * np.sin(lobes * t + phase)
    P = np.stack([r * np.cos(t), r * np.sin(t), tilt * r * np.cos(t) ** 2], axis=1)
    assert_same_run(P, (), merge)


def test_failures_are_the_reference_failures():
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    eight = np.stack([np.sin(t), np.sin(t) * np.cos(t), 1e-3 * np.cos(t)], axis=1)
    assert assert_same_run(eight) is None  # the front leaves the hole
    circle = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)
    assert assert_same_run(circle, max_faces=5) is None  # the triangle bound


def test_heap_pops_in_heapq_order():
    rng = np.random.default_rng(3)
    ht, hn, hv = np.empty(400), np.empty(400, np.int64), np.empty(400, np.int64)
    C = np.zeros(state.N_COUNTERS, np.int64)
    ref, popped, expected = [], [], []
    for step in range(300):
        if rng.random() < 0.6 or not ref:
            entry = (float(rng.integers(0, 5)) * 0.5, int(rng.integers(0, 6)), int(rng.integers(0, 3)))
            heapq.heappush(ref, entry)
            state.heap_push(ht, hn, hv, C, *entry)
        else:
            expected.append(heapq.heappop(ref)[1:])
            popped.append(state.heap_pop(ht, hn, hv, C))
    assert popped == expected and C[state.N_HEAP] == len(ref)


def test_pair_tables_behave_as_a_set_and_a_dict():
    # The state's hash tables of vertex pairs (insert, find, delete, rebuild) against Python's dict.
    rng = np.random.default_rng(5)
    C = np.zeros(state.N_COUNTERS, np.int64)
    keys = state._empty_table(8)
    vals = np.zeros((keys.shape[0], 3))
    ref = {}
    for step in range(3000):
        a, b = (int(x) for x in rng.integers(0, 40, 2))
        op = rng.random()
        slot = state._find(keys, a, b)
        assert (slot >= 0) == ((a, b) in ref)
        if op < 0.5:
            slot = state._insert(keys, a, b, C, state.F_USED)
            vals[slot] = step
            ref[(a, b)] = step
        elif op < 0.8 and slot >= 0:
            keys[slot] = state.DELETED
            del ref[(a, b)]
        if 2 * (C[state.F_USED] + 16) >= keys.shape[0]:
            keys, vals, C[state.F_USED] = state._rehashed(keys, vals, 4)
    assert state._find(keys, -1, 3) == -1  # temporary (negative) ids are never stored
    for (a, b), value in ref.items():
        assert vals[state._find(keys, a, b), 0] == value
    assert (keys >= 0).sum() == len(ref)
