"""Differential evolution DE/rand/1/bin (Storn and Price 1997), vectorised and batched.

The algorithm is Algorithm 1 of Xie and Zou (2013, Sec. 3), step by step: mutation
V_i = X_r1 + F (X_r2 - X_r3) (Eq. 2) with r1, r2, r3 mutually different, binomial crossover
(Eq. 3, at least the component rn_i from V_i), greedy selection U_i vs X_i (Eq. 4), then the
new generation is constrained to the bounds by reflection (Eq. 5) and the objective values of
the reflected individuals are renewed (step 9).

Vectorisation: one generation updates all N individuals at once (the for-loop of Algorithm 1
is a sweep whose individuals do not see each other's updates, as in the classical synchronous
DE). Several independent problems of different dimension and population size can be solved
in one call ("batch"): arrays carry a leading batch axis, problem b uses its first
``pop_size[b]`` individuals and first ``dims[b]`` components; the unused components must have
lower == upper (they stay fixed).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._de_kernels import (mutate_crossover, reflect_moved, renew_variation, select, select_reflect_terms,
                          trial_changed_terms_into, turning_terms)

__all__ = ["reflect_into_bounds", "de_rand_1_bin"]

# The uniform draws of several generations are taken in one block of at most this many numbers.
BLOCK_DOUBLES = 1 << 20


def reflect_into_bounds(X, lower, upper):
    """Constrain variables to [l, u] by reflection at the violated bound (Eq. 5).

    X_ij -> min(2 l_j - X_ij, u_j) if X_ij < l_j;  max(2 u_j - X_ij, l_j) if X_ij > u_j.

    Parameters
    ----------
    X : (..., N, n) float64
    lower, upper : (..., n) float64, broadcast against X without its population axis.

    Returns
    -------
    (..., N, n) float64
    """
    lo = lower[..., None, :]
    hi = upper[..., None, :]
    out = np.where(X < lo, np.minimum(2.0 * lo - X, hi), X)
    return np.where(out > hi, np.maximum(2.0 * hi - out, lo), out)


def _distinct_triples(rng, pop_size, shape):
    """Indices r1, r2, r3, mutually different, each uniform in [0, pop_size[b]).

    Algorithm 1, step 4 asks only that r1, r2, r3 differ from each other (not from i), so a
    population of 3 suffices (Xie and Zou use N = 3 m, so N = 3 when m = 1).

    Parameters
    ----------
    pop_size : (B,) int >= 3
    shape : (B, N)

    Returns
    -------
    r1, r2, r3 : (B, N) int64
    """
    N = pop_size[:, None].astype(np.float64)
    u = rng.random((3,) + shape)
    r1 = np.floor(u[0] * N).astype(np.int64)
    r2 = np.floor(u[1] * (N - 1)).astype(np.int64)
    r2 += r2 >= r1
    lo, hi = np.minimum(r1, r2), np.maximum(r1, r2)
    r3 = np.floor(u[2] * (N - 2)).astype(np.int64)
    r3 += r3 >= lo
    r3 += r3 >= hi
    return r1, r2, r3


@dataclass
class _Population:
    """The state of one batched DE run: the individuals, their objective values and the problem sizes."""

    X: np.ndarray  # (B, N, n) individuals
    fX: np.ndarray  # (B, N) objective values, inf on padding rows
    active: np.ndarray  # (B, N) bool: row i < pop_size[b]
    pop: np.ndarray  # (B,) population sizes
    dims: np.ndarray  # (B,) used components
    lower: np.ndarray  # (B, n) contiguous bounds
    upper: np.ndarray
    angles: np.ndarray = None  # (B, N, n + 2) masked turning angles of X (fused turning-angle runs)
    trial: "_TrialArrays" = None  # the fused generations' working arrays


@dataclass
class _TrialArrays:
    """What a fused generation writes and then reads once, kept for the next: the trials, their changed terms, angles."""

    U: np.ndarray  # (B, N, n) trial vectors (the padding rows, which no generation writes, their parents')
    changed: np.ndarray  # (B N (n + 2),) flat indices of the terms a crossover changed (the first c)
    cross: np.ndarray  # (B N (n + 2),) their arctan2 arguments
    dot: np.ndarray
    angles: np.ndarray  # (B, N, n + 2) the trials' masked angles

    @classmethod
    def like(cls, X, angles):
        size = angles.size
        return cls(X.copy(), np.empty(size, np.int64), np.empty(size), np.empty(size), np.empty_like(angles))


def _problem_sizes(lower, upper, pop_size, dims, bounds):
    """Validated bounds (B, n), population sizes (B,) and used components (B,) of a batch."""
    if bounds not in ("paper", "trial"):
        raise ValueError(f"unknown bounds handling {bounds!r}")
    lower = np.atleast_2d(np.asarray(lower, np.float64))
    upper = np.atleast_2d(np.asarray(upper, np.float64))
    B, n = lower.shape
    if np.any(upper < lower):
        raise ValueError("upper bound below lower bound")
    if pop_size is None:
        pop_size = 10 * n
    pop = np.broadcast_to(np.asarray(pop_size, np.int64), (B,)).copy()
    if np.any(pop < 3):
        raise ValueError("DE/rand/1 needs a population of at least 3")
    dims = np.full(B, n, np.int64) if dims is None else np.asarray(dims, np.int64)
    return lower, upper, pop, dims


def _initial_population(objective, lower, upper, pop, dims, rng, init):
    """Algorithm 1, line 1: uniform in the box, or ``init`` reflected into it (Eq. 5); evaluated."""
    B, n = lower.shape
    Nmax = int(pop.max())
    active = np.arange(Nmax)[None, :] < pop[:, None]  # (B, N)
    if init is None:
        X = lower[:, None, :] + rng.random((B, Nmax, n)) * (upper - lower)[:, None, :]
    else:
        X = reflect_into_bounds(np.asarray(init, np.float64).reshape(B, Nmax, n), lower, upper)
    fX = np.asarray(objective(X), np.float64)
    fX = np.ascontiguousarray(np.where(active, fX, np.inf))
    return _Population(np.ascontiguousarray(X), fX, active, pop, dims, np.ascontiguousarray(lower),
                       np.ascontiguousarray(upper))


class _Uniforms:
    """The uniform numbers of each generation: 3 B N for r1, r2, r3, B N for rn_i, B N n for Eq. 3.

    ``Generator.random`` fills its output in order, so a block of g generations drawn at once
    holds exactly the numbers g successive per-generation draws would give; the blocks never
    run past ``generations``, and with an early stop (``per_block=False``) every generation draws
    its own, so the generator is left where generation-by-generation draws would leave it.
    """

    def __init__(self, rng, shape, generations, per_block=True):
        B, N, n = shape
        self.rng, self.shape, self.left, self.per_block = rng, shape, generations, per_block
        self.ends = (3 * B * N, 4 * B * N, 4 * B * N + B * N * n)
        self.block, self.row = np.zeros((0, self.ends[2])), 0

    def next(self):
        """(u_index (3, B, N), u_rn (B, N), u_take (B, N, n)) of the next generation."""
        if self.row == len(self.block):
            g = max(1, min(self.left, BLOCK_DOUBLES // max(self.ends[2], 1))) if self.per_block else 1
            self.block, self.row, self.left = self.rng.random((g, self.ends[2])), 0, self.left - g
        row = self.block[self.row]
        self.row += 1
        B, N, n = self.shape
        a, b, _ = self.ends
        return row[:a].reshape(3, B, N), row[a:b].reshape(B, N), row[b:].reshape(B, N, n)


def _trial_population(state, draws, F, CR):
    """Algorithm 1, steps 4-6: distinct r1, r2, r3, the component rn_i, mutation (Eq. 2) and crossover (Eq. 3).

    Compiled (:func:`._de_kernels.mutate_crossover`): the indices of :func:`_distinct_triples`,
    rn_i = floor(u dims) and U = where(u <= CR or j == rn, X[r1] + F (X[r2] - X[r3]), X).
    """
    u_index, u_rn, u_take = draws.next()
    return mutate_crossover(state.X, u_index, u_rn, u_take, state.pop, state.dims, float(F), float(CR))


def _reflect_and_renew(objective, state):
    """Algorithm 1, steps 8-9: reflect the new generation into the bounds (Eq. 5) and renew f of the moved ones."""
    Xr, moved = reflect_moved(state.X, state.lower, state.upper)
    moved &= state.active
    if not moved.any():
        return
    state.X = Xr
    B = len(moved)
    # Only the reflected individuals are evaluated again, gathered per problem.
    count = moved.sum(axis=1)
    K = int(count.max())
    order = np.argsort(~moved, axis=1, kind="stable")[:, :K]
    f_new = np.asarray(objective(Xr[np.arange(B)[:, None], order]), np.float64)
    take_new = np.arange(K)[None, :] < count[:, None]
    problem_of = np.repeat(np.arange(B)[:, None], K, axis=1)
    state.fX[problem_of[take_new], order[take_new]] = f_new[take_new]


def _generation(objective, state, draws, F, CR, bounds):
    """One generation of Algorithm 1 (steps 3-9) for every individual at once."""
    U = _trial_population(state, draws, F, CR)
    if bounds == "trial":
        U = reflect_moved(U, state.lower, state.upper)[0]
    fU = np.ascontiguousarray(objective(U), np.float64)
    select(state.X, state.fX, U, fU, state.active)  # Eq. 4, in place
    if bounds == "paper":
        _reflect_and_renew(objective, state)


def _turning_generation(objective, state, draws, F, CR):
    """One generation of Algorithm 1 (bounds 'paper') for a turning-angle objective, fused.

    The same operations as :func:`_generation` with ``objective(X) = variation(
    *objective.angle_sums(arctan2(cross, dot)))`` split at the numpy steps it keeps (arctan2, sums):
    the trial vectors and their turning terms in one kernel, the selection (Eq. 4), the
    reflection (Eq. 5) and the terms of the reflected individuals in another. A trial's
    angles are its parent's except next to its crossover components (Eq. 3,
    :func:`._de_kernels.trial_changed_terms_into`); only those go through arctan2 (the same numbers,
    so the same angles: numpy's arctan2 was 2.9 of 7.0 s on bunny_212k's large holes, under cProfile).
    """
    seg_x, seg_y_add, count = objective.turning_chain
    u_index, u_rn, u_take = draws.next()
    trial = state.trial
    c = trial_changed_terms_into(state.X, u_index, u_rn, u_take, state.pop, state.dims, float(F), float(CR), seg_x,
                                 seg_y_add, trial.U, trial.changed, trial.cross, trial.dot)
    beta = np.arctan2(trial.cross[:c], trial.dot[:c])
    square_sum, total = objective.changed_angle_sums(state.angles, trial.changed[:c], beta, trial.angles)
    order, counts, cross, dot = select_reflect_terms(state.X, state.fX, trial.U, square_sum, total, count, state.active,
                                                     state.angles, trial.angles, state.lower, state.upper, seg_x,
                                                     seg_y_add)
    if order.shape[1] == 0:
        return
    reflected = np.arctan2(cross, dot)
    square_sum, total = objective.angle_sums(reflected)
    renew_variation(state.fX, order, counts, square_sum, total, count, state.angles, reflected)


def _population_spread_within(state, tol):
    """True when every problem's max f - min f is <= tol (the optional early stop)."""
    f_act = np.where(state.active, state.fX, np.nan)
    return bool(np.all(np.nanmax(f_act, axis=1) - np.nanmin(f_act, axis=1) <= tol))


