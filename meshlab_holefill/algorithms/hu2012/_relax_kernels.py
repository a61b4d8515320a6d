"""Compiled relaxation rounds with the hole-sector veto (numba): :func:`.hole_guards.relax_in_sectors`.

A refinement runs a few hundred relaxations of a few rounds each; in Python every round cost
some 25 us of calls around the kernels of :mod:`geometry._flip_kernels`, and each round
rebuilt the half-edge table and tested every interior edge again, though a round swaps few
of them. :func:`relax_rounds` runs the rounds in one call and keeps, between rounds, the
half-edge twins, the vertex adjacency and the swap test of every edge whose two faces did
not change (the test depends on those faces alone). The decisions are those of
``relax_edges(V, F, fixed, allowed=<sector test>)`` round by round: the same tests
(:func:`._flip_kernels._swap_tests`, :func:`._sector_kernels.new_edge_in_sectors`), the same
priority (half-edge order) and choice (:func:`._flip_kernels.choose_swaps`). Where one of
them cannot decide (an angle too close to its bound) the kernel stops before that round and
the caller runs it in Python.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ...geometry._flip_kernels import (_contains, _interior_edges, _keeps_orientation, _swap_tests, choose_swaps,
                                       swap_faces)
from ._sector_kernels import new_edge_in_sectors

__all__ = ["relax_rounds", "STOPPED", "UNDECIDED", "REFUSED", "SETTLED"]

STOPPED, UNDECIDED, REFUSED, SETTLED = 0, 1, 2, 3


@njit(cache=True)
def _adjacency(F, n, twin):
    """Neighbour lists (n, cap) and degrees (n,) of the undirected edges of F (cap with room for swaps)."""
    deg = np.zeros(n, np.int64)
    for h in range(3 * F.shape[0]):
        a, b = F[h // 3, h % 3], F[h // 3, (h % 3 + 1) % 3]
        if twin[h] < 0 or a < b:
            deg[a] += 1
            deg[b] += 1
    nbr = np.empty((n, deg.max() + 8 if n else 0), np.int64)
    deg[:] = 0
    for h in range(3 * F.shape[0]):
        a, b = F[h // 3, h % 3], F[h // 3, (h % 3 + 1) % 3]
        if twin[h] < 0 or a < b:
            nbr[a, deg[a]] = b
            nbr[b, deg[b]] = a
            deg[a] += 1
            deg[b] += 1
    return nbr, deg


@njit(cache=True)
def _adjacent(nbr, deg, a, b):
    for r in range(deg[a]):
        if nbr[a, r] == b:
            return True
    return False


@njit(cache=True)
def _unlink(nbr, deg, a, b):
    for r in range(deg[a]):
        if nbr[a, r] == b:
            deg[a] -= 1
            nbr[a, r] = nbr[a, deg[a]]
            return


@njit(cache=True)
def _link(nbr, deg, a, b):
    """Add b to a's neighbours; returns the lists, reallocated when a's row is full."""
    if deg[a] == nbr.shape[1]:
        wider = np.empty((nbr.shape[0], 2 * nbr.shape[1]), np.int64)
        for v in range(nbr.shape[0]):
            for r in range(deg[v]):
                wider[v, r] = nbr[v, r]
        nbr = wider
    nbr[a, deg[a]] = b
    deg[a] += 1
    return nbr


@njit(cache=True)
def _corners(F, twin, h):
    """(a, b, c, d, f1, f2) of the interior edge of half-edge h = a -> b in f1, its twin in f2."""
    f1, c1, f2, c2 = h // 3, h % 3, twin[h] // 3, twin[h] % 3
    return F[f1, c1], F[f1, (c1 + 1) % 3], F[f1, (c1 + 2) % 3], F[f2, (c2 + 2) % 3], f1, f2


@njit(cache=True)
def _swap(F, twin, known, nbr, deg, h):
    """Swap the edge of half-edge h, keeping twins, adjacency and the known tests in step."""
    a, b, c, d, f1, f2 = _corners(F, twin, h)
    c1, c2 = h % 3, twin[h] % 3
    # The outer twins of the four kept sides, read before f1, f2 are rewritten: a -> d (was in f2),
    # d -> c (new), c -> a (was in f1) then b -> c (was in f1), c -> d (new), d -> b (was in f2).
    outer = (twin[3 * f2 + (c2 + 1) % 3], -1, twin[3 * f1 + (c1 + 2) % 3],
             twin[3 * f1 + (c1 + 1) % 3], -1, twin[3 * f2 + (c2 + 2) % 3])
    swap_faces(F, a, b, c, d, f1, f2)
    for j in range(6):
        x = 3 * (f1 if j < 3 else f2) + j % 3
        t = outer[j] if j % 3 != 1 else (3 * f2 + 1 if j < 3 else 3 * f1 + 1)
        twin[x] = t
        known[x] = False
        if t >= 0:
            twin[t] = x
            known[t] = False
    _unlink(nbr, deg, a, b)
    _unlink(nbr, deg, b, a)
    nbr = _link(nbr, deg, c, d)
    return _link(nbr, deg, d, c)


@njit(cache=True)
def _make_swaps(F, twin, known, nbr, deg, cand, n):
    """The swaps of one round among the allowed candidate half-edges (ascending): (count, adjacency)."""
    s = cand.shape[0]
    f1f2 = np.empty((s, 2), np.int64)
    new_key = np.empty(s, np.int64)
    for r in range(s):
        _, _, c, d, f1, f2 = _corners(F, twin, cand[r])
        f1f2[r, 0], f1f2[r, 1] = f1, f2
        new_key[r] = min(c, d) * n + max(c, d)
    chosen = choose_swaps(np.arange(s), f1f2, new_key, F.shape[0])
    for x in chosen:
        nbr = _swap(F, twin, known, nbr, deg, cand[x])
    return chosen.shape[0], nbr


@njit(cache=True)
def _has_degenerate_face(F):
    for f in range(F.shape[0]):
        if F[f, 0] == F[f, 1] or F[f, 1] == F[f, 2] or F[f, 2] == F[f, 0]:
            return True
    return False


@njit(cache=True)
def relax_rounds(V, F, fixed, sphere, max_rounds, points, u, w, limit, margin, stop_on_refusal):
    """Rounds of ``relax_edges(V, F, fixed, allowed=<sector test>, criterion)`` (normal_cos 0), F in place.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int64
    fixed : (p,) int64 sorted unique keys min * n + max of the fixed edges
    sphere : bool  the circumsphere test ("sphere") instead of the unfolded angles ("angles")
    max_rounds : int
    points, u, w, limit : the :class:`.hole_guards.LoopSectors` of loop vertices 0 .. k - 1
    margin : float  of the sector test
    stop_on_refusal : bool  stop before a round in which the sector test refuses a swap

    Returns
    -------
    status : STOPPED (as relax_edges stops, or after max_rounds), SETTLED (stopped, and the sector
        test refused no swap of the last round tested: run again on the result, with any veto that
        agrees with it where it allows every candidate, relax_edges makes no swap), UNDECIDED (a
        test of the next round could not be decided here) or REFUSED (the sector test refuses a
        swap of the next round)
    swaps : int  made in the rounds run
    rounds : int  rounds run (each made swaps)
    """
    n, m = V.shape[0], F.shape[0]
    he, tw, _, _, _, fine = _interior_edges(F, n)
    if not fine or _has_degenerate_face(F):  # the twins kept below assume neither
        return UNDECIDED, 0, 0
    twin = np.full(3 * m, -1, np.int64)
    for i in range(he.shape[0]):
        twin[he[i]], twin[tw[i]] = tw[i], he[i]
    nbr, deg = _adjacency(F, n, twin)
    known = np.zeros(3 * m, np.bool_)  # the tests below hold for half-edge h's edge
    fails = np.zeros(3 * m, np.bool_)
    swappable = np.zeros(3 * m, np.bool_)
    cand = np.empty(3 * m, np.int64)
    total = 0
    for rounds in range(max_rounds):
        edges, failing, count = 0, 0, 0
        for h in range(3 * m):
            if twin[h] < 0 or not F[h // 3, h % 3] < F[h // 3, (h % 3 + 1) % 3]:
                continue
            edges += 1
            if not known[h]:
                a, b, c, d, _, _ = _corners(F, twin, h)
                inside, passes = _swap_tests(V, a, b, c, d, sphere)
                if inside < 0 or passes < 0:
                    return UNDECIDED, total, rounds
                fails[h] = inside == 1
                swappable[h] = inside == 1 and passes == 1 and _keeps_orientation(V, a, b, c, d) and c != d
                known[h] = True
            failing += fails[h]
            if swappable[h]:
                cand[count] = h
                count += 1
        if edges == 0 or failing == 0:
            return SETTLED, total, rounds
        kept, refusals = 0, 0
        for r in range(count):
            a, b, c, d, _, _ = _corners(F, twin, cand[r])
            if _adjacent(nbr, deg, c, d) or _contains(fixed, min(a, b) * n + max(a, b)) or \
                    _contains(fixed, min(c, d) * n + max(c, d)):
                continue
            verdict = new_edge_in_sectors(points, u, w, limit, V, c, d, margin)
            if verdict < 0:
                return UNDECIDED, total, rounds
            if verdict == 0:
                if stop_on_refusal:
                    return REFUSED, total, rounds
                refusals += 1
                continue
            cand[kept] = cand[r]
            kept += 1
        if kept == 0:
            return (STOPPED if refusals else SETTLED), total, rounds
        made, nbr = _make_swaps(F, twin, known, nbr, deg, cand[:kept], n)
        total += made
    return STOPPED, total, max_rounds
