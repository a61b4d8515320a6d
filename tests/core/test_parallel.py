import os
import threading
import time

import pytest

from meshlab_holefill.core import parallel
from meshlab_holefill.core.parallel import HoleTimeLimit, fill_one, run_jobs, worker_count

pytestmark = pytest.mark.skipif(parallel.available_workers() < 2, reason="needs two CPUs and fork")


def _slow_square(item):
    time.sleep(0.02)  # long enough for the forked child to take some items too
    return item * item, os.getpid()


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_results_come_back_in_item_order_whatever_the_number_of_processes(workers):
    items = list(range(12))
    with parallel.limit_workers(3):
        results = run_jobs(_slow_square, items, workers)
    assert [value for value, _ in results] == [i * i for i in items]
    pids = {pid for _, pid in results}
    # this process takes items too: one fork fewer than there are processes
    assert os.getpid() in pids and len(pids) == min(workers, worker_count(workers, len(items)))


def test_progress_is_called_here_once_per_item():
    calls = []
    run_jobs(_slow_square, list(range(8)), 2, progress=lambda position: calls.append((position, os.getpid())))
    assert sorted(position for position, _ in calls) == list(range(8))
    assert {pid for _, pid in calls} == {os.getpid()}


def _fails_in_the_child(item):
    if os.getpid() != PARENT:
        raise KeyError(f"bug on item {item}")
    time.sleep(0.05)
    return item


PARENT = os.getpid()


def test_a_bug_in_a_childs_job_is_raised_here():
    with pytest.raises(KeyError, match="bug on item"):
        run_jobs(_fails_in_the_child, list(range(6)), 2)


def _dies_in_the_child(item):
    time.sleep(0.05)
    if os.getpid() != PARENT:
        os._exit(3)  # as the system's out-of-memory killer would end it
    return item


def test_the_items_of_a_child_that_died_fail_with_the_reason_and_the_others_are_done():
    results = run_jobs(_dies_in_the_child, list(range(6)), 2)
    died = [r for r in results if isinstance(r, str)]
    assert died and all("died (exit code 3)" in r for r in died)
    assert [r for r in results if not isinstance(r, str)] == [i for i, r in enumerate(results) if r == i]


class _Ctx:
    points = forbidden_edges = ()


def _busy(seconds):
    """Work in Python lines for ``seconds``: where a time limit can stop it (it waits out a blocking call)."""
    deadline = time.perf_counter() + seconds
    while time.perf_counter() < deadline:
        pass


def _timed_fill(item):
    def fill(ctx):
        _busy(5 if item == 0 else 0.0)
        raise HoleTimeLimit("not reached")  # a fill that returned would be validated; failing is enough here

    reason, seconds = fill_one(fill, _Ctx(), {}, 0.3)
    return reason, seconds, os.getpid()


def test_the_time_limit_holds_in_every_process_and_from_a_thread():
    """From a thread other than the main one this process cannot time a job: then only children take them."""
    out = {}
    for where in ("main", "thread"):
        if where == "main":
            out[where] = run_jobs(_timed_fill, list(range(4)), 2)
        else:
            worker = threading.Thread(target=lambda: out.__setitem__(where, run_jobs(_timed_fill, list(range(4)), 2)))
            worker.start()
            worker.join()
        reason, seconds, _ = out[where][0]
        assert "time limit of 0.3 s" in reason and seconds < 2
    assert os.getpid() not in {pid for _, _, pid in out["thread"]}


@pytest.mark.parametrize("estimate, expected", [(None, 2), (0.01, 1), (0.09, 1), (0.1, 2), (50.0, 2)])
def test_automatic_count_forks_only_for_work_worth_a_process_each(estimate, expected):
    with parallel.limit_workers(2):
        assert worker_count(0, 10, estimate) == expected


def test_an_explicit_count_is_kept_whatever_the_estimate():
    with parallel.limit_workers(2):
        assert worker_count(2, 10, 0.001) == 2
        assert worker_count(2, 1, 50.0) == 1  # never more processes than jobs


def test_automatic_count_keeps_small_runs_in_this_process_and_forks_for_large_ones(monkeypatch):
    import numpy as np

    from meshlab_holefill.array_api import fill_holes
    from meshlab_holefill.core import examples, pipeline

    asked = []

    def recording_run_jobs(job, items, workers=1, progress=None):
        asked.append(workers)
        return run_jobs(job, items, workers, progress)

    monkeypatch.setattr(pipeline, "run_jobs", recording_run_jobs)
    V, F, loop = examples.bowl_with_hole()
    with parallel.limit_workers(2):
        V1, F1, _ = fill_holes(V, F, "min_angle_bilateral")  # one small hole: far below 0.1 s of work
        monkeypatch.setattr(parallel, "SECONDS_PER_PROCESS", 1e-9)  # every run worth a fork
        V2, F2, _ = fill_holes(V, F, "min_angle_bilateral")
    assert asked == [1, 1]  # one hole: one process, however much it is worth
    holes = 3
    Vs = np.concatenate([V + [3.0 * k, 0.0, 0.0] for k in range(holes)])
    Fs = np.concatenate([F + k * len(V) for k in range(holes)])
    asked.clear()
    with parallel.limit_workers(2):
        fill_holes(Vs, Fs, "min_angle_bilateral")
        monkeypatch.setattr(parallel, "SECONDS_PER_PROCESS", 0.05)
        fill_holes(Vs, Fs, "min_angle_bilateral")
    assert asked == [2, 1]
    assert np.array_equal(V1, V2) and np.array_equal(F1, F2)


def test_a_fallback_that_catches_the_time_limit_does_not_carry_on_past_it():
    from meshlab_holefill.errors import HoleFillError

    def fill_with_fallback(ctx):
        try:
            _busy(5)
        except HoleFillError:
            _busy(5)  # a fallback taking over: stopped again
        return None

    reason, seconds = fill_one(fill_with_fallback, _Ctx(), {}, 0.2)
    assert "time limit of 0.2 s" in reason and seconds < 2


def test_a_fill_that_ends_past_its_limit_in_a_blocking_call_fails_all_the_same():
    def fill_blocking(ctx):
        time.sleep(0.3)  # a blocking call is waited out
        raise AssertionError("the limit's error is raised as soon as Python code runs again")

    reason, seconds = fill_one(fill_blocking, _Ctx(), {}, 0.1)
    assert "time limit of 0.1 s" in reason and seconds < 1
