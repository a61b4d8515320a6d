"""Run filters isolated from the caller: a spawned worker process per comparison, killed on timeout.

One worker is kept and reused (its imports are paid once); a task that times out or crashes
the worker (a segfault in native code, ``os._exit``) costs only that worker, which is
replaced for the next task. Only arrays and plain values cross the pipe.
"""
from __future__ import annotations

import ctypes
import gc
import importlib
import multiprocessing
import time
import traceback

import numpy as np

from ..meshlab import register_all
from ..meshlab.mesh_files import mesh_arrays, meshset_from_arrays
from ..meshlab.registration import apply_filter, parse_text_value

__all__ = ["IsolatedRunner", "execute_task", "json_safe", "peak_memory_since", "reset_peak_memory"]


def json_safe(value):
    """``value`` with numpy arrays and scalars turned into lists and Python numbers, dict keys into str.

    Anything else that JSON cannot hold becomes its ``str``.
    """
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def _worker_params(params):
    """Parameters as the filter takes them: a text ``"5%"`` becomes MeshLab's percentage value."""
    return {key: parse_text_value(value) if isinstance(value, str) and value.endswith("%") else value
            for key, value in params.items()}


def _rss_mb(field):
    """A memory figure of this process from /proc/self/status in MB (None where there is no /proc)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def reset_peak_memory():
    """Start a new peak-memory window (Linux: writing 5 to clear_refs resets VmHWM to the current RSS).

    Free heap memory is first handed back to the system (glibc's ``malloc_trim``), so memory
    an earlier run freed but the allocator kept does not hide this run's growth. Returns the
    resident memory at the start of the window in MB, or None when peaks cannot be reset
    here (then no memory figure is reported).
    """
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
    except OSError:
        return None
    return _rss_mb("VmRSS")


def peak_memory_since(start_mb):
    """Peak resident memory above ``start_mb`` since :func:`reset_peak_memory`, in MB (None if unknown)."""
    peak = _rss_mb("VmHWM")
    return None if start_mb is None or peak is None else max(peak - start_mb, 0.0)


def execute_task(task):
    """Run one task (in the worker): a filter on arrays, a third-party filler (kind "anchor"), or a named function.

    Returns
    -------
    dict with ``status`` ("ok" or "error"), ``error``, ``seconds`` and, for a filter, ``result``,
    ``memory_mb`` (peak resident memory of building the MeshSet and running the filter, above
    the worker's memory before; None off Linux) and the mesh: ``V_new``/``F_new`` (appended
    elements, originals untouched) or ``V``/``F``.
    """
    if task["kind"] == "call":
        module, name = task["function"].rsplit(".", 1)
        t0 = time.perf_counter()
        value = getattr(importlib.import_module(module), name)(*task.get("args", []), **task.get("kwargs", {}))
        return {"status": "ok", "value": json_safe(value), "seconds": time.perf_counter() - t0}
    V0, F0 = task["V"], task["F"]
    if task["kind"] == "anchor":
        return _execute_anchor(task)
    start_mb = reset_peak_memory()
    ms = meshset_from_arrays(V0, F0, task.get("label", "mesh"))
    t0 = time.perf_counter()
    try:
        result = apply_filter(ms, task["filter"], **_worker_params(task["params"]))
    except Exception as exc:  # a comparison reports a failing filter and goes on
        tb = traceback.format_exc(limit=-3)
        return {"status": "error", "error": f"{type(exc).__name__}: {exc}", "traceback": tb,
                "seconds": time.perf_counter() - t0, "memory_mb": peak_memory_since(start_mb)}
    seconds = time.perf_counter() - t0
    memory_mb = peak_memory_since(start_mb)
    V1, F1 = mesh_arrays(ms)
    reply = {"status": "ok", "error": None, "seconds": seconds, "memory_mb": memory_mb,
             "result": json_safe(result or {})}
    n0, m0 = len(V0), len(F0)
    if len(V1) >= n0 and len(F1) >= m0 and np.array_equal(V1[:n0], V0) and np.array_equal(F1[:m0], F0):
        reply.update(V_new=V1[n0:], F_new=F1[m0:])
    else:
        reply.update(V=V1, F=F1)
    return reply


def _execute_anchor(task):
    """A third-party filler (:mod:`.anchors`) on arrays; the reply has the same shape as a filter's."""
    from .anchors import run_anchor

    V0, F0 = np.asarray(task["V"], np.float64), np.asarray(task["F"], np.int64)
    start_mb = reset_peak_memory()
    t0 = time.perf_counter()
    try:
        V1, F1, result = run_anchor(task["filter"], V0, F0, dict(task["params"]))
    except Exception as exc:  # a comparison reports a failing filler and goes on
        return {"status": "error", "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc(limit=-3),
                "seconds": time.perf_counter() - t0, "memory_mb": peak_memory_since(start_mb)}
    # map_back and the CGAL wrapper return the originals first, untouched
    return {"status": "ok", "error": None, "seconds": time.perf_counter() - t0,
            "memory_mb": peak_memory_since(start_mb), "result": json_safe(result),
            "V_new": V1[len(V0):], "F_new": F1[len(F0):]}


def _worker_loop(conn):
    register_all()  # the filters, in the fresh interpreter

    while True:
        try:
            task = conn.recv()
        except (EOFError, KeyboardInterrupt):
            return
        if task is None:
            return
        try:
            reply = execute_task(task)
        except BaseException as exc:  # noqa: BLE001  report anything rather than die silently
            reply = {"status": "error", "error": f"{type(exc).__name__}: {exc}", "seconds": float("nan")}
        conn.send(reply)


class IsolatedRunner:
    """A reusable spawned worker; a run that times out or crashes costs only that worker."""

    def __init__(self):
        self._ctx = multiprocessing.get_context("spawn")
        self._proc = None
        self._conn = None

    def _start(self):
        parent, child = self._ctx.Pipe()
        self._proc = self._ctx.Process(target=_worker_loop, args=(child,), daemon=True)
        self._proc.start()
        child.close()
        self._conn = parent

    def _discard(self):
        if self._proc is not None:
            if self._proc.is_alive():
                self._proc.kill()
            self._proc.join(5)
        if self._conn is not None:
            self._conn.close()
        self._proc = self._conn = None

    def run(self, task, timeout):
        """Run a task; returns execute_task's reply, or status "timeout" / "crashed"."""
        if self._proc is None or not self._proc.is_alive():
            self._discard()
            self._start()
        t0 = time.perf_counter()
        try:
            self._conn.send(task)
            if self._conn.poll(timeout):
                return self._conn.recv()
            self._discard()
            return {"status": "timeout", "error": f"no answer within {timeout:g} s (worker killed)",
                    "seconds": time.perf_counter() - t0}
        except (EOFError, BrokenPipeError, ConnectionResetError, OSError):
            code = self._proc.exitcode if self._proc is not None else None
            if self._proc is not None:
                self._proc.join(5)
                code = self._proc.exitcode
            self._discard()
            return {"status": "crashed", "error": f"worker process died (exit code {code})",
                    "seconds": time.perf_counter() - t0}

    def close(self):
        if self._conn is not None and self._proc is not None and self._proc.is_alive():
            try:
                self._conn.send(None)
                self._proc.join(5)
            except (BrokenPipeError, OSError):
                pass
        self._discard()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
