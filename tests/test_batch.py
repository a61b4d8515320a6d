"""Batch repair on real dask clusters: same meshes as sequential fills, resume, crashing files, a scheduler by address."""
import json
import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pymeshlab
import pytest

import meshlab_holefill
from meshlab_holefill.batching import BatchInputError, batch
from meshlab_holefill.batching._inputs import plan_outputs
from meshlab_holefill.cli import main

FILTER = "meshing_close_holes_min_angle_bilateral"  # the fastest filter keeps the file under a minute
PARAMS = {"maxholesize": 500, "iterations": 2}
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _holed_mesh(kind, seed, path):
    """A sphere or torus with one disk of faces removed around a random vertex, saved to ``path``."""
    ms = pymeshlab.MeshSet()
    if kind == "sphere":
        ms.create_sphere(subdiv=3)
    else:
        ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=24, vsubdiv=12)
    m = ms.current_mesh()
    V, F = m.vertex_matrix(), m.face_matrix()
    centre = V[np.random.default_rng(seed).integers(len(V))]
    keep = np.linalg.norm(V[F].mean(axis=1) - centre, axis=1) > 0.3
    out = pymeshlab.MeshSet()
    out.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F[keep]))
    out.save_current_mesh(str(path))


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    """A folder of 6 small meshes with holes, .ply and .obj, spheres and tori."""
    folder = tmp_path_factory.mktemp("meshes")
    for i in range(6):
        _holed_mesh("sphere" if i % 2 == 0 else "torus", i, folder / f"mesh{i}.{'obj' if i % 3 == 0 else 'ply'}")
    return folder


