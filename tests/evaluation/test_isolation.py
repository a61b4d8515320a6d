"""evaluation.isolation: the worker survives crashes and hangs; peak memory of a run."""
from __future__ import annotations

import time

import numpy as np
import pytest

from meshlab_holefill.evaluation.isolation import IsolatedRunner, execute_task, peak_memory_since, reset_peak_memory

from conftest import mesh_arrays


def test_runner_survives_crash_and_hang():
    with IsolatedRunner() as runner:
        crashed = runner.run({"kind": "call", "function": "os._exit", "kwargs": {"status": 3}}, timeout=30)
        assert crashed["status"] == "crashed" and "3" in crashed["error"]
        hung = runner.run({"kind": "call", "function": "time.sleep", "args": [30]}, timeout=1.0)
        assert hung["status"] == "timeout"
        ok = runner.run({"kind": "call", "function": "math.hypot", "args": [3, 4]}, timeout=30)
        assert ok["status"] == "ok" and ok["value"] == 5.0


def test_peak_memory_window_sees_a_freed_allocation():
    start = reset_peak_memory()
    if start is None:
        pytest.skip("no /proc/self/clear_refs here: memory is not reported")
    block = np.ones(50_000_000)  # 400 MB, touched
    del block
    assert peak_memory_since(start) > 350
    assert peak_memory_since(reset_peak_memory()) < 50  # a new window forgets it


def test_filter_task_reports_its_memory(bunny_scan):
    if reset_peak_memory() is None:
        pytest.skip("no /proc/self/clear_refs here: memory is not reported")
    V, F = mesh_arrays(bunny_scan)
    reply = execute_task({"kind": "filter", "V": V, "F": F, "filter": "meshing_close_holes_min_angle_bilateral",
                          "params": {}})
    assert reply["status"] == "ok" and reply["result"]["closed_holes"] == 5
    assert 0.1 < reply["memory_mb"] < 500  # the MeshSet of a 10k-face scan and the fill



def test_a_filter_task_loads_its_kernels_before_the_clock_starts(monkeypatch, bunny_scan):
    from meshlab_holefill.algorithms.hu2012 import min_angle_bilateral

    calls = []
    monkeypatch.setattr(min_angle_bilateral, "WARM_UP", lambda: calls.append("warm"))
    V, F = mesh_arrays(bunny_scan)
    started = []
    real_perf_counter = time.perf_counter
    monkeypatch.setattr(time, "perf_counter", lambda: started.append(len(calls)) or real_perf_counter())
    reply = execute_task({"kind": "filter", "V": V, "F": F, "filter": "meshing_close_holes_min_angle_bilateral",
                          "params": {}})
    assert reply["status"] == "ok" and reply["result"]["closed_holes"] == 5
    assert started and started[0] == 1  # warmed once before the first clock reading (the pipeline asks again)
    before = len(calls)
    baseline = execute_task({"kind": "filter", "V": V, "F": F, "filter": "meshing_close_holes", "params": {}})
    assert baseline["status"] == "ok" and len(calls) == before  # MeshLab's own filter: nothing to load
