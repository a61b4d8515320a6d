"""HPDE final quality pass (beyond the paper): guarded local operations on the worst triangles.

Sec. 4.7 of Xie and Zou (2013) ends the patch with decimation of short edges (midpoint
collapse) and edge swaps raising the minimum angle. On holes whose loop edges are much
longer than the ring's mean edge (range-scan borders, ~2-4 EdgeLen) those steps, and the
obtuse-edge splits of option ``relax``, leave slivers: a free vertex close to a long loop
edge, its angle opposite that edge near 150 degrees (2r/R ~ 0.1-0.2). :func:`raise_min_quality`
works on the triangles below a quality floor, worst first, with the paper's two operations
and two more, the first that helps being kept:

* swap of an edge of the poor triangle (the Sec. 4.7 swap, scored by the smaller 2r/R);
* move of a free vertex of the poor triangle in its tangent plane (compass search), first to
  lower the star's sum of 1 / q (which spares its good triangles), then, if the triangle is
  still below the floor, to raise the star's minimum up to the floor;
* collapse of an edge of the poor triangle with a free end (the Sec. 4.7 decimation: onto the
  loop vertex if one end is on the loop, else the kept vertex at its best position);
* optionally (the loop-only last resort, which has no free vertex) a split of its longest
  interior edge at a new vertex placed at its best.

Every operation must raise the smallest quality of the triangles it changes. Guards: each
changed triangle keeps its normal within 60 degrees of the old one (of the old pair's mean
for a swap) and of the moved vertex's normal, a triangle on a loop edge stays within 150
degrees of the mesh face across it, no edge is duplicated or forbidden (nor a ``blocked``
loop triangle created), a collapse passes the link condition, and an operation that adds a
fold-over (``fold_test``) is undone: a round that adds one is run again, each operation kept
only if the fold count stays. The caller undoes the pass if the patch then crosses
the surrounding rings.

The operations run compiled (:mod:`._quality_pass_ops`, on flat arrays, the faces at each
vertex kept in the order of the Python sets of the numpy pass, :mod:`._incidence_kernels`);
:func:`raise_min_quality_numpy` runs the numpy pass (:mod:`._quality_pass_numpy`), the
tests' reference: both give the same bits.
"""
from __future__ import annotations

import numpy as np

from ...geometry.quality import triangle_quality
from ...geometry.topology import vertex_face_runs
from . import _quality_pass_ops as ops
from ._incidence_kernels import copied_sets, new_incidence
from ._patch_kernels import EDGE_BASE, TRIPLE_BASE, context
from ._quality_pass_numpy import BORDER_COS, GAIN, TURN_COS, _Patch
from .optimisation import compact_vertices

__all__ = ["raise_min_quality", "raise_min_quality_numpy"]

# The compass's 8 directions, numpy's cosines and sines (as the numpy pass computes them).
_ANGLES = np.arange(8) * (np.pi / 4)
_COS, _SIN = np.cos(_ANGLES), np.sin(_ANGLES)
_KINDS = ("swaps", "moves", "collapses", "splits")


def raise_min_quality(V, F, k, forbidden_edges=(), border_normals=None, floor=0.4, rounds=6, fold_test=None,
                      blocked=frozenset(), split=False):
    """Raise the smallest 2r/R of the patch by guarded swaps, vertex moves and collapses (beyond the paper).

    Each triangle below ``floor`` (worst first) is worked on by: swaps of its three edges,
    moves of its free vertices, collapses of its edges with a free end, the first operation
    that raises the smallest quality of the triangles it changes being kept (see the module
    docstring for the guards). Rounds repeat while anything changes; a round after which
    ``fold_test(V, F)`` (optional, returns a count of folded faces) reports more folds than
    before is run again from its start, each operation kept only if the count stays (before, the
    round was undone and the pass ended: on airplane.obj's 69-edge hole cut with ``--seed 1``
    one fold-over cost the swaps that lift two ears of consecutive loop vertices from 2r/R
    0.002 and 0.007).

    Parameters
    ----------
    V : (n, 3) float64  loop vertices first (the first k never move)
    F : (m, 3) int64  consistently oriented
    k : int
    forbidden_edges : (p, 2) int  loop vertex pairs that must not be joined
    border_normals : (k, 3) float64, optional  mesh normal across each loop edge (0 rows: none)
    floor : float
    rounds : int
    fold_test : callable, optional  ``fold_test(V, F) -> int`` folded faces (a round raising it is undone)
    blocked : set of sorted loop-vertex triples that a swap must not create (they cross the surroundings)
    split : bool  also split the longest (interior) edge of a poor triangle when nothing else helps

    Returns
    -------
    V : (n', 3) float64  compacted (loop vertices first, unchanged)
    F : (m', 3) int64
    keep : (n',) int64  input index of each remaining vertex (-1: a vertex made by a split)
    stats : dict  ``swaps``, ``moves``, ``collapses``, ``splits``
    """
    return _run(V, F, k, forbidden_edges, border_normals, floor, rounds, fold_test, blocked, split, True)


def raise_min_quality_numpy(V, F, k, forbidden_edges=(), border_normals=None, floor=0.4, rounds=6, fold_test=None,
                            blocked=frozenset(), split=False):
    """:func:`raise_min_quality` in numpy and Python sets (the tests' reference; the same results)."""
    return _run(V, F, k, forbidden_edges, border_normals, floor, rounds, fold_test, blocked, split, False)


