"""The compiled relaxation rounds with the hole-sector veto against relax_edges with the same veto as a hook."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.hu2012 import _relax_kernels as R
from meshlab_holefill.algorithms.hu2012.hole_guards import LoopSectors, relax_in_sectors
from meshlab_holefill.geometry._flip_kernels import fixed_keys
from meshlab_holefill.geometry.flips import relax_edges
from meshlab_holefill.geometry.topology import interior_edges

from conftest import grid


def _sector_hook(sectors):
    return lambda V, F, A, B, replaced: sectors.swaps_allowed(V, B)


def _bumpy_patch_with_sectors(rng):
    """A jittered bumpy grid with random diagonals whose first k vertices carry hole sectors."""
    nx = int(rng.integers(3, 12))
    V, F = grid(nx, nx)
    V = V + np.concatenate([rng.normal(scale=0.3 / nx, size=(len(V), 2)), np.zeros((len(V), 1))], axis=1)
    V[:, 2] = 0.3 * np.sin(3 * V[:, 0]) * rng.uniform(0, 1) + rng.normal(scale=0.02, size=len(V)) * rng.integers(0, 2)
    flip = rng.random(len(F) // 2) < 0.5  # the other diagonal of some grid squares
    quads = F.reshape(2, -1, 3)
    a, b, c, d = quads[0, :, 0], quads[0, :, 1], quads[0, :, 2], quads[1, :, 2]
    F = np.concatenate([np.where(flip[:, None], np.stack([a, b, d], 1), quads[0]),
                        np.where(flip[:, None], np.stack([b, c, d], 1), quads[1])])
    k = int(rng.integers(3, len(V)))
    sectors = LoopSectors(V[:k], np.array([0.0, 0.0, 1.0]) + 0.5 * rng.normal(size=(k, 3)))
    E = interior_edges(F, len(V))[0]
    fixed = E[rng.random(len(E)) < 0.1]
    return V, F, fixed, sectors


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), criterion=st.sampled_from(["angles", "sphere"]),
       max_rounds=st.sampled_from([1, 2, 3, 200]))
def test_compiled_rounds_make_the_swaps_of_relax_edges_with_the_sector_hook(seed, criterion, max_rounds):
    V, F, fixed, sectors = _bumpy_patch_with_sectors(np.random.default_rng(seed))
    want = relax_edges(V, F, fixed, allowed=_sector_hook(sectors), criterion=criterion, max_rounds=max_rounds)
    got = relax_in_sectors(sectors, V, F, fixed, criterion, max_rounds=max_rounds)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), criterion=st.sampled_from(["angles", "sphere"]))
def test_rounds_the_sector_test_refuses_a_swap_of_are_left_to_the_hook(seed, criterion):
    # A hook that allows more than the sector test (deterministic in the swap): the rounds where
    # the sector test refuses something must follow it, the others the sector test.
    V, F, fixed, sectors = _bumpy_patch_with_sectors(np.random.default_rng(seed))

    def hook(V, F, A, B, replaced):
        return sectors.swaps_allowed(V, B) | ((A.sum(axis=1) + B.sum(axis=1)) % 2 == 0)

    want = relax_edges(V, F, fixed, allowed=hook, criterion=criterion)
    got = relax_in_sectors(sectors, V, F, fixed, criterion, refused=hook)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), criterion=st.sampled_from(["angles", "sphere"]))
def test_a_settled_relaxation_leaves_nothing_for_a_hook_to_reconsider(seed, criterion):
    # Settled: the sector test refused nothing in the last round, so a hook that allows more than
    # it (where it refuses) finds no swap either; otherwise the hook may find some.
    V, F, fixed, sectors = _bumpy_patch_with_sectors(np.random.default_rng(seed))

    def hook(V, F, A, B, replaced):
        return np.ones(len(A), bool)

    F1, _, settled = relax_in_sectors(sectors, V, F, fixed, criterion)
    F2, swaps, _ = relax_in_sectors(sectors, V, F1, fixed, criterion, refused=hook)
    want = relax_edges(V, F1, fixed, allowed=hook, criterion=criterion)
    np.testing.assert_array_equal(F2, want[0])
    if settled:
        assert swaps == 0 and np.array_equal(F2, F1)


def test_bumpy_patches_are_settled_or_not():
    # Both outcomes occur on these patches: a refusal of the sector test unsettles the relaxation.
    flags = set()
    for seed in range(40):
        V, F, fixed, sectors = _bumpy_patch_with_sectors(np.random.default_rng(seed))
        flags.add(relax_in_sectors(sectors, V, F, fixed, "angles")[2])
    assert flags == {True, False}


def _limit_quad(move=0.0):
    """Edge (0, 1) with opposite angles pi / 2 and pi / 2 + pi 1e-9: the unfolded test's limit (plus ``move``)."""
    t = 1.0 / np.tan(np.pi / 4 + np.pi / 2 * 1e-9)
    V = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, t + move, 0], [5, 5, 0], [6, 5, 0], [5, 6, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3], [4, 5, 6]])
    return V, F


