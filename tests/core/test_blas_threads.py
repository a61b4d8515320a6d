"""The single BLAS thread: one thread inside, the previous count restored after the last block, results unchanged;
no thread pool started in run_jobs' children."""
import os
import sys
import threading
import time

import numpy as np
import pytest
import scipy.linalg as sla

from meshlab_holefill.core import parallel
from meshlab_holefill.core.blas_threads import _thread_local_setters, single_blas_thread


def local_threads():
    """The calling thread's OpenBLAS thread counts (read by setting and restoring them)."""
    out = []
    for fn in _thread_local_setters():
        value = fn(1)
        fn(value)
        out.append(value)
    return out


def test_one_thread_inside_the_previous_setting_after():
    before = local_threads()
    with single_blas_thread():
        assert all(n == 1 for n in local_threads())
    assert local_threads() == before


def test_concurrent_blocks_restore_the_count_once_the_last_ends():
    before = local_threads()
    inside, release = threading.Event(), threading.Event()

    def fill():
        with single_blas_thread():
            inside.set()
            release.wait(10)

    worker = threading.Thread(target=fill)
    with single_blas_thread():
        worker.start()
        inside.wait(10)
    assert all(n == 1 for n in local_threads())  # the worker's block is still running
    release.set()
    worker.join()
    assert local_threads() == before


def _threads_of_this_process():
    return len(os.listdir("/proc/self/task"))


def _blas_job(item):
    """A fill's shape: a block of its own around dense algebra; (pid, threads before, threads after, BLAS counts)."""
    threads = _threads_of_this_process()
    rng = np.random.default_rng(item)
    A = rng.normal(size=(200, 200))
    with single_blas_thread():
        sla.cho_factor(A @ A.T + 200 * np.eye(200))
        time.sleep(0.02)  # long enough for the forked child to take some items too
    after = _threads_of_this_process()
    return os.getpid(), threads, after, local_threads()


@pytest.mark.skipif(not sys.platform.startswith("linux") or not _thread_local_setters()
                    or parallel.available_workers() < 2, reason="needs Linux, OpenBLAS, two CPUs and fork")
def test_run_jobs_children_have_one_blas_thread_and_start_no_thread_pool():
    # A child that set the count itself would start OpenBLAS's pool (threads busy-waiting beside the fill).
    before = local_threads()
    results = parallel.run_jobs(_blas_job, list(range(8)), workers=2)
    children = [r for r in results if r[0] != os.getpid()]
    assert children, "the forked child took no job"
    assert all(counts == [1] * len(before) for *_, counts in results)
    assert all(after == threads for _, threads, after, _ in children)
    assert local_threads() == before


def test_cholesky_with_one_thread_is_within_rounding_of_several():
    # OpenBLAS splits the trailing updates between threads: the last bits may move.
    rng = np.random.default_rng(0)
    for n in (50, 249, 600):
        A = rng.normal(size=(n, n))
        A = A @ A.T + n * np.eye(n)
        b = rng.normal(size=n)
        ref = sla.cho_solve(sla.cho_factor(A, lower=True), b)
        with single_blas_thread():
            got = sla.cho_solve(sla.cho_factor(A, lower=True), b)
        assert np.abs(got - ref).max() <= 1e-13 * np.abs(ref).max()


def test_filled_patch_with_one_blas_thread_is_within_rounding(monkeypatch):
    # The whole fill of a 116-edge hole (100 training samples): the same faces, vertices within
    # 1e-12 of the bounding-box diagonal (measured on the benchmark: at most 7e-15).
    import contextlib

    import pymeshlab

    from meshlab_holefill.algorithms.xu2013 import lssvm_poisson
    from conftest import cut_disks, mesh_arrays, meshset_from_arrays

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=5)
    V, F = mesh_arrays(ms)
    V, F, _ = cut_disks(V, F, np.array([[0.0, 0.0, 1.0]]), 0.5)

    def filled():
        out = meshset_from_arrays(V, F)
        out.meshing_close_holes_lssvm_poisson(workers=1)
        return mesh_arrays(out)

    V1, F1 = filled()
    monkeypatch.setattr(lssvm_poisson, "single_blas_thread", contextlib.nullcontext)
    V2, F2 = filled()
    assert np.array_equal(F1, F2) and len(F1) > len(F)
    assert np.abs(V1 - V2).max() <= 1e-12 * np.linalg.norm(V.max(axis=0) - V.min(axis=0))
