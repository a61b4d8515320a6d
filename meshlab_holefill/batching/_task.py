"""The task a dask worker runs for one file, and the per-file result JSON it leaves next to the output.

The result file is also the task's trail: it is written with status ``running`` (the stage,
the worker's pid, how many times the file was started in this run) before the mesh is
loaded, so when a worker dies the client can tell what it was doing, a retry can see it is a
retry, and a file that timed out is not run again.
"""
from __future__ import annotations

import json
import os
import socket
import threading
import time
import traceback

from ..evaluation.isolation import process_memory_mb
from ._inputs import sha256_file

# How often one file may be started in one run: the first try and one retry.
MAX_STARTS = 2
TIMEOUT_EXIT_CODE = 75


def read_result(path):
    """A per-file result dict, or None when it is missing or unreadable (a save cut short)."""
    try:
        with open(path) as fh:
            data = json.load(fh)
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def write_result(path, record):
    """Write a per-file result atomically (a temporary file renamed), so readers never see half of one."""
    tmp = f"{path}.tmp-{os.getpid()}-{threading.get_ident()}"
    with open(tmp, "w") as fh:
        json.dump(record, fh, indent=1, default=_plain)
    os.replace(tmp, path)


def _plain(value):
    """JSON fallback for numpy scalars and arrays in filter results."""
    if hasattr(value, "tolist"):
        return value.tolist()
    return str(value)


def _reset_peak():
    """Start a new peak-memory window for this worker process; returns the scope of later figures.

    Linux resets VmHWM to the current resident size when 5 is written to clear_refs, so the peak
    belongs to this file and not to whatever the long-lived worker did before. Elsewhere only
    the process's lifetime peak is known.
    """
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return "file"
    except OSError:
        return "process"


def _peak_mb():
    peak = process_memory_mb("VmHWM")
    if peak is None:  # no /proc: the lifetime peak (ru_maxrss, KiB on Linux and the BSDs)
        import resource

        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return peak


def _starts_so_far(previous, job):
    """How many times this file was started earlier in this run (0 for a fresh start)."""
    if previous and previous.get("run_id") == job["run_id"] and previous.get("status") in ("running", "timeout"):
        return int(previous.get("starts", 0))
    return 0


def _done_in_this_run(previous, job):
    return bool(previous and previous.get("run_id") == job["run_id"] and previous.get("status") in ("ok", "failed")
                and previous.get("key") == job["params_key"])


def _watchdog(job, trail):
    """A timer that ends the worker process when the file runs past its timeout.

    Native code cannot be interrupted from Python, so the only way to stop it is to end the
    process; dask's nanny starts a new worker. The trail says ``timeout`` first, so the retry
    that dask schedules gives up at once instead of timing out again.
    """
    if not job.get("timeout"):
        return None

    def expire():
        trail.update(status="timeout", error=f"timed out after {job['timeout']:g} s (stage {trail.get('stage')})")
        try:
            write_result(job["result"], trail)
        finally:
            os._exit(TIMEOUT_EXIT_CODE)

    timer = threading.Timer(job["timeout"], expire)
    timer.daemon = True
    timer.start()
    return timer


def base_record(job):
    """The fields every per-file record has, whatever happened to the file."""
    return {"input": job["input"], "output": job["output"], "name": job["name"], "run_id": job["run_id"],
            "key": job["params_key"], "filter": job["filter"], "params": job["params"], "mlx": job["mlx"],
            "mlx_sha256": job["mlx_sha256"], "input_sha256": job.get("input_sha256")}


def run_file(job):
    """Repair one file (runs in a dask worker): load, fill, save, write its result JSON.

    Parameters
    ----------
    job : dict
        Plain data made by the client: ``input``, ``output``, ``result`` (the result JSON path),
        ``name``, ``run_id``, ``params_key``, ``filter``, ``params`` (encoded), ``mlx``,
        ``mlx_sha256``, ``timeout`` (seconds or None) and ``on_start`` (a callable taking the
        input path, run in the worker before the file is loaded, or None).

    Returns
    -------
    dict
        The per-file record (also written to ``job["result"]``): ``status`` ``"ok"`` or
        ``"failed"``, ``error`` and ``traceback`` on failure, ``result`` (the filter's report
        with its per-hole list), ``seconds`` (``hash``, ``load``, ``fill``, ``save``, ``total``),
        ``peak_rss_mb`` (the worker's peak resident memory while on this file) and its
        ``peak_scope``, ``starts``, ``worker`` (host and pid).
    """
    from ..meshlab.file_job import fill_file

    t0 = time.perf_counter()
    previous = read_result(job["result"])
    if _done_in_this_run(previous, job):  # run again after its worker died holding the return value
        return previous
    starts = _starts_so_far(previous, job) + 1
    record = base_record(job)
    record.update(status="running", stage="hash", starts=starts, worker={"host": socket.gethostname(), "pid": os.getpid()},
                  started=time.time())
    if previous and previous.get("status") == "timeout" and starts > 1:
        record["starts"] = starts - 1  # this start only gives up
        return _finish(job, record, t0, error=previous.get("error"))
    if starts > MAX_STARTS:
        return _finish(job, record, t0, error=f"its worker died on each of {MAX_STARTS} starts "
                                              f"(last seen in stage {previous.get('stage')})")
    write_result(job["result"], record)
    timer = _watchdog(job, record)
    error = tb = None
    try:
        record["peak_scope"] = _reset_peak()
        record["input_sha256"] = sha256_file(job["input"])
        hashed = time.perf_counter()

        def stage(name):
            record["stage"] = name
            write_result(job["result"], record)

        if job.get("on_start") is not None:
            stage("on_start")
            job["on_start"](job["input"])
        done = fill_file(job["input"], job["output"], filter=job["filter"], params=job["params"],
                         mlx=job["mlx"], on_stage=stage)
        record.update(result=done["result"], vertices=done["vertices"], faces=done["faces"],
                      seconds={"hash": hashed - t0, **done["seconds"]})
    except Exception as exc:  # a bad file fails alone; the batch goes on
        error, tb = f"{type(exc).__name__}: {exc}", traceback.format_exc(limit=-4)
    finally:
        if timer is not None:
            timer.cancel()
    return _finish(job, record, t0, error, tb)


def _finish(job, record, t0, error=None, tb=None):
    record["status"] = "failed" if error else "ok"
    record["error"] = error
    if tb:
        record["traceback"] = tb
    record.setdefault("seconds", {})["total"] = time.perf_counter() - t0
    if "peak_scope" in record:
        record["peak_rss_mb"] = _peak_mb()
    if not error:
        record.pop("stage", None)
    write_result(job["result"], record)
    return record
