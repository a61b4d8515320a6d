"""Running the file tasks on dask.distributed: the embedded cluster or a given one, dead workers, interrupts.

A worker that dies (a segfault in native code, the nanny's memory limit, a timeout) is dask's
business: its nanny starts a new worker, and the scheduler gives each task that was running
there ``distributed.scheduler.allowed-failures`` more tries before the task ends with
``KilledWorker``. The embedded cluster allows one retry and hands a worker one task at a time
(``worker-saturation`` 1.0 with one thread), so only the file that was running when a worker
died is blamed for it.
"""
from __future__ import annotations

import contextlib
import logging
import os
import sys
import time
import uuid

from ._task import MAX_STARTS, base_record, read_result, run_file, write_result

# A batch whose cluster has had no worker this long gives up on the files not yet done (workers
# that cannot start, a scheduler nobody serves) instead of waiting for ever.
NO_WORKER_SECONDS = 120.0

LOCAL_CLUSTER_CONFIG = {
    "distributed.scheduler.allowed-failures": MAX_STARTS - 1,
    "distributed.scheduler.worker-saturation": 1.0,
}


def default_workers():
    """Worker processes for the embedded cluster: one per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def open_client(client=None, scheduler=None, n_workers=None, memory_limit="auto"):
    """A ``distributed.Client``: the one given, one connected to ``scheduler``, or an embedded cluster.

    Parameters
    ----------
    client : distributed.Client, optional
        Used as it is (and left open).
    scheduler : str, optional
        Address of a running scheduler, e.g. ``tcp://10.0.0.5:8786``.
    n_workers : int, optional
        Worker processes of the embedded ``LocalCluster`` (default: one per core), one thread each.
    memory_limit : str, float or int
        Per-worker memory limit of the embedded cluster (``"4GiB"``, bytes, or ``"auto"``: the
        machine's memory shared out); a worker above 95 % of it is restarted by its nanny.
    """
    from distributed import Client, LocalCluster

    if client is not None:
        yield client
        return
    if scheduler is not None:
        with Client(scheduler, timeout="30s") as connected:
            yield connected
        return
    import dask

    with main_script_not_rerun():
        with dask.config.set(LOCAL_CLUSTER_CONFIG):
            cluster = LocalCluster(n_workers=n_workers or default_workers(), threads_per_worker=1, processes=True,
                                   memory_limit=memory_limit, dashboard_address=":0", silence_logs=logging.ERROR)
        with cluster, Client(cluster) as local:
            yield local


@contextlib.contextmanager
def main_script_not_rerun():
    """While the embedded cluster runs, keep the caller's script from running again in its workers.

    The cluster's nannies start worker processes with multiprocessing's ``spawn`` method, which
    imports the calling process's main script (as ``__mp_main__``) in every new worker: a
    script that calls :func:`meshlab_holefill.batch` without an ``if __name__ == "__main__":``
    guard would start a cluster from each worker, and the first one fails with "Nanny failed to
    start". With the main module's ``__file__`` and ``__spec__`` hidden, as in an interactive
    session, workers import only what the tasks need; functions defined in the script (an
    ``on_start`` hook) still reach them, pickled by value. Restarted workers (after a crash or
    the memory limit) are spawned by the same nannies, so the names stay hidden until the
    cluster is closed.
    """
    main = sys.modules.get("__main__")
    hidden = {name: main.__dict__[name] for name in ("__file__", "__spec__")
              if main is not None and main.__dict__.get(name) is not None}
    if not hidden:
        yield
        return
    main.__dict__.pop("__file__", None)
    main.__spec__ = None
    try:
        yield
    finally:
        main.__dict__.update(hidden)


def run_jobs(client, jobs, on_record, progress=False):
    """Run one task per job on ``client`` and hand every per-file record to ``on_record`` as it arrives.

    Parameters
    ----------
    client : distributed.Client
    jobs : list of dict
        Made by the client side of the batch (see :func:`meshlab_holefill.batch._task.run_file`),
        largest input first: the scheduler starts tasks in submission order.
    on_record : callable
        Called with each file's final record (``status`` ``"ok"`` or ``"failed"``).
    progress : bool
        Show a tqdm bar on stderr.

    Notes
    -----
    Task keys are ``holefill-<run token>-<index>`` (``-r`` appended for a resubmission): one
    dask task group, so the scheduler queues the tasks instead of handing them all out.
    A task that ends with ``KilledWorker`` although its file was started fewer than
    ``MAX_STARTS`` times (it was queued on a worker that another file killed, or the cluster
    allows no retry) is submitted once more. On KeyboardInterrupt the tasks not yet finished
    are cancelled and the interrupt goes on to the caller.
    """
    from distributed import as_completed
    from tqdm import tqdm

    token = uuid.uuid4().hex[:8]
    keys = [f"holefill-{token}-{i:05d}" for i in range(len(jobs))]
    futures = client.map(run_file, jobs, key=keys, pure=False)
    job_of = dict(zip(keys, jobs))
    pending, resubmitted = set(futures), set()
    bar = tqdm(total=len(jobs), unit="file", disable=not progress, file=sys.stderr, dynamic_ncols=True)
    done = as_completed(futures)
    try:
        for future in _arrivals(done, client):
            pending.discard(future)
            job = job_of[future.key]
            record = _outcome(future, job, retry_allowed=future.key not in resubmitted)
            if record is _WAIT:
                pending.add(future)
                done.add(future)
                continue
            if record is _RESUBMIT:
                again = client.submit(run_file, job, key=future.key + "-r", pure=False)
                job_of[again.key] = job
                resubmitted.add(again.key)
                pending.add(again)
                done.add(again)
                continue
            if record is _FAILED:
                record = _failed(client, future, job)
            future.release()
            on_record(record)
            bar.update(1)
            if record["status"] == "failed":
                bar.set_postfix_str(f"failed: {record['name']}")
    except NoWorkers as stalled:
        client.cancel(list(pending))
        for future in pending:
            job = job_of[future.key]
            record = base_record(job)
            record.update(status="failed", error=str(stalled), starts=0)
            write_result(job["result"], record)
            on_record(record)
    except KeyboardInterrupt:
        client.cancel(list(pending))
        raise
    finally:
        bar.close()


class NoWorkers(RuntimeError):
    """The cluster has had no worker for :data:`NO_WORKER_SECONDS`."""


def _arrivals(done, client, poll=0.05):
    """The futures of ``done`` as they finish; raises NoWorkers when the cluster stays without workers.

    ``as_completed`` alone waits for ever when no worker is left to run the queued tasks.
    """
    idle_since = last_check = time.monotonic()
    while not done.is_empty():
        ready = done.next_batch(block=False)
        now = time.monotonic()
        if ready:
            idle_since = now
            yield from ready
            continue
        if now - last_check >= 5.0:
            last_check = now
            if client.scheduler_info(n_workers=-1).get("workers"):
                idle_since = now
            elif now - idle_since >= NO_WORKER_SECONDS:
                raise NoWorkers(f"not run: the cluster had no worker for {NO_WORKER_SECONDS:g} s")
        time.sleep(poll)


_WAIT, _RESUBMIT, _FAILED = object(), object(), object()


def _outcome(future, job, retry_allowed):
    """The file's final record, ``_WAIT`` (its task runs again), ``_RESUBMIT`` (submit it once more) or
    ``_FAILED`` (see :func:`_failed`).

    The record is read from the result JSON the task wrote, not gathered from the worker: a
    finished task's return value lives in its worker's memory and is lost (and the task run
    again) when that worker dies before the client fetches it.
    """
    record = read_result(job["result"]) or {}
    if record.get("run_id") == job["run_id"] and record.get("status") in ("ok", "failed"):
        return record
    if future.status == "finished":  # a shared file system that shows the worker's write late
        return future.result()
    if future.status in ("pending", "lost"):  # lost with a dead worker; the scheduler runs it again
        return _WAIT
    if future.status != "error":
        return _FAILED
    from distributed import KilledWorker

    killed = isinstance(future.exception(), KilledWorker) and record.get("status") != "timeout"
    return _RESUBMIT if killed and _starts(record, job) < MAX_STARTS and retry_allowed else _FAILED


def _starts(trail, job):
    same_run = trail.get("run_id") == job["run_id"]
    return int(trail.get("starts", 0)) if same_run and trail.get("status") in ("running", "timeout") else 0


def _failed(client, future, job):
    """The record of a file whose task ended in error (its worker died, or the task could not run)."""
    from distributed import KilledWorker

    exc = future.exception() if future.status == "error" else None
    trail = read_result(job["result"]) or {}
    same_run = trail.get("run_id") == job["run_id"]
    starts = _starts(trail, job)
    if same_run and trail.get("status") == "timeout":
        error = trail.get("error")
    elif isinstance(exc, KilledWorker):
        error = _death_reason(client, trail, starts)
    elif exc is None:
        error = f"its task was {future.status} by the cluster"
    else:  # e.g. the worker cannot import this package
        error = f"{type(exc).__name__}: {exc}"
    record = base_record(job)
    record.update(status="failed", error=error, starts=starts, worker=trail.get("worker"))
    if same_run and trail.get("stage"):
        record["stage"] = trail["stage"]
    write_result(job["result"], record)
    return record


def _death_reason(client, trail, starts):
    """Why the worker that had this file died, as far as the cluster knows."""
    worker = trail.get("worker") or {}
    pid = worker.get("pid")
    where = f"in stage {trail['stage']}" if trail.get("stage") else "before it started"
    try:  # the nanny reports restarts for memory to the scheduler, with the pid
        events = client.get_events("worker-restart-memory")
    except Exception:  # an older scheduler or a lost connection: the generic reason below
        events = ()
    for _, event in events:
        if pid is not None and event.get("pid") == pid:
            return (f"killed its worker (pid {pid}) by going over the worker memory limit "
                    f"({event.get('rss', 0) / 2**20:.0f} MiB resident) {where}; {starts} start(s)")
    if starts == 0:
        return "its worker died repeatedly while the file waited to start (another file crashed it)"
    return (f"killed its worker (pid {pid} on {worker.get('host')}) {where} on each of {starts} start(s): "
            "a crash in native code, a kill by the operating system, or an exit")
