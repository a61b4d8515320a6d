"""The curve-unfolding filter's work kept for one hole: each piece made once, the same numbers each time."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.brunton2009 import crossing_repair, embedding
from meshlab_holefill.algorithms.brunton2009 import tangential_relaxation as relaxation
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009.planar_domains import PlanarDomains
from meshlab_holefill.algorithms.brunton2009.recent_solves import RecentSolves
from meshlab_holefill.algorithms.brunton2009.unfolding import unfold_loop
from meshlab_holefill.core.holes import hole_context
from meshlab_holefill.geometry.development import boundary_gap_angles


@pytest.fixture(scope="module")
def folded_border(bunny_loops):
    """bunny10k_textured's 22-edge hole: a border face folds over it, so the unfolding's patch crosses the mesh."""
    V, F, loops = bunny_loops
    ctx = hole_context(V, F, loops[1], rings=cu.RINGS)
    first, _ = unfold_loop(ctx.points, np.random.default_rng(0))
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)
    domains = PlanarDomains(ctx.points, gaps, 1e-5, True, 6.0).all(first, "annealing")
    return ctx, domains


def _embeds(monkeypatch):
    calls = []
    embed = crossing_repair.triangulate_and_embed
    monkeypatch.setattr(crossing_repair, "triangulate_and_embed", lambda *a, **kw: calls.append(1) or embed(*a, **kw))
    return calls


@pytest.mark.parametrize("clean_domains", [True, False])
def test_a_repair_made_before_gives_the_same_patch_and_records_without_embedding_again(folded_border, monkeypatch,
                                                                                       clean_domains):
    ctx, domains = folded_border
    # Without the other domains, the repair clips ears: both pieces of MadePatches are met.
    domains = domains if clean_domains else domains[:2]
    made = crossing_repair.MadePatches("area", True, True, "surrounding")
    start = made.patch(ctx, domains[0][0])
    assert len(start.crossings(ctx)) > 0

    def repaired(made):
        records = []
        out = crossing_repair.repair_crossings(ctx, domains, start.vertices.copy(), start.faces.copy(), "area", True,
                                               True, "surrounding", records, made=made)
        return out, records

    fresh, fresh_records = repaired(None)
    calls = _embeds(monkeypatch)
    first, first_records = repaired(made)
    made_calls = len(calls)
    again, again_records = repaired(made)
    assert len(calls) == made_calls > 0  # the second repair embeds nothing
    for out in (first, again):
        assert out[0] == fresh[0] and out[3:] == fresh[3:]
        assert np.array_equal(out[1], fresh[1]) and np.array_equal(out[2], fresh[2])
    for records in (first_records, again_records):
        assert [r.faces.tobytes() for r in records] == [r.faces.tobytes() for r in fresh_records]
        assert [r.points.tobytes() for r in records] == [r.points.tobytes() for r in fresh_records]
    if not clean_domains:
        assert fresh[3] > 0  # ears were clipped
    # the caller's copies: changing them leaves what is kept
    again[1][:] = 0.0
    assert np.array_equal(repaired(made)[0][1], fresh[1])


def test_the_default_domain_choice_embeds_no_domain_twice(folded_border, monkeypatch):
    ctx, _ = folded_border
    patch = cu.fill(ctx)
    seen = []
    embed = crossing_repair.triangulate_and_embed

    def recorded(ctx, Q, keep, ears, *args, **kwargs):
        seen.append((np.ascontiguousarray(Q).tobytes(), np.asarray(keep).tobytes(), repr(ears), args[:4]))
        return embed(ctx, Q, keep, ears, *args, **kwargs)

    monkeypatch.setattr(crossing_repair, "triangulate_and_embed", recorded)
    monkeypatch.setattr(cu, "triangulate_and_embed", recorded)
    again = cu.fill(ctx)
    assert len(seen) == len(set(seen)) > 1
    assert np.array_equal(again.vertices, patch.vertices) and np.array_equal(again.faces, patch.faces)


def _bowl_joint():
    """The bowl example's hole joined to a three-vertex patch: positions, faces, free mask."""
    from meshlab_holefill.core import examples
    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=cu.RINGS)
    k = ctx.size
    X = np.concatenate([ctx.vertices, np.zeros((3, 3))])
    centre = len(ctx.vertices) + np.arange(3)
    joint = np.concatenate([ctx.faces, np.c_[np.arange(k), (np.arange(k) + 1) % k, centre[np.arange(k) % 3]],
                            [centre]])
    return X, joint, np.arange(len(X)) >= len(ctx.vertices)


