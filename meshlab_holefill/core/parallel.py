"""Holes filled by several processes at once (they are independent), with a time limit per hole.

Each fill sees only its own hole and is deterministic (stochastic algorithms take a seed),
so the outcome of a hole does not depend on which process fills it or when: the result is
the same whatever the number of workers. :func:`run_jobs` runs one job per hole in this
process and in children forked for the call, which inherit the mesh, the job and the loaded
kernels without pickling them (closures and monkeypatched functions work too); only each
job's result travels back. This process takes jobs too, so ``workers`` processes means
``workers - 1`` forks. Where fork is not available, or inside a daemonic process (a Dask or
multiprocessing worker, which may not have children), jobs run in this process.

While several processes fill holes, each keeps OpenBLAS to one thread, set once before the
forks (:mod:`.blas_threads`): a child that set it itself would first start a pool of threads
that busy-wait beside its fill.
"""
from __future__ import annotations

import multiprocessing
import os
import queue
import signal
import sys
import threading
import time
import traceback
from contextlib import contextmanager

import numpy as np

from ..errors import HoleFillError
from .blas_threads import single_blas_thread
from .patch import validate_patch

__all__ = ["FILL_ERRORS", "HoleTimeLimit", "available_workers", "fill_one", "limit_workers", "reason_of", "run_jobs",
           "worker_count"]

_WORKER_CAP = None  # set by limit_workers
_PACKAGE = __name__.split(".")[0]

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


#: Estimated seconds of work each process must have before ``workers=0`` forks it: about twice
#: what forking, the children's first touches of the inherited mesh and collecting their
#: results cost a run (15-30 ms: the min-angle filter's whole runs on the benchmark's cases,
#: two processes against one). With it, of the benchmark's 56 runs (14 cases, 4 filters) all but
#: 4 got the faster of one and two processes, and those 4 lost at most 30 ms.
SECONDS_PER_PROCESS = 0.05


def worker_count(workers, jobs, estimated_seconds=None):
    """Processes :func:`run_jobs` uses for ``jobs`` jobs when asked for ``workers``.

    Parameters
    ----------
    workers : int
        Processes asked for; 0 chooses: one per CPU, and given ``estimated_seconds`` no more
        than give each process :data:`SECONDS_PER_PROCESS` of it (a run worth less than two
        stays in this process).
    jobs : int
    estimated_seconds : float, optional
        The jobs' estimated total time in one process.

    Returns
    -------
    int  at least 1, at most ``jobs`` and :func:`available_workers`
    """
    count = available_workers() if workers == 0 else workers
    if workers == 0 and estimated_seconds is not None:
        count = min(count, max(1, int(estimated_seconds / SECONDS_PER_PROCESS)))
    return max(1, min(count, available_workers(), jobs))


@contextmanager
def limit_workers(count):
    """Fill holes with at most ``count`` processes, each with one BLAS thread, inside the block.

    A batch task runs where the batch already keeps every core busy with one file each.
    """
    global _WORKER_CAP
    previous, _WORKER_CAP = _WORKER_CAP, max(1, int(count))
    try:
        with single_blas_thread():
            yield
    finally:
        _WORKER_CAP = previous


def _can_time():
    """Whether :func:`_time_limit` works here: only a main thread receives SIGALRM."""
    return threading.current_thread() is threading.main_thread()


#: Seconds between the alarms that follow an expired time limit (see :func:`_time_limit`).
_REPEAT_ALARM = 0.01


@contextmanager
def _time_limit(seconds, module=None):
    """Raise HoleTimeLimit in this thread after ``seconds`` (0: no limit; only in a main thread).

    The SIGALRM handler does not raise: it can run inside a compiled kernel or a C function
    that calls back into Python (numba's dispatcher, its constant unpickling), where an
    exception corrupts their state (a SystemError, or a crash). It sets a trace function,
    which raises at the next line of the package's own Python code (or of ``module``'s: the
    fill's), so the limit is honoured between kernel calls, not within one. The alarm repeats every 10 ms after the limit, and
    a block that completes after it raises too, so a fallback that catches the error cannot
    carry on past the limit.
    """
    if not seconds or not _can_time():
        yield
        return
    message = f"took longer than the time limit of {seconds:g} s"
    armed, expired = [True], [False]

    def ours(frame):
        name = frame.f_globals.get("__name__", "")
        return (name.startswith(_PACKAGE) or name == module) and name != __name__

    def raise_in_ours(frame, event, arg):
        if armed[0] and ours(frame):
            raise HoleTimeLimit(message)  # the interpreter then removes the trace function
        return None

    def expire(signum, frame):
        expired[0] = True
        sys.settrace(raise_in_ours)
        while frame is not None:
            if ours(frame):
                frame.f_trace = raise_in_ours
            frame = frame.f_back

    previous_trace = sys.gettrace()
    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds, _REPEAT_ALARM)
    try:
        yield
    finally:
        armed[0] = False
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        sys.settrace(previous_trace)
    if expired[0]:
        raise HoleTimeLimit(message)


