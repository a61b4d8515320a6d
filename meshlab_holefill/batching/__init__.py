"""Batch repair of many mesh files on dask.distributed: :func:`batch` (``meshlab_holefill.batch``).

Each file is one dask task that loads the mesh, runs a filter (or a .mlx script), saves it
under the output folder and writes ``<output>.json`` beside it with the filter's per-hole
report, timings, the worker's peak memory and any error. The run report (``batch.json``,
``batch.csv``, ``summary.md``) goes to the output folder, also when the run is interrupted.

Inputs, the output folder and the script must be on a file system that every worker sees at
the same paths (on one machine they always are).
"""
from __future__ import annotations

import hashlib
import json
import os
import sys
import time

from ._inputs import OUTPUT_FORMATS, BatchInputError, plan_outputs, sha256_file
from ._report import BatchReport, make_report, write_report
from ._task import read_result

DEFAULT_FILTER = "meshing_close_holes_min_angle_bilateral"

__all__ = ["BatchInputError", "BatchInterrupted", "BatchReport", "OUTPUT_FORMATS", "batch"]


class BatchInterrupted(KeyboardInterrupt):
    """The batch was interrupted (Ctrl-C); ``.report`` holds what finished (already written to disk)."""

    def __init__(self, report):
        super().__init__(f"batch interrupted; report in {report.paths.get('summary')}")
        self.report = report


def batch(inputs, out, filter=None, mlx=None, client=None, *, scheduler=None, n_workers=None, memory_limit="auto",
          timeout=None, format=None, force=False, progress=None, on_start=None, **params):
    """Repair many mesh files, one dask task per file; resumable, and isolated from crashes.

    Parameters
    ----------
    inputs : str, os.PathLike or sequence of them
        Files, folders (walked recursively for mesh files) and glob patterns.
    out : str or os.PathLike
        Output folder. A file keeps its name (and its path below a given folder); the output
        never overwrites an input. ``<output>.json`` beside each output is its result.
    filter : str, optional
        Filter to run (ours or a pymeshlab built-in); default
        ``meshing_close_holes_min_angle_bilateral`` unless ``mlx`` is given.
    mlx : str or os.PathLike, optional
        A MeshLab .mlx filter script to run instead of one filter (built-in filters and ours).
    client : distributed.Client, optional
        Run on this client's cluster. Default: an embedded ``LocalCluster`` of ``n_workers``
        worker processes (one thread each), closed at the end.
    scheduler : str, optional
        Address of a running dask scheduler (``tcp://host:8786``) instead of ``client``.
    n_workers : int, optional
        Worker processes of the embedded cluster; default one per core.
    memory_limit : str or int
        Per-worker memory limit of the embedded cluster (``"4GiB"``; default ``"auto"``, the
        machine's memory shared out); a file that drives its worker above it fails.
    timeout : float, optional
        Seconds one file may take; a file over it fails (its worker is restarted) and is not retried.
    format : {"ply", "obj", "stl", "off"}, optional
        Output format; default each input's own (ply for formats a batch does not write).
    force : bool
        Redo files whose output is up to date.
    progress : bool, optional
        Progress bar on stderr; default: when stderr is a terminal.
    on_start : callable, optional
        ``on_start(input_path)``, run in the worker just before a file is loaded (e.g. to set
        up logging); an exception from it fails that file. It must pickle (cloudpickle).
    **params
        Parameters of ``filter``.

    Returns
    -------
    BatchReport
        Per-file records and counts; also written to ``out/batch.json``, ``batch.csv`` and
        ``summary.md``. A file that was started and whose worker died (crash, memory limit) is
        retried once, then reported ``failed`` with the reason; the batch goes on.

    Raises
    ------
    BatchInputError
        No input matched, an output would overwrite an input, conflicting options.
    meshlab_holefill.FilterParameterError, meshlab_holefill.MlxScriptError
        Unknown filter or parameter, malformed script: all before any work starts.
    BatchInterrupted
        Ctrl-C: the report of what finished is written first.

    Notes
    -----
    A file is up to date, and skipped, when its output exists and its result JSON says ``ok``
    for the same input content (SHA-256), filter, parameters, script content and package
    version. On a cluster of your own, start workers with one thread (``dask worker ADDRESS
    --nthreads 1``), since a crash or timeout ends the whole worker process; its scheduler's
    ``allowed-failures`` gives the retries (a file is started at most twice all the same).
    """
    started = time.perf_counter()
    settings, items = _prepare(inputs, out, filter, mlx, client, scheduler, n_workers, timeout, format, params)
    records, todo = {}, []
    for item in items:
        previous = None if force else _up_to_date(item, settings["key"])
        if previous is not None:
            records[item.name] = {**previous, "status": "skipped", "reason": "up to date"}
        else:
            todo.append(item)
    if progress is None:
        progress = sys.stderr.isatty()
    interrupted = False
    try:
        if todo:
            _execute(todo, settings, records, client, scheduler, n_workers, memory_limit, progress, on_start)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        files = [records.get(item.name) or _not_run(item) for item in items]
        report = write_report(make_report(files, time.perf_counter() - started, settings["out"], interrupted,
                                          {k: v for k, v in settings.items() if k != "key"}))
    if interrupted:
        raise BatchInterrupted(report)
    return report


