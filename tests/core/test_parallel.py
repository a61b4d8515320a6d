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


def _timed_fill(item):
    def fill(ctx):
        time.sleep(5 if item == 0 else 0.0)
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