def fill_one(fill, ctx, fill_kwargs, timelimit):
    """Fill and validate one hole within ``timelimit`` seconds (0: no limit).

    Returns
    -------
    (Patch or str, float)
        The validated patch or the reason the hole failed, and the seconds it took.
    """
    t0 = time.perf_counter()
    try:
        with _time_limit(timelimit, getattr(fill, "__module__", None)):
            patch = fill(ctx, **fill_kwargs)
            validate_patch(patch, ctx.points, ctx.forbidden_edges)
    except FILL_ERRORS as exc:
        return reason_of(exc), time.perf_counter() - t0
    return patch, time.perf_counter() - t0


class _Raised:
    """An exception a job raised in a child, carried back to be raised here."""

    def __init__(self, exc):
        self.exc = exc
        self.trace = "".join(traceback.format_exception(exc))


def _take(counter, count):
    """The next position nobody has taken, or None when all are."""
    with counter.get_lock():
        position = counter.value
        counter.value = position + 1
    return position if position < count else None


def _child_main(job, items, counter, conn):
    try:
        while (position := _take(counter, len(items))) is not None:
            conn.send((position, job(items[position])))
    except BaseException as exc:  # a bug in a job: raised again by the parent, as if the job ran there
        try:
            conn.send((None, _Raised(exc)))
        except Exception:  # the exception itself does not pickle
            conn.send((None, _Raised(RuntimeError(f"{type(exc).__name__}: {exc}"))))
    finally:
        conn.close()


def _receive(conn, inbox):
    """Move what one child sends into ``inbox`` until it closes its end (done, or dead)."""
    try:
        while True:
            inbox.put(conn.recv())
    except (EOFError, OSError):
        pass
    finally:
        inbox.put(conn)  # this child is done


def _fork_children(count, fork, job_items_counter, inbox, procs):
    """Fork ``count`` children running :func:`_child_main` (appended to ``procs``), each with a reader thread here."""
    receivers = []
    for _ in range(count):  # every fork before the first reader thread, which a child would not have
        receiving, sending = fork.Pipe(duplex=False)
        procs.append(fork.Process(target=_child_main, args=(*job_items_counter, sending), daemon=True))
        procs[-1].start()
        sending.close()  # only the child holds it now: its end of the pipe closes when the child is done
        receivers.append(receiving)
    for receiving in receivers:
        threading.Thread(target=_receive, args=(receiving, inbox), daemon=True).start()


def run_jobs(job, items, workers=1, progress=None):
    """``job(item)`` for every item, by up to ``workers`` processes at once: this one and forked children.

    Every process takes the next item not yet taken, in the order given: put the longest
    jobs first, as the run ends when the last job does. Children are forked here, after
    everything the jobs read is ready, and gone when this returns.

    Parameters
    ----------
    job : callable ``job(item) -> picklable value``
        Should catch what makes one item fail; anything else it raises is raised here.
    items : sequence
    workers : int
        Processes at once (0: one per CPU); see :func:`worker_count`.
    progress : callable, optional
        ``progress(position)`` after each job, ``position`` into ``items``, in the order jobs
        finish (called in this thread).

    Returns
    -------
    list
        Per item, in order: ``job(item)``, or for an item whose child died (killed by the
        system, out of memory) the str reason.
    """
    workers = worker_count(workers, len(items))
    # A job's time limit is a SIGALRM, which only a main thread gets: elsewhere this process only collects.
    children = workers - 1 if workers == 1 or _can_time() else workers
    results, done = [None] * len(items), [False] * len(items)

    def record(position, value):
        results[position], done[position] = value, True
        if progress:
            progress(position)

    if children == 0:
        for position, item in enumerate(items):
            record(position, job(item))
        return results
    fork = multiprocessing.get_context("fork")
    counter = fork.Value("q", 0)
    inbox = queue.SimpleQueue()
    procs = []
    open_children, finished = children, False

    def collect(block):
        """Record what the children sent (all of it, when ``block``: until every child is done)."""
        nonlocal open_children
        while open_children:
            try:
                message = inbox.get(block=block)
            except queue.Empty:
                return
            if not isinstance(message, tuple):  # a child's connection, closed: it sends nothing more
                message.close()
                open_children -= 1
                continue
            position, value = message
            if isinstance(value, _Raised):
                raise value.exc from RuntimeError(f"in a worker process:\n{value.trace}")
            record(position, value)

    with single_blas_thread():  # before the forks: the children inherit the count and the open block
        try:
            _fork_children(children, fork, (job, items, counter), inbox, procs)
            if children < workers:
                while (position := _take(counter, len(items))) is not None:
                    record(position, job(items[position]))
                    collect(block=False)
            collect(block=True)
            finished = True
        finally:
            if not finished:  # this process raised: the children's work is not wanted
                with counter.get_lock():
                    counter.value = len(items)
                for proc in procs:
                    proc.terminate()
            for proc in procs:
                proc.join()
    codes = ", ".join(sorted({str(p.exitcode) for p in procs if p.exitcode}))
    for position in range(len(items)):
        if not done[position]:
            results[position] = f"the worker process filling this hole died (exit code {codes or 'unknown'})"
    return results