def _prepare(inputs, out, filter, mlx, client, scheduler, n_workers, timeout, format, params):
    """Check every option and plan the outputs; nothing is written yet."""
    from ..meshlab.file_job import check_filter, check_script, encode_params
    from .._version import __version__

    if filter is not None and mlx is not None:
        raise BatchInputError("give a filter or an .mlx script, not both")
    if mlx is not None and params:
        raise BatchInputError(f"filter parameters ({', '.join(params)}) go inside the .mlx script")
    if client is not None and scheduler is not None:
        raise BatchInputError("give a client or a scheduler address, not both")
    if timeout is not None and not timeout > 0:
        raise BatchInputError(f"timeout must be a positive number of seconds, got {timeout!r}")
    if n_workers is not None and (client is not None or scheduler is not None):
        raise BatchInputError("n_workers sizes the embedded cluster; a given cluster has its own workers")
    if n_workers is not None and n_workers < 1:
        raise BatchInputError(f"n_workers must be at least 1, got {n_workers!r}")
    out = os.path.abspath(os.fspath(out))
    if os.path.exists(out) and not os.path.isdir(out):
        raise BatchInputError(f"the output {out} exists and is not a folder")
    encoded = encode_params(params)
    if mlx is not None:
        mlx = os.path.abspath(os.fspath(mlx))
        check_script(mlx)
        mlx_sha256, filter = sha256_file(mlx), None
    else:
        filter, mlx_sha256 = filter or DEFAULT_FILTER, None
        check_filter(filter, encoded)
    items = plan_outputs(inputs, out, format)
    key = hashlib.sha256(json.dumps({"filter": filter, "params": encoded, "mlx_sha256": mlx_sha256,
                                     "version": __version__}, sort_keys=True).encode()).hexdigest()
    settings = {"out": out, "filter": filter, "params": encoded, "mlx": mlx, "mlx_sha256": mlx_sha256,
                "timeout": timeout, "format": format, "scheduler": scheduler, "version": __version__, "key": key}
    return settings, items


def _up_to_date(item, key):
    """The previous record of a file whose output needs no work, else None."""
    previous = read_result(item.result)
    if not previous or previous.get("status") != "ok" or previous.get("key") != key:
        return None
    if not os.path.isfile(item.output) or previous.get("input_sha256") != sha256_file(item.input):
        return None
    return previous


def _job(item, settings, run_id, on_start):
    return {"input": item.input, "output": item.output, "result": item.result, "name": item.name,
            "run_id": run_id, "params_key": settings["key"], "filter": settings["filter"],
            "params": settings["params"], "mlx": settings["mlx"], "mlx_sha256": settings["mlx_sha256"],
            "timeout": settings["timeout"], "on_start": on_start}


def _execute(todo, settings, records, client, scheduler, n_workers, memory_limit, progress, on_start):
    import uuid

    from ._run import open_client, run_jobs

    for item in todo:
        os.makedirs(os.path.dirname(item.output), exist_ok=True)
    run_id = uuid.uuid4().hex
    jobs = [_job(item, settings, run_id, on_start) for item in sorted(todo, key=lambda i: -i.size)]
    with open_client(client, scheduler, n_workers, memory_limit) as c:
        settings["workers"] = len(c.scheduler_info(n_workers=-1).get("workers", {}))
        run_jobs(c, jobs, lambda record: records.__setitem__(record["name"], record), progress)


def _not_run(item):
    return {"input": item.input, "output": item.output, "name": item.name, "status": "not run",
            "error": "interrupted before it finished"}
