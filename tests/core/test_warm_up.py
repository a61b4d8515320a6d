"""Every compiled kernel a fill and its checks call is loaded before the first hole's clock starts.

A kernel loaded lazily inside a fill costs the first hole of every process (and every forked
worker) tens of milliseconds; a kernel called with argument types its warm-up did not use (a
read-only array, another integer width) is loaded a second time. Each filter runs in a fresh
process, where nothing is loaded yet.
"""
import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent('''
    import gc
    import numpy as np
    from numba.core.registry import CPUDispatcher
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core import pipeline
    from meshlab_holefill.core.examples import bowl_with_hole

    def overloads():
        return {id(d): (d, len(d.overloads)) for d in gc.get_objects() if isinstance(d, CPUDispatcher)}

    first_context, before = pipeline.hole_context, []

    def hole_context(*args, **kwargs):  # the first hole's clock starts here
        if not before:
            before.append(overloads())
        return first_context(*args, **kwargs)

    pipeline.hole_context = hole_context
    V, F, _ = bowl_with_hole(n=25, radius=0.45)
    V[:, 2] += 0.05 * np.sin(4.0 * V[:, 0]) * np.cos(3.0 * V[:, 1])
    F = F[np.linalg.norm(V[F].mean(axis=1)[:, :2] - [0.7, 0.7], axis=1) > 0.15]
    _, _, info = fill_holes(V, F, ALGORITHM, workers=1)
    assert info["closed_holes"] == 2, info
    for key, (dispatcher, count) in overloads().items():
        if before[0].get(key, (None, 0))[1] < count and dispatcher.py_func.__module__.startswith("meshlab_holefill"):
            print(f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__name__}")
''')


@pytest.mark.parametrize("algorithm", ["min_angle_bilateral", "curve_unfolding", "lssvm_poisson",
                                       "differential_evolution"])
def test_no_kernel_is_loaded_within_the_fills(algorithm):
    run = subprocess.run([sys.executable, "-c", f"ALGORITHM = {algorithm!r}\n" + SCRIPT], capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert run.stdout.split() == [], f"loaded within the fills: {run.stdout.split()}"
