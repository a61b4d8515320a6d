"""The one-time cost of compiling the kernels, cold (empty numba cache) and warm."""
from __future__ import annotations

import os
import sys
import time



def compile_cost():
    """Cold and warm ``meshlab-holefill compile``: numba's cache empty (a fresh install) and then current.

    Runs the command in a subprocess with ``NUMBA_CACHE_DIR`` pointing at an empty temporary folder,
    twice; each filter's process seconds come from the command's table, the wall seconds from here.
    """
    import subprocess
    import tempfile

    rows, columns = {}, []
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for run in ("cold (empty cache)", "warm (cache current)"):
            t = time.perf_counter()
            out = subprocess.run([sys.executable, "-m", "meshlab_holefill.cli", "compile"], env=env, check=True,
                                 capture_output=True, text=True).stdout
            columns.append((run, time.perf_counter() - t))
            for line in out.splitlines():
                label, seconds = line.rsplit(None, 2)[0].strip(), float(line.rsplit(None, 2)[1])
                rows.setdefault(label, []).append(seconds)
    header = ["filter"] + [f"{run}: process s" for run, _ in columns]
    table = [[f"`{label}`"] + [f"{x:.1f}" for x in values] for label, values in rows.items()]
    table.append(["whole command, wall s (one process per core)"] + [f"{wall:.1f}" for _, wall in columns])
    return header, table