def test_a_least_squares_mesh_solved_before_is_the_same_array_and_a_changed_system_is_solved_again():
    X, joint, free = _bowl_joint()
    embedding.AREA_SOLVES.clear()
    solved = embedding.minimise_area_energy(X, joint, free)
    assert len(embedding.AREA_SOLVES) == 1
    kept = embedding.minimise_area_energy(X, joint, free)
    assert np.array_equal(kept, solved) and kept is not solved
    kept[free] = 1.0  # the caller's copy
    assert np.array_equal(embedding.minimise_area_energy(X, joint, free), solved)
    moved = X.copy()
    moved[0] += 0.1  # a loop vertex moved: another system
    assert not np.array_equal(embedding.minimise_area_energy(moved, joint, free), solved)
    assert len(embedding.AREA_SOLVES) == 2


def test_a_tangential_relaxation_made_before_is_the_same_array():
    X, joint, free = _bowl_joint()
    X = embedding.minimise_area_energy(X, joint, free)
    index = np.flatnonzero(free)
    relaxation.TANGENTIAL_STEPS.clear()
    fresh = relaxation._relaxed(X.copy(), joint, index)
    first = relaxation.tangential_relaxation(X, joint, index)
    again = relaxation.tangential_relaxation(X, joint, index)
    assert np.array_equal(first, fresh) and np.array_equal(again, fresh) and len(relaxation.TANGENTIAL_STEPS) == 1
    assert not np.array_equal(fresh[free], X[free])  # it moved them
    assert np.array_equal(again[~free], X[~free])


def test_recent_solves_keep_copies_of_the_latest_results_within_their_bytes():
    recent = RecentSolves(3 * 80)
    keys = [recent.key(np.arange(i), np.float64(i)) for i in range(5)]
    assert len(set(keys)) == 5 and recent.key(np.arange(3), np.float64(3)) == keys[3]
    assert recent.key(np.arange(3, dtype=np.int32)) != recent.key(np.arange(3, dtype=np.int64))
    for i, key in enumerate(keys[:3]):
        recent.put(key, np.full(10, float(i)))
    assert len(recent) == 3 and recent.nbytes == 240
    got = recent.get(keys[0])  # now the most recent
    got[:] = -1.0
    assert np.array_equal(recent.get(keys[0]), np.zeros(10))
    recent.put(keys[3], np.full(10, 3.0))  # the least recently used goes: keys[1]
    assert recent.get(keys[1]) is None and recent.get(keys[0]) is not None and len(recent) == 3
    recent.put(keys[4], np.zeros(40))  # larger than all: everything else goes, and it too
    assert len(recent) == 0 and recent.get(keys[4]) is None


def test_recent_solves_count_a_result_put_again_once():
    recent = RecentSolves(1000)
    key = recent.key(np.arange(3))
    recent.put(key, np.zeros(10))
    recent.put(key, np.ones(20))
    assert len(recent) == 1 and recent.nbytes == 160 and np.array_equal(recent.get(key), np.ones(20))
    recent.clear()
    assert len(recent) == 0 and recent.nbytes == 0


def test_each_run_starts_without_the_systems_an_earlier_run_solved(monkeypatch):
    # The kept solves serve one run's fills (a hole filled again clear of faces beyond its rings); a run
    # repeated on the same mesh does all of its work again, as the benchmark's repeated runs measure it.
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core import examples
    V, F, _ = examples.bowl_with_hole()
    fill_holes(V, F, "curve_unfolding", workers=1)
    assert len(embedding.AREA_SOLVES) and len(relaxation.TANGENTIAL_STEPS)
    kept = []  # per system the second run asks for: whether it was found
    get = embedding.AREA_SOLVES.get
    monkeypatch.setattr(embedding.AREA_SOLVES, "get", lambda key: kept.append(get(key) is not None) or get(key))
    again = fill_holes(V, F, "curve_unfolding", workers=1)
    assert kept and not kept[0]  # its first system was solved again
    assert again[2]["closed_holes"] == 1
