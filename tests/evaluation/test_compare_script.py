"""compare() from a plain script: no ``if __name__ == "__main__":`` guard needed."""
from __future__ import annotations

import json
import multiprocessing
import subprocess
import sys
import textwrap

import pytest

from meshlab_holefill.evaluation.isolation import IsolatedRunner, check_not_bootstrapping

SCRIPT = textwrap.dedent("""
    import json
    import pymeshlab
    import meshlab_holefill

    print("TOP LEVEL RUN")  # printed once: the workers do not re-run this script
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    m = ms.current_mesh()
    result = meshlab_holefill.compare([(m.vertex_matrix(), m.face_matrix())], holes=1, sizes=("small",),
                                      filters="meshing_close_holes:maxholesize=all,min_angle_bilateral",
                                      progress=False)
    print("RUNS " + json.dumps([[r["filler"], r["status"], r["error"]] for r in result.runs]))
""")


def test_compare_at_a_scripts_top_level(tmp_path):
    # Before: multiprocessing's spawn re-ran this script in each worker, which then tried to start
    # workers itself and died: every run "crashed: worker process died (exit code 1)".
    script = tmp_path / "plain_script.py"
    script.write_text(SCRIPT)
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("TOP LEVEL RUN") == 1, proc.stdout
    runs = json.loads(next(line for line in proc.stdout.splitlines() if line.startswith("RUNS "))[5:])
    assert len(runs) == 2
    assert all(status == "ok" for _, status, _ in runs), runs


def test_compare_inside_a_multiprocessing_bootstrap_names_the_guard(monkeypatch):
    # Where compare() cannot work (the caller's own unguarded multiprocessing child importing the
    # script), it fails at once and names the guard.
    monkeypatch.setattr(multiprocessing.current_process(), "_inheriting", True, raising=False)
    with pytest.raises(RuntimeError, match=r'if __name__ == "__main__":'):
        check_not_bootstrapping()
    with pytest.raises(RuntimeError, match="multiprocessing was starting a child process"):
        IsolatedRunner()
