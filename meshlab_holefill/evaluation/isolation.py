"""Run filters isolated from the caller: a worker process per comparison, killed on timeout.

One worker is kept and reused (its imports are paid once); a task that times out or crashes
the worker (a segfault in native code, ``os._exit``) costs only that worker, which is
replaced for the next task. Only arrays and plain values cross the pipe.
"""
from __future__ import annotations

import ctypes
import gc
import importlib
import multiprocessing
import os
import socket
import subprocess
import sys
import time
import traceback

import numpy as np

from ..meshlab import register_all
from ..meshlab.mesh_files import mesh_arrays, meshset_from_arrays
from ..meshlab.registration import apply_filter, load_filter_kernels, parse_text_value

__all__ = ["IsolatedRunner", "check_not_bootstrapping", "execute_task", "json_safe", "peak_memory_since",
           "process_memory_mb", "reset_peak_memory", "worker_main"]


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


def process_memory_mb(field):
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
    return process_memory_mb("VmRSS")


def peak_memory_since(start_mb):
    """Peak resident memory above ``start_mb`` since :func:`reset_peak_memory`, in MB (None if unknown)."""
    peak = process_memory_mb("VmHWM")
    return None if start_mb is None or peak is None else max(peak - start_mb, 0.0)


def execute_task(task):
    """Run one task (in the worker): a filter on arrays, a third-party filler (kind "anchor"), or a named function.

    Returns
    -------
    dict with ``status`` ("ok" or "error"), ``error``, ``seconds`` and, for a filter, ``result``,
    ``memory_mb`` (peak resident memory of building the MeshSet and running the filter, above
    the worker's memory before, its kernels loaded; None off Linux) and the mesh: ``V_new``/``F_new`` (appended
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
    # Like the worker's imports, the kernels' one-time loading is paid before the clock starts, so a
    # filter's seconds do not depend on whether an earlier task here ran it (--compile-cost measures it).
    load_filter_kernels(task["filter"])
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
        except (EOFError, OSError, KeyboardInterrupt):
            return
        if task is None:
            return
        try:
            reply = execute_task(task)
        except BaseException as exc:  # noqa: BLE001  report anything rather than die silently
            reply = {"status": "error", "error": f"{type(exc).__name__}: {exc}", "seconds": float("nan")}
        conn.send(reply)


def worker_main(fd):
    """The worker process's entry point: serve tasks on the socket ``fd`` until told to stop.

    Run as ``python -c "from meshlab_holefill.evaluation.isolation import worker_main; worker_main(FD)"``
    by :class:`IsolatedRunner`, so the worker's ``__main__`` is that one line and never the
    caller's script.
    """
    from multiprocessing.connection import Connection

    _worker_loop(Connection(fd))


def _package_root():
    """The directory holding the ``meshlab_holefill`` package (put on the worker's PYTHONPATH)."""
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def check_not_bootstrapping():
    """Raise RuntimeError when called while ``multiprocessing`` imports a script in a child process.

    That happens when a script without an ``if __name__ == "__main__":`` guard starts
    processes of its own (a ``multiprocessing.Pool``, ...) in spawn or forkserver mode: each
    child re-runs the script's top level, and a comparison started there would run once per
    child. Our own workers never re-run the caller's script (see :class:`IsolatedRunner`).
    """
    if getattr(multiprocessing.current_process(), "_inheriting", False):
        raise RuntimeError(
            "meshlab_holefill.compare() was called while multiprocessing was starting a child process of your "
            "script (it re-runs the script's top level): put the calls that start processes under "
            "'if __name__ == \"__main__\":'")


class IsolatedRunner:
    """A reusable worker process; a run that times out or crashes costs only that worker.

    The worker is a fresh interpreter started with ``subprocess`` (``python -c`` calling
    :func:`worker_main`), talking over a socket pair with ``multiprocessing.connection``.
    Unlike a ``multiprocessing`` spawn or forkserver child it does not import the caller's
    ``__main__`` (``multiprocessing.spawn`` re-runs the main script in every child, under the
    name ``__mp_main__``, so a script calling ``compare()`` at its top level without an
    ``if __name__ == "__main__":`` guard would start a comparison in each worker and the
    worker would die): ``compare()`` works from a plain script, a notebook or ``python -c``.
    """

    def __init__(self):
        check_not_bootstrapping()
        self._proc = None
        self._conn = None

    def _start(self):
        from multiprocessing.connection import Connection

        parent, child = socket.socketpair()
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join([_package_root()] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep)
                                                                   if p])
        # -c puts the current directory first on sys.path; the worker imports only this package,
        # so that entry goes (a mesh folder's own python files never shadow a library here).
        code = ("import sys; sys.path[:1] = [] if sys.path[:1] == [''] else sys.path[:1]; "
                f"from meshlab_holefill.evaluation.isolation import worker_main; worker_main({child.fileno()})")
        try:
            self._proc = subprocess.Popen([sys.executable, "-c", code], pass_fds=(child.fileno(),), env=env,
                                          stdin=subprocess.DEVNULL, close_fds=True)
        finally:
            child.close()
        self._conn = Connection(parent.detach())

    def _discard(self):
        if self._proc is not None:
            if self._proc.poll() is None:
                self._proc.kill()
            try:
                self._proc.wait(5)
            except subprocess.TimeoutExpired:
                pass
        if self._conn is not None:
            self._conn.close()
        self._proc = self._conn = None

    def _alive(self):
        return self._proc is not None and self._proc.poll() is None

    def run(self, task, timeout):
        """Run a task; returns execute_task's reply, or status "timeout" / "crashed"."""
        if not self._alive():
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
            code = None
            if self._proc is not None:
                try:
                    code = self._proc.wait(5)
                except subprocess.TimeoutExpired:
                    code = None
            self._discard()
            return {"status": "crashed", "error": f"worker process died (exit code {code})",
                    "seconds": time.perf_counter() - t0}

    def close(self):
        if self._conn is not None and self._alive():
            try:
                self._conn.send(None)
                self._proc.wait(5)
            except (BrokenPipeError, OSError, subprocess.TimeoutExpired):
                pass
        self._discard()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