def _arrays(path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    m = ms.current_mesh()
    return m.vertex_matrix(), m.face_matrix()


def _assert_same_mesh(a, b):
    (Va, Fa), (Vb, Fb) = _arrays(a), _arrays(b)
    assert np.array_equal(Va, Vb) and np.array_equal(Fa, Fb), f"{a} differs from {b}"


def test_local_cluster_gives_the_sequential_meshes_and_a_rerun_does_no_work(meshes, tmp_path):
    out = tmp_path / "out"
    report = batch(meshes, out=out, filter=FILTER, n_workers=2, progress=False, **PARAMS)
    assert report.counts == {"ok": 6, "failed": 0, "skipped": 0, "not run": 0}
    assert report.settings["workers"] == 2
    for record in report.files:
        sequential = tmp_path / ("sequential_" + record["name"])
        args = [f"--{k}={v}" for k, v in PARAMS.items()]
        assert main(["fill", record["input"], str(sequential), "--filter", FILTER, *args]) == 0
        _assert_same_mesh(record["output"], sequential)
        with open(record["output"] + ".json") as fh:
            result = json.load(fh)
        assert result["status"] == "ok" and result["result"]["closed_holes"] == 1
        assert result["result"]["holes"][0]["status"] == "closed"
        assert result["peak_rss_mb"] > 0 and result["seconds"]["fill"] > 0
    assert {r["name"] for r in report.files} == {f"mesh{i}.{'obj' if i % 3 == 0 else 'ply'}" for i in range(6)}
    with open(out / "batch.csv") as fh:
        assert len(fh.read().strip().splitlines()) == 7
    assert "| 6 | 0 | 0 | 0 |" in (out / "summary.md").read_text()

    again = batch(meshes, out=out, filter=FILTER, progress=False, **PARAMS)  # no cluster is even started
    assert again.counts == {"ok": 0, "failed": 0, "skipped": 6, "not run": 0}
    assert all(r["reason"] == "up to date" for r in again.files)
    assert json.loads((out / "batch.json").read_text())["counts"]["skipped"] == 6


def _exit_or_hang(exit_in, hang_in):
    """An ``on_start`` hook: ends the worker process in one file, as a crash in native code would; hangs in another."""
    def hook(path):
        if os.path.basename(path) == exit_in:
            os._exit(1)
        if os.path.basename(path) == hang_in:
            time.sleep(120)
    return hook


def test_a_file_that_kills_its_worker_or_hangs_fails_alone(meshes, tmp_path):
    out = tmp_path / "out"
    report = batch(meshes, out=out, filter=FILTER, n_workers=2, progress=False, timeout=5,
                   on_start=_exit_or_hang("mesh2.ply", "mesh4.ply"), **PARAMS)
    assert report.counts == {"ok": 4, "failed": 2, "skipped": 0, "not run": 0}
    crashed, hung = report.failed
    assert crashed["name"] == "mesh2.ply" and crashed["starts"] == 2  # retried once
    assert "killed its worker" in crashed["error"] and "stage on_start" in crashed["error"]
    assert hung["name"] == "mesh4.ply" and hung["starts"] == 1  # a timeout is not retried
    assert hung["error"] == "timed out after 5 s (stage on_start)"
    assert json.loads((out / "mesh2.ply.json").read_text())["status"] == "failed"
    assert "mesh4.ply" in (out / "summary.md").read_text().split("## Failed files")[1]

    # the rerun redoes only the failed files
    again = batch(meshes, out=out, filter=FILTER, n_workers=1, progress=False, **PARAMS)
    assert again.counts == {"ok": 2, "failed": 0, "skipped": 4, "not run": 0}


def _grow_memory(in_file):
    """An ``on_start`` hook: in one file, allocates 50 MiB every 50 ms until something stops it."""
    def hook(path):
        if os.path.basename(path) == in_file:
            hog = []
            for _ in range(200):
                hog.append(np.ones(50 * 2**20 // 8))
                time.sleep(0.05)
    return hook


def test_a_file_over_the_worker_memory_limit_fails_alone_with_the_reason(meshes, tmp_path):
    report = batch(meshes, out=tmp_path / "out", filter=FILTER, n_workers=2, memory_limit="600MiB", timeout=60,
                   progress=False, on_start=_grow_memory("mesh1.ply"), **PARAMS)
    assert report.counts == {"ok": 5, "failed": 1, "skipped": 0, "not run": 0}
    (failed,) = report.failed
    assert failed["name"] == "mesh1.ply" and failed["starts"] == 2
    assert "going over the worker memory limit" in failed["error"] and "stage on_start" in failed["error"]


def test_a_plain_script_without_a_main_guard_runs_the_batch(meshes, tmp_path):
    # the cluster's workers are spawned processes; they must not run the caller's script again
    script = tmp_path / "repair_all.py"
    script.write_text(
        "import sys\n"
        "from meshlab_holefill.batching import batch\n"
        f"report = batch(sys.argv[1], out=sys.argv[2], filter={FILTER!r}, n_workers=1, progress=False, "
        f"**{PARAMS!r})\n"
        "print('counts', report.counts['ok'], report.counts['failed'], '__file__' in globals())\n")
    inputs = tmp_path / "in"
    inputs.mkdir()
    for name in ("mesh0.obj", "mesh1.ply"):
        (inputs / name).write_bytes((meshes / name).read_bytes())
    run = subprocess.run([sys.executable, str(script), str(inputs), str(tmp_path / "out")], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "counts 2 0 True" in run.stdout  # and the script's own __file__ is back afterwards


def test_a_filter_script_on_every_file(meshes, tmp_path):
    script = os.path.join(ROOT, "filters", "close_holes_min_angle_bilateral.mlx")
    inputs = [str(meshes / "mesh0.obj"), str(meshes / "*1.ply")]
    report = batch(inputs, out=tmp_path / "out", mlx=script, n_workers=1, timeout=120, format="ply", progress=False)
    assert report.counts["ok"] == 2
    for record in report.files:
        sequential = tmp_path / ("sequential_" + record["name"])
        assert main(["run", script, record["input"], str(sequential)]) == 0
        _assert_same_mesh(record["output"], sequential)
        assert record["output"].endswith(".ply") and len(record["result"]["steps"]) > 1


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _start(args, log):
    # a session of its own, so the worker's nanny and worker process are ended with it
    return subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def _stop(proc):
    for sig, wait in ((signal.SIGTERM, 15), (signal.SIGKILL, 5)):
        try:
            os.killpg(proc.pid, sig)
            proc.wait(wait)
            return
        except ProcessLookupError:
            return
        except subprocess.TimeoutExpired:
            continue


def _wait_for_worker(address, seconds=90):
    from distributed import Client

    with Client(address, timeout="30s") as client:
        client.wait_for_workers(1, timeout=seconds)


def test_cli_runs_the_batch_on_a_scheduler_by_address(meshes, tmp_path):
    broken = tmp_path / "broken.ply"
    broken.write_text("ply\nformat nonsense\n")
    dask = os.path.join(os.path.dirname(sys.executable), "dask")
    address = f"tcp://127.0.0.1:{_free_port()}"
    procs = []
    with open(tmp_path / "cluster.log", "w") as log:
        try:
            procs.append(_start([dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                                 "--no-dashboard"], log))
            procs.append(_start([dask, "worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--nworkers", "1",
                                 "--no-dashboard"], log))
            _wait_for_worker(address)
            out = tmp_path / "out"
            code = main(["batch", str(meshes), str(broken), "--out", str(out), "--scheduler", address, "--strict",
                         "--quiet", "--filter", FILTER] + [f"--{k}={v}" for k, v in PARAMS.items()])
        finally:
            for proc in reversed(procs):
                _stop(proc)
    assert code == 1  # --strict: a file failed
    data = json.loads((out / "batch.json").read_text())
    assert data["counts"] == {"ok": 6, "failed": 1, "skipped": 0, "not run": 0}
    (failed,) = [r for r in data["files"] if r["status"] == "failed"]
    assert failed["name"] == "broken.ply" and failed["stage"] == "load" and failed["error"]
    assert data["settings"]["scheduler"] == address
    assert all(os.path.getsize(r["output"]) > 0 for r in data["files"] if r["status"] == "ok")


def test_a_cluster_without_workers_fails_the_files_instead_of_waiting(meshes, tmp_path, monkeypatch):
    from meshlab_holefill.batching import _run

    monkeypatch.setattr(_run, "NO_WORKER_SECONDS", 6.0)
    address = f"tcp://127.0.0.1:{_free_port()}"
    dask = os.path.join(os.path.dirname(sys.executable), "dask")
    with open(tmp_path / "cluster.log", "w") as log:
        scheduler = _start([dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1],
                            "--no-dashboard"], log)
        try:
            from distributed import Client

            Client(address, timeout="30s").close()  # the scheduler is up
            t0 = time.monotonic()
            report = batch(meshes, out=tmp_path / "out", filter=FILTER, scheduler=address, progress=False, **PARAMS)
            waited = time.monotonic() - t0
        finally:
            _stop(scheduler)
    assert report.counts == {"ok": 0, "failed": 6, "skipped": 0, "not run": 0}
    assert all(r["error"] == "not run: the cluster had no worker for 6 s" for r in report.failed)
    assert 6.0 <= waited < 60.0
    assert json.loads((tmp_path / "out" / "mesh0.obj.json").read_text())["status"] == "failed"


def test_bad_input_is_refused_before_any_work(meshes, tmp_path):
    out = tmp_path / "out"
    with pytest.raises(BatchInputError, match="no file matches"):
        batch([str(meshes / "*.xyz")], out=out)
    with pytest.raises(BatchInputError, match="would overwrite the input"):
        batch([str(meshes / "mesh1.ply")], out=meshes)
    with pytest.raises(BatchInputError, match="every file found lies inside the output folder"):
        batch([str(meshes)], out=meshes)
    with pytest.raises(meshlab_holefill.FilterParameterError, match="unknown filter 'nope'"):
        batch(meshes, out=out, filter="nope")
    with pytest.raises(meshlab_holefill.FilterParameterError, match="'alpha'.*below the minimum"):
        batch(meshes, out=out, filter=FILTER, alpha=-3)
    bad = tmp_path / "bad.mlx"
    bad.write_text("<FilterScript><filter name='Close Holes'>")
    with pytest.raises(meshlab_holefill.MlxScriptError, match="bad.mlx"):
        batch(meshes, out=out, mlx=bad)
    with pytest.raises(BatchInputError, match="not both"):
        batch(meshes, out=out, filter=FILTER, mlx=bad)
    with pytest.raises(BatchInputError, match="unknown output format"):
        batch(meshes, out=out, format="xyz")
    assert not out.exists()
    assert main(["batch", str(meshes / "*.xyz"), "--out", str(out)]) == 2


def test_outputs_keep_names_and_never_clash(tmp_path):
    (tmp_path / "scans" / "sub").mkdir(parents=True)
    (tmp_path / "other").mkdir()
    for name in ("scans/a.ply", "scans/a.obj", "scans/sub/b.stl", "scans/notes.txt", "other/b.stl"):
        (tmp_path / name).write_text("x")
    items = plan_outputs([str(tmp_path / "scans")], tmp_path / "out", format="ply")
    assert sorted(i.name for i in items) == ["a_obj.ply", "a_ply.ply", os.path.join("sub", "b.ply")]
    items = plan_outputs([str(tmp_path / "scans")], tmp_path / "scans" / "sub")  # earlier outputs are not inputs
    assert sorted(i.name for i in items) == ["a.obj", "a.ply"]
    with pytest.raises(BatchInputError, match="would both be written"):
        plan_outputs([str(tmp_path / "scans" / "sub"), str(tmp_path / "other")], tmp_path / "out2")
