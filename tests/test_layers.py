"""The package's layers: no import cycle (function-level imports included), pymeshlab only in meshlab/."""
import ast
import os
import subprocess
import sys

import meshlab_holefill

PACKAGE_DIR = os.path.dirname(meshlab_holefill.__file__)
LAYERS = ["errors", "_version", "geometry", "core", "algorithms", "array_api", "meshlab", "evaluation", "batching", "cli"]


def _modules():
    """Every module of the package: dotted name -> (path, is_package)."""
    out = {}
    for folder, _, files in os.walk(PACKAGE_DIR):
        for name in files:
            if name.endswith(".py"):
                rel = os.path.relpath(os.path.join(folder, name), os.path.dirname(PACKAGE_DIR))[:-3]
                dotted = rel.replace(os.sep, ".")
                is_package = dotted.endswith(".__init__")
                out[dotted[: -len(".__init__")] if is_package else dotted] = (os.path.join(folder, name), is_package)
    return out


def _imports(module, path, is_package, modules):
    """The package modules that ``module`` imports anywhere in its body (functions included)."""
    tree = ast.parse(open(path, encoding="utf-8").read())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".") if is_package else module.split(".")[:-1]
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            # "from package import submodule" imports the submodule, not the package's __init__
            names = [f"{target}.{alias.name}" if f"{target}.{alias.name}" in modules else target
                     for alias in node.names]
        else:
            continue
        found.update(name for name in names if name in modules and name != module)
    return found


def _graph():
    modules = _modules()
    return {name: _imports(name, path, is_package, modules) for name, (path, is_package) in modules.items()}


def _cycles(graph):
    """Strongly connected components with more than one module (Tarjan), or a module importing itself."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return out


def test_the_cycle_finder_finds_a_cycle_through_a_function_level_import():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_of_the_package_takes_part_in_an_import_cycle():
    assert _cycles(_graph()) == []


def _layer(module):
    parts = module.split(".")
    return LAYERS.index(parts[1]) if len(parts) > 1 else len(LAYERS)


def test_every_import_points_to_the_same_or_a_lower_layer():
    upward = [(a, b) for a, targets in _graph().items() for b in targets
              if a != "meshlab_holefill" and _layer(b) > _layer(a)]
    assert upward == []


def test_only_the_meshlab_package_imports_pymeshlab():
    importers = []
    for name, (path, _) in _modules().items():
        tree = ast.parse(open(path, encoding="utf-8").read())
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else [])
            if any(n == "pymeshlab" or n.startswith("pymeshlab.") for n in names):
                importers.append(name)
    assert importers and all(name.startswith("meshlab_holefill.meshlab") for name in importers), importers


PYMESHLAB_BLOCKED = """
import sys
sys.modules["pymeshlab"] = None
import numpy as np
import meshlab_holefill
from conftest_free import holed_sphere
V, F = holed_sphere()
for name in meshlab_holefill.algorithm_names():
    V2, F2, result = meshlab_holefill.fill_holes(V, F, algorithm=name)
    print(name, result["closed_holes"], len(V2) - len(V), len(F2) - len(F))
try:
    meshlab_holefill.apply_filter(None, "meshing_close_holes")
except ImportError as exc:
    print("ImportError:", exc)
print("pymeshlab loaded:", sys.modules["pymeshlab"] is not None)
"""

SPHERE = '''
import numpy as np
from scipy.spatial import ConvexHull


def holed_sphere(n=400, holes=((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)), radius=0.45):
    """A unit sphere (convex hull of a Fibonacci point set) with two caps removed."""
    i = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
    V = np.c_[np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
    F = ConvexHull(V).simplices
    F = np.where((np.einsum("ij,ij->i", np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                            V[F].mean(axis=1)) < 0)[:, None], F[:, ::-1], F)
    keep = np.ones(len(F), bool)
    for c in holes:
        keep &= np.linalg.norm(V[F].mean(axis=1) - np.asarray(c), axis=1) > radius
    return V, F[keep]
'''


def test_without_pymeshlab_the_array_api_fills_a_holed_sphere_with_every_algorithm(tmp_path):
    (tmp_path / "conftest_free.py").write_text(SPHERE)
    out = subprocess.run([sys.executable, "-c", PYMESHLAB_BLOCKED], cwd=tmp_path, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(tmp_path)}, timeout=300)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    rows = [line.split() for line in lines if line.split()[0] in meshlab_holefill.algorithm_names()]
    assert [row[0] for row in rows] == meshlab_holefill.algorithm_names()
    for name, closed, new_vertices, new_faces in rows:
        assert (int(closed), int(new_faces) > 0) == (2, True), name
    assert any(line.startswith("ImportError:") and "needs pymeshlab" in line for line in lines)
    assert lines[-1] == "pymeshlab loaded: False"