def test_an_undecided_angle_sum_stops_the_kernel_and_runs_in_relax_edges():
    V, F = _limit_quad()
    far = LoopSectors(V[4:7], np.tile([0.0, 0.0, 1.0], (3, 1)))  # sectors at the far triangle only
    sectors = LoopSectors(np.concatenate([V[:3]]), np.tile([0.0, 0.0, 1.0], (3, 1)))
    for s in (far, sectors):
        status, swaps, rounds = R.relax_rounds(V, F.copy(), np.zeros(0, np.int64), False, 200, s.points, s.u, s.w,
                                               s.limit, 1e-9, False)
        assert (status, swaps, rounds) == (R.UNDECIDED, 0, 0)
    for move in (0.0, 1e-6, -1e-6):
        W, _ = _limit_quad(move)
        want = relax_edges(W, F, allowed=_sector_hook(sectors), criterion="angles")
        got = relax_in_sectors(sectors, W, F, criterion="angles")
        np.testing.assert_array_equal(got[0], want[0])
        assert got[1] == want[1]


def test_a_new_edge_on_a_sector_bound_is_left_to_relax_edges():
    # The swap of (0, 1) makes the edge (2, 3), which leaves loop vertex 2 along its sector's bound.
    V = np.array([[-1, 0, 0], [1, 0, 0], [0, -0.2, 0], [0, 0.3, 0], [0, -1.0, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    sectors = LoopSectors(V[:3], np.tile([0.0, 0.0, 1.0], (3, 1)))
    sectors.limit[2] = sectors._angle(np.array([2]), V[[3]])[0] + 1e-9  # upper bound exactly at the new edge
    status = R.relax_rounds(V, F.copy(), np.zeros(0, np.int64), True, 200, sectors.points, sectors.u, sectors.w,
                            sectors.limit, 1e-9, False)[0]
    assert status == R.UNDECIDED
    want = relax_edges(V, F, allowed=_sector_hook(sectors), criterion="sphere")
    np.testing.assert_array_equal(relax_in_sectors(sectors, V, F)[0], want[0])


def test_a_face_with_a_repeated_vertex_is_left_to_relax_edges():
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -0.1, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3], [2, 2, 3]])
    sectors = LoopSectors(V[:3], np.tile([0.0, 0.0, 1.0], (3, 1)))
    status = R.relax_rounds(V, F.copy(), np.zeros(0, np.int64), True, 200, sectors.points, sectors.u, sectors.w,
                            sectors.limit, 1e-9, False)[0]
    assert status == R.UNDECIDED
    want = relax_edges(V, F, allowed=_sector_hook(sectors), criterion="sphere")
    got = relax_in_sectors(sectors, V, F)
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


def test_the_neighbour_lists_grow_past_their_room():
    F = np.array([[0, 1, 2]])
    nbr, deg = R._adjacency(F, 40, np.full(3, -1))
    assert sorted(nbr[0, :deg[0]]) == [1, 2] and nbr.shape[1] == 10
    for b in range(3, 40):
        nbr = R._link(nbr, deg, 0, b)
    assert sorted(nbr[0, :deg[0]]) == list(range(1, 40)) and sorted(nbr[1, :deg[1]]) == [0, 2]
    R._unlink(nbr, deg, 0, 7)
    assert not R._adjacent(nbr, deg, 0, 7) and R._adjacent(nbr, deg, 0, 39)


@pytest.mark.parametrize("criterion", ["angles", "sphere"])
def test_refinement_with_the_compiled_rounds_is_the_refinement_with_the_hook(criterion):
    from meshlab_holefill.core import examples
    from meshlab_holefill.core.holes import hole_context
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation
    from meshlab_holefill.geometry.refine import refine_patch

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=2)
    F0 = min_angle_triangulation(ctx.points, ctx.loop_normals, ctx.forbidden_edges)
    k = ctx.size
    fixed = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    sectors = LoopSectors(ctx.points, ctx.loop_normals)
    want = refine_patch(ctx.points, F0, ctx.edge_scale, fixed_edges=fixed, allowed=_sector_hook(sectors),
                        criterion=criterion)
    got = refine_patch(ctx.points, F0, ctx.edge_scale, fixed_edges=fixed, criterion=criterion,
                       relax=lambda V, F: relax_in_sectors(sectors, V, F, fixed, criterion)[:2])
    assert want[3]["swaps"] > 0 and got[3] == want[3]
    for a, b in zip(got[:3], want[:3]):
        np.testing.assert_array_equal(a, b)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_fixed_keys_are_the_sorted_distinct_undirected_edge_keys(seed):
    from meshlab_holefill.geometry.sets import unique_ints
    from meshlab_holefill.geometry.topology import undirected_keys

    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    E = rng.integers(0, n, (int(rng.integers(0, 30)), 2))
    E = np.concatenate([E, E[:, ::-1][: len(E) // 2]])  # each edge also the other way round
    got = fixed_keys(np.ascontiguousarray(E), n)
    np.testing.assert_array_equal(got, unique_ints(undirected_keys(E, n)))
    assert got.dtype == np.int64
