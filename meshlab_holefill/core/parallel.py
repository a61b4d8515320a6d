"""Holes filled one per worker process (they are independent), with a time limit per hole.

Each fill sees only its :class:`~meshlab_holefill.core.holes.HoleContext` and is
deterministic (stochastic algorithms take a seed), so the outcome of a hole does not depend
on which process fills it or when: the result is the same whatever the number of workers.
Workers are forked, so they inherit the fill function and the contexts without pickling
them (closures and monkeypatched functions work too); only each outcome travels back. Where
fork is not available, or inside a daemonic process (a Dask or multiprocessing worker,
which may not have children), holes are filled in this process.
"""
from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import signal
import threading
import time
from contextlib import contextmanager

import numpy as np

from ..errors import HoleFillError
from .patch import validate_patch

__all__ = ["FILL_ERRORS", "HoleTimeLimit", "available_workers", "fill_contexts", "limit_workers", "reason_of"]

_WORKER_CAP = None  # set by limit_workers

# What a fill may raise that makes its hole fail rather than the filter: the algorithm's own
# refusal, and the numerical errors of degenerate input.
FILL_ERRORS = (HoleFillError, np.linalg.LinAlgError, ArithmeticError, ValueError, RuntimeError)


class HoleTimeLimit(HoleFillError):
    """A hole took longer than the filter's ``timelimit``."""


def reason_of(exc):
    """The per-hole reason for a fill's exception."""
    return str(exc) if isinstance(exc, HoleFillError) else f"{type(exc).__name__}: {exc}"


def available_workers():
    """Worker processes this process may use: the CPUs it may run on, 1 where it cannot fork children."""
    if "fork" not in multiprocessing.get_all_start_methods() or multiprocessing.current_process().daemon:
        return 1
    try:
        cpus = max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        cpus = max(1, os.cpu_count() or 1)
    return cpus if _WORKER_CAP is None else min(cpus, _WORKER_CAP)


@contextmanager
def limit_workers(count):
    """Fill holes with at most ``count`` processes inside the block (a batch task already runs one file per core)."""
    global _WORKER_CAP
    previous, _WORKER_CAP = _WORKER_CAP, max(1, int(count))
    try:
        yield
    finally:
        _WORKER_CAP = previous


@contextmanager
def _time_limit(seconds):
    """Raise HoleTimeLimit in this thread after ``seconds`` (0: no limit; only in a main thread)."""
    if not seconds or threading.current_thread() is not threading.main_thread():
        yield
        return

    def expire(signum, frame):
        raise HoleTimeLimit(f"took longer than the time limit of {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def _fill_one(fill, ctx, fill_kwargs, timelimit):
    """(validated patch or failure reason, seconds) of one hole."""
    t0 = time.perf_counter()
    try:
        with _time_limit(timelimit):
            patch = fill(ctx, **fill_kwargs)
            validate_patch(patch, ctx.points, ctx.forbidden_edges)
    except FILL_ERRORS as exc:
        return reason_of(exc), time.perf_counter() - t0
    return patch, time.perf_counter() - t0


_JOB = None  # (fill, contexts, fill_kwargs, timelimit, check) of the pool being run, inherited by forked workers


def _fill_in_worker(index):
    fill, contexts, fill_kwargs, timelimit, check = _JOB
    patch, seconds = _fill_one(fill, contexts[index], fill_kwargs, timelimit)
    checked = check(contexts[index], patch) if check is not None and not isinstance(patch, str) else None
    return index, (patch, seconds, checked)


def fill_contexts(fill, contexts, fill_kwargs, workers=1, timelimit=0.0, progress=None, check=None):
    """Fill every context, in worker processes when ``workers`` > 1.

    Parameters
    ----------
    fill : callable ``fill(ctx, **fill_kwargs) -> Patch``
    contexts : list of HoleContext
    fill_kwargs : dict
    workers : int
        Processes at once; 0: :func:`available_workers`; 1: in this process.
    timelimit : float
        Seconds one fill may take; 0: no limit. A fill over it fails with the reason.
    progress : callable, optional
        ``progress(position)`` after each fill, ``position`` into ``contexts``, in the order
        fills finish.
    check : callable, optional
        ``check(ctx, patch) -> small picklable value``, run on each validated patch by the
        worker that filled it, when holes are filled in workers: per-hole work that would
        otherwise wait for every fill in this process (the crossing check against the mesh).

    Returns
    -------
    list of (Patch or str, float, object)
        Per context, in order: the validated patch or the reason it failed, the seconds its
        fill took, and ``check``'s value (None when it was not run: in this process, or
        for a failed fill).
    """
    global _JOB
    workers = min(available_workers() if workers == 0 else workers, available_workers(), len(contexts))
    if workers <= 1:
        outcomes = []
        for position, ctx in enumerate(contexts):
            outcomes.append(_fill_one(fill, ctx, fill_kwargs, timelimit) + (None,))
            if progress:
                progress(position)
        return outcomes
    # Largest holes first: the pool ends when its longest fill does, so start that one early.
    order = sorted(range(len(contexts)), key=lambda j: -len(contexts[j].loop))
    outcomes = [None] * len(contexts)
    _JOB = (fill, contexts, fill_kwargs, timelimit, check)
    try:
        with concurrent.futures.ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork")) as pool:
            futures = [pool.submit(_fill_in_worker, j) for j in order]
            try:
                for future in concurrent.futures.as_completed(futures):
                    index, outcome = future.result()
                    outcomes[index] = outcome
                    if progress:
                        progress(index)
            except concurrent.futures.process.BrokenProcessPool as exc:  # a fill killed its worker (e.g. memory)
                for index, outcome in enumerate(outcomes):
                    if outcome is None:
                        outcomes[index] = (f"the worker process filling this hole died ({exc})", 0.0, None)
    finally:
        _JOB = None
    return outcomes