def _run(V, F, k, forbidden_edges, border_normals, floor, rounds, fold_test, blocked, split, compiled):
    """:func:`raise_min_quality` on compiled patches (``compiled``, where they take the inputs) or numpy ones."""
    V = np.array(V, np.float64)
    F = np.array(F, np.int64)
    stats = dict.fromkeys(_KINDS, 0)
    keep = np.arange(len(V))
    if len(F) == 0 or floor <= 0:
        return V, F, keep, stats
    new_patch = _compiled_patches(k, forbidden_edges, border_normals, floor, blocked) if compiled else None
    if new_patch is None:
        def new_patch(V_, F_, capacity):
            return _Patch(V_, F_, k, forbidden_edges, border_normals, floor, blocked)
    return _rounds(V, F, k, floor, rounds, fold_test, split, stats, keep, new_patch)


def _rounds(V, F, k, floor, rounds, fold_test, split, stats, keep, new_patch):
    """The rounds of :func:`raise_min_quality` on patches made by ``new_patch(V, F, capacity)``."""
    folds_before = fold_test(V, F) if fold_test is not None else 0
    for _ in range(rounds):
        q = triangle_quality(V, F)
        poor = np.flatnonzero(q < floor)
        if len(poor) == 0:
            break
        order = poor[np.argsort(q[poor], kind="stable")].tolist()
        p = new_patch(V, F, len(order))
        done = p.improve_round(order, split)
        if not any(done.values()):
            break
        V2, F2, kept = p.compact()
        if fold_test is not None and fold_test(V2, F2) > folds_before:
            # One operation of the round folded the patch: the round again, each operation kept
            # only if it adds no fold (one fold-over used to cost the round's other repairs).
            p = new_patch(V, F, len(order))
            done = p.improve_round(order, split, lambda: fold_test(*p.compact()[:2]) <= folds_before)
            V2, F2, kept = p.compact()
        if not any(done.values()):
            break
        V, F, keep = V2, F2, np.r_[keep, np.full(len(p.V) - len(keep), -1, np.int64)][kept]
        for key in stats:
            stats[key] += done[key]
    return V, F, keep, stats


def _compiled_patches(k, forbidden_edges, border_normals, floor, blocked):
    """``new_patch(V, F, capacity)`` of the compiled rounds; None for inputs they do not take (the numpy
    pass then runs, and raises what it raises): edge or triple indices beyond the keys' range, or
    fewer mesh normals than loop edges."""
    E = np.sort(np.asarray(forbidden_edges, np.int64).reshape(-1, 2), axis=1)
    # Only sorted triples can match the pass's sorted queries.
    B = np.array([t for t in blocked if list(t) == sorted(t)], np.int64).reshape(-1, 3)
    border = None if border_normals is None else np.asarray(border_normals, np.float64)
    if (len(E) and (E.min() < 0 or E.max() >= EDGE_BASE)) or (len(B) and (B.min() < 0 or B.max() >= TRIPLE_BASE)) \
            or (border is not None and (border.ndim != 2 or border.shape[1] != 3 or len(border) < k)):
        return None
    forbidden = np.unique(E[:, 0] * EDGE_BASE + E[:, 1])
    blocked_keys = np.unique((B[:, 0] * TRIPLE_BASE + B[:, 1]) * TRIPLE_BASE + B[:, 2])
    ctx = context(k, floor, GAIN, TURN_COS, BORDER_COS, border, forbidden, blocked_keys, _COS, _SIN)
    return lambda V, F, capacity: _CompiledPatch(V, F, k, ctx, capacity)


class _CompiledPatch:
    """The patch of the compiled rounds: flat arrays with room for ``capacity`` splits.

    ``V``, :meth:`improve_round` and :meth:`compact` are those of the numpy pass's ``_Patch``.
    """

    def __init__(self, V, F, k, ctx, capacity):
        n, m = len(V), len(F)
        self.k, self.ctx = k, ctx
        self._V = np.zeros((n + capacity, 3))
        self._V[:n] = V
        self._F = np.zeros((m + 2 * capacity, 3), np.int64)
        self._F[:m] = F
        self._alive = np.zeros(m + 2 * capacity, bool)
        self._alive[:m] = True
        faces, start = vertex_face_runs(F, n)
        self.tab, self.pool, self.sizes = new_incidence(faces, start, n, n + capacity)
        self.sizes[1] = m

    @property
    def V(self):
        return self._V[: self.sizes[0]]

    def improve_round(self, order, split, keeps=None):
        """One round over the poor faces ``order``; counts of the operations kept (see ``_improve_round``)."""
        order = np.asarray(order, np.int64)
        arrays = (self._V, self._F, self._alive, self.tab)
        if keeps is None:
            self.pool, counts = ops.improve_round(*arrays, self.pool, self.sizes, order, bool(split), self.ctx)
            return dict(zip(_KINDS, counts.tolist()))
        done = dict.fromkeys(_KINDS, 0)
        for f in order.tolist():
            if not self._alive[f]:
                continue
            state = [a.copy() for a in arrays] + [self.pool[: self.sizes[2]].copy(), self.sizes.copy()]
            self.pool, kind = ops.improve_face(*arrays, self.pool, self.sizes, f, bool(split), self.ctx)
            if kind == ops.NOTHING:
                continue
            if not keeps():
                # The numpy pass restores copies of its sets, set(s), which may lay them out anew.
                self._V, self._F, self._alive = state[:3]
                self.tab, self.pool, self.sizes = copied_sets(*state[3:])
                arrays = (self._V, self._F, self._alive, self.tab)
                continue
            done[_KINDS[kind]] += 1
        return done

    def compact(self):
        n, m = self.sizes[0], self.sizes[1]
        used = np.zeros(n, bool)
        used[: self.k] = True
        F = self._F[:m][self._alive[:m]]
        used[F.ravel()] = True
        return compact_vertices(self._V[:n], F, used)
