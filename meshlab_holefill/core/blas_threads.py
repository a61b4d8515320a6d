"""One OpenBLAS thread inside a block (OpenBLAS's thread count, set and restored).

Two users:

- LS-SVM + Poisson fills every hole inside :func:`single_blas_thread`: the dense algebra of one
  hole is small (the KKT system of a few hundred samples, Xu et al. Sec. 2.2) and OpenBLAS's
  threads cost more than they share. On the benchmark machine (2 cores, other processes
  running) the Cholesky factorisation of a 249-sample system took 0.67 s wall-clock with
  OpenBLAS's default threads and 0.009 s with one.
- :func:`.parallel.run_jobs` holds one block from before it forks its children until they are
  joined, so that every process filling holes has one BLAS thread and two processes on two
  cores do not run four. The count is set once, in the parent: a fork stops OpenBLAS's thread
  pool, and a child that set the count again (as a fill would, outside a block) would start a
  fresh pool whose threads busy-wait beside the fill (0.2 s of a second core per child).
  Children inherit the count and this module's state, so their fills, nested in the inherited
  block, do not touch it.

``openblas_set_num_threads_local`` (OpenBLAS >= 0.3.27, in the builds numpy and scipy ship) sets
the count and returns the previous one; in these (pthreads) builds the setting is
process-wide, so concurrent blocks share one save and restore (the first to enter saves, the
last to leave restores). Elsewhere (other BLAS, other builds) this is a no-op. The arithmetic of
each BLAS call is the same with one thread as with several for these sizes (the filters'
outputs are bit-identical on the benchmark).
"""
from __future__ import annotations

import ctypes
import glob
import os
import threading
from contextlib import contextmanager

__all__ = ["single_blas_thread"]

_SETTERS = None
_LOCK = threading.Lock()
_STATE = {"depth": 0, "saved": []}  # blocks open, the counts to restore


def _thread_local_setters():
    """``openblas_set_num_threads_local`` of the OpenBLAS libraries numpy and scipy load (may be none)."""
    global _SETTERS
    if _SETTERS is None:
        import numpy
        import scipy
        import scipy.linalg  # noqa: F401  (loads scipy's OpenBLAS)

        _SETTERS = []
        for package in (numpy, scipy):
            site = os.path.dirname(os.path.dirname(package.__file__))
            for path in sorted(glob.glob(os.path.join(site, package.__name__ + ".libs", "*openblas*"))):
                try:
                    fn = ctypes.CDLL(path).openblas_set_num_threads_local
                except (OSError, AttributeError):
                    continue
                fn.argtypes, fn.restype = [ctypes.c_int], ctypes.c_int
                _SETTERS.append(fn)
    return _SETTERS


@contextmanager
def single_blas_thread():
    """Run the block with one OpenBLAS thread; the previous count is restored when the last such block ends."""
    setters = _thread_local_setters()
    with _LOCK:
        if _STATE["depth"] == 0:
            _STATE["saved"] = [fn(1) for fn in setters]
        _STATE["depth"] += 1
    try:
        yield
    finally:
        with _LOCK:
            _STATE["depth"] -= 1
            if _STATE["depth"] == 0:
                for fn, value in zip(setters, _STATE["saved"]):
                    fn(value)
