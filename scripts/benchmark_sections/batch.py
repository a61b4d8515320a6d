"""Batch throughput: files per minute of meshlab_holefill.batch on a LocalCluster."""
from __future__ import annotations

import os
import time

import meshlab_holefill
import pymeshlab

from .cases import SAMPLES


def batch_throughput(out, files=24, workers=(1, 2)):
    """Files per minute of ``meshlab_holefill.batch`` on a running LocalCluster of 1 and 2 workers.

    The files are copies of the bunny scan (bunny10k_textured.obj, 5 natural holes) saved as
    ply; each filled with ``meshing_close_holes_min_angle_bilateral`` at its defaults. The
    cluster is started and warmed up (every worker has imported the package) before the clock
    runs, so the figure is the steady rate; the start-up is reported beside it.

    Returns
    -------
    str
        A markdown table: workers, files, seconds, files per minute, speed-up over 1 worker,
        cluster start-up seconds.
    """
    import shutil

    import dask
    from distributed import Client, LocalCluster

    from meshlab_holefill.batching._run import LOCAL_CLUSTER_CONFIG

    src = os.path.join(out, "batch_inputs")
    os.makedirs(src, exist_ok=True)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "bunny10k_textured.obj"))
    for i in range(files):
        ms.save_current_mesh(os.path.join(src, f"bunny_{i:03d}.ply"))
    rows = []
    for n in workers:
        t0 = time.perf_counter()
        with dask.config.set(LOCAL_CLUSTER_CONFIG):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, dashboard_address=":0")
        with cluster, Client(cluster) as client:
            client.run(lambda: __import__("meshlab_holefill.batching._task"))
            startup = time.perf_counter() - t0
            dest = os.path.join(out, f"batch_{n}_workers")
            shutil.rmtree(dest, ignore_errors=True)
            t0 = time.perf_counter()
            report = meshlab_holefill.batch(src, dest, client=client, progress=False)
            seconds = time.perf_counter() - t0
        assert report.counts["ok"] == files, report.counts
        rows.append((n, seconds, startup))
    base = rows[0][1]
    lines = ["| workers | files | seconds | files per minute | speed-up | cluster start-up (s) |",
             "|---|---|---|---|---|---|"]
    lines += [f"| {n} | {files} | {sec:.1f} | {60 * files / sec:.0f} | {base / sec:.2f} | {start:.1f} |"
              for n, sec, start in rows]
    return "\n".join(lines)
