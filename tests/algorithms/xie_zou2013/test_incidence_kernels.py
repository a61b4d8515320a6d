"""The compiled incidence sets yield their faces in the order of Python's sets under the same edits."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xie_zou2013 import _incidence_kernels as K


def items(tab, pool, v):
    out = np.empty(tab[v, 3], np.int64)
    return out[:K.set_items(pool, tab, v, out)].tolist()


def run(ops, n_sets, seed_lists):
    """Apply ops to Python sets and to the compiled ones; the orders after each op must agree."""
    faces = np.concatenate([np.asarray(s, np.int64) for s in seed_lists] + [np.zeros(0, np.int64)])
    start = np.r_[0, np.cumsum([len(s) for s in seed_lists])].astype(np.int64)
    sets = [set(s) for s in seed_lists]
    tab, pool, sizes = K.new_incidence(faces, start, n_sets, n_sets)
    pool = pool[:8]  # force growth of the pool on the first new table
    for v in range(n_sets):
        assert items(tab, pool, v) == list(sets[v])
    for op, v, key in ops:
        if op == "add":
            sets[v].add(key)
            pool = K.set_add(pool, tab, sizes, v, key)
        elif op == "discard":
            sets[v].discard(key)
            K.set_discard(pool, tab, v, key)
        elif op == "clear":
            sets[v] = set()
            pool = K.empty_set(pool, tab, sizes, v)
        else:  # copy all: the quality pass's snapshot
            sets = [set(s) for s in sets]
            tab, pool, sizes = K.copied_sets(tab, pool, sizes)
        assert items(tab, pool, v) == list(sets[v]), (op, v, key)
        assert K.set_contains(pool, tab, v, key) == (key in sets[v])
    for v in range(n_sets):
        assert items(tab, pool, v) == list(sets[v])
        assert tab[v, 3] == len(sets[v])


def random_ops(rng, n_sets, hi, count):
    ops = []
    members = [set() for _ in range(n_sets)]
    for _ in range(count):
        v = int(rng.integers(n_sets))
        r = rng.random()
        if r < 0.5:
            key = int(rng.integers(hi))
            ops.append(("add", v, key))
            members[v].add(key)
        elif r < 0.92:
            # Mostly faces that are there (a dummy is left), sometimes absent ones (nothing happens).
            pool = sorted(members[v])
            key = int(rng.choice(pool)) if pool and rng.random() < 0.85 else int(rng.integers(hi))
            ops.append(("discard", v, key))
            members[v].discard(key)
        elif r < 0.96:
            ops.append(("clear", v, 0))
            members[v] = set()
        else:
            ops.append(("copy", v, 0))
    return ops


@pytest.mark.parametrize("hi", [8, 20, 64, 300, 5000, 1 << 40])
def test_orders_follow_python_sets_under_random_edits(hi):
    rng = np.random.default_rng(hi % 1000)
    for trial in range(30):
        n_sets = int(rng.integers(1, 6))
        seeds = [sorted(rng.integers(0, hi, rng.integers(0, 14)).tolist()) for _ in range(n_sets)]
        run(random_ops(rng, n_sets, hi, 300), n_sets, seeds)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(["add", "add", "discard", "clear", "copy"]), st.integers(0, 2),
                          st.integers(0, 200)), max_size=200),
       st.lists(st.lists(st.integers(0, 200), max_size=12), min_size=3, max_size=3))
def test_orders_follow_python_sets_hypothesis(ops, seeds):
    run(ops, 3, seeds)


def test_a_set_of_many_faces_resizes_as_python_does():
    # A loop vertex of a fan holds hundreds of faces: tables of 32 .. 2048 slots, with dummies.
    rng = np.random.default_rng(5)
    ops = [("add", 0, int(x)) for x in rng.permutation(600)]
    ops += [("discard", 0, int(x)) for x in rng.permutation(600)[:450]]
    ops += [("add", 0, int(x)) for x in rng.integers(0, 2000, 300)] + [("copy", 0, 0)]
    run(ops, 1, [[]])