def de_rand_1_bin(objective, lower, upper, pop_size=None, dims=None, F=0.8, CR=0.05, generations=100,
                  seed=0, init=None, tol=0.0, bounds="paper"):
    """Minimise a batch of box-constrained problems by DE/rand/1/bin (Algorithm 1).

    Parameters
    ----------
    objective : callable
        ``objective(X) -> f`` with X : (B, N, n) float64 and f : (B, N) float64; evaluated
        once per generation on all trial individuals (vectorised over population and batch).
        An objective of the turning-angle form of Eq. 14 may say so with the attribute
        ``turning_chain`` = (seg_x, seg_y_add, count) of :func:`._de_kernels.turning_terms`
        and the methods ``angle_sums(beta) -> (sum of squared angles, sum of angles)`` of the
        angles beta = arctan2(cross, dot), masked by it in place, and
        ``changed_angle_sums(parent, changed, beta, out)``, the same of the angles ``parent``
        with ``out.flat[changed] = beta`` written into ``out`` (as
        :class:`.prediction.AngleVariation`); with ``bounds='paper'`` its generations
        then run fused (the same arithmetic, fewer calls).
    lower, upper : (B, n) or (n,) float64
        Bounds l_j <= x_j <= u_j. A 1-D input is one problem (B = 1) and the result is 1-D.
    pop_size : int or (B,) int, optional
        N per problem, >= 3 (default 10 n). Rows beyond pop_size[b] are padding.
    dims : (B,) int, optional
        Number of used components per problem (default n): the random crossover component
        rn_i is drawn among them. Unused components need lower == upper.
    F : float
        Mutation factor in [0, 1] (Eq. 2).
    CR : float
        Crossover probability (Eq. 3).
    generations : int
        Maximum number of generations (the stopping condition of Algorithm 1, line 2).
    seed : int or numpy.random.Generator
    init : (B, N, n) float64, optional
        Initial population (reflected into the bounds); default uniform in the box
        (Algorithm 1, line 1).
    tol : float
        Optional early stop when, for every problem, the spread max f - min f of its population
        is <= tol (0 disables it).
    bounds : {'paper', 'trial'}
        'paper' follows Algorithm 1 literally: select on f of the raw trial (Eq. 4), reflect the
        new generation (Eq. 5) and renew f of the reflected individuals (step 9, a second
        evaluation). 'trial' reflects each trial before it is evaluated (the usual DE practice;
        one evaluation per generation, selection stays greedy).

    Returns
    -------
    best : (B, n) float64 (or (n,) for a 1-D problem)
        Best individual of the last generation (always inside the bounds).
    best_f : (B,) float64 (or float)
    generations_run : int
    """
    single = np.ndim(lower) == 1
    lower, upper, pop, dims = _problem_sizes(lower, upper, pop_size, dims, bounds)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    state = _initial_population(objective, lower, upper, pop, dims, rng, init)
    draws = _Uniforms(rng, state.X.shape, generations, per_block=tol <= 0)
    g = 0
    fused = bounds == "paper" and getattr(objective, "turning_chain", None) is not None
    if fused:
        state.angles = np.arctan2(*turning_terms(state.X, *objective.turning_chain[:2]))
        objective.angle_sums(state.angles)  # masked, as the generations keep them
        state.trial = _TrialArrays.like(state.X, state.angles)
    for g in range(1, generations + 1):
        if fused:
            _turning_generation(objective, state, draws, F, CR)
        else:
            _generation(objective, state, draws, F, CR, bounds)
        if tol > 0 and _population_spread_within(state, tol):
            break
    B = len(pop)
    best_idx = np.argmin(np.where(state.active, state.fX, np.inf), axis=1)
    best = state.X[np.arange(B), best_idx]
    best_f = state.fX[np.arange(B), best_idx]
    if single:
        return best[0], float(best_f[0]), g
    return best, best_f, g
