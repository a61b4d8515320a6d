"""evaluation.anchors: CGAL's Liepa fill and MeshFix as comparison fillers, mapped back to the original numbering,
selected by --filters, skipped with a note when their package is missing."""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.evaluation import anchors
from meshlab_holefill.evaluation.anchors import (cgal_fill, map_back, missing_package, pymeshfix_fill,
                                                 split_nonmanifold_vertices)
from meshlab_holefill.evaluation.comparison import MeshCase, parse_fillers, run_comparison
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.metrics import compact_mesh, mesh_checks
from meshlab_holefill.evaluation.report.tables import failures, report_blocks, to_markdown

from evaluation_meshes import sphere

needs_cgal = pytest.mark.skipif(importlib.util.find_spec("CGAL") is None, reason="cgal not installed")
needs_meshfix = pytest.mark.skipif(importlib.util.find_spec("pymeshfix") is None, reason="pymeshfix not installed")


def holed_sphere(sizes=("small", "medium"), seed=0):
    V, F = sphere(4)
    F0, holes = cut_holes(V, F, sizes=sizes, seed=seed)
    V0, F0 = compact_mesh(V, F0)
    return V0, F0


@needs_cgal
def test_cgal_fills_each_hole_alone_originals_first():
    V0, F0 = holed_sphere()
    V1, F1, result = cgal_fill(V0, F0)
    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)
    checks = mesh_checks(V0, F0, V1, F1)
    assert checks["boundary_edges_left"] == 0 and checks["nonmanifold_edges"] == 0
    assert checks["intersecting_new_faces"] == 0
    assert [h["status"] for h in result["holes"]] == ["closed", "closed"]
    assert all(h["seconds"] >= 0 and h["new_faces"] > 0 for h in result["holes"])
    assert sum(h["new_faces"] for h in result["holes"]) == len(F1) - len(F0)
    # new vertices lie close to the unit sphere (the fair patch follows the surface)
    assert np.abs(np.linalg.norm(V1[len(V0):], axis=1) - 1).max() < 0.05


@needs_cgal
def test_cgal_maxholesize_and_parameter_errors():
    V0, F0 = holed_sphere()
    sizes = sorted(len(lp) for lp in boundary_loops(F0))
    V1, F1, result = cgal_fill(V0, F0, maxholesize=sizes[1])
    assert sorted(h["status"] for h in result["holes"]) == ["closed", "skipped"]
    assert len(boundary_loops(F1)) == 1
    with pytest.raises(ValueError, match="continuity must be 0, 1 or 2"):
        cgal_fill(V0, F0, continuity=3)
    with pytest.raises(ValueError, match="density must be positive"):
        cgal_fill(V0, F0, density=0.0)


@needs_cgal
def test_cgal_pinched_loops_fail_with_the_reason():
    V, F = sphere(3)
    # two faces that share only one vertex: removing both leaves two 3-edge loops pinched at it
    v = F[0, 0]
    at = np.flatnonzero((F == v).any(axis=1))
    other = next(f for f in at if len(np.intersect1d(F[f], F[0])) == 1)
    keep = np.ones(len(F), bool)
    keep[[0, other]] = False
    V0, F0 = V, F[keep]
    assert len(boundary_loops(F0)) == 2
    V1, F1, result = cgal_fill(V0, F0)
    # split by fans, the pinched vertex joins the two loops into one 6-edge border cycle in CGAL's mesh
    assert [h["status"] for h in result["holes"]] == ["failed", "failed"]
    assert all("pinched loop" in h["reason"] for h in result["holes"])
    assert np.array_equal(F1, F0) and np.array_equal(V1, V0)


def test_split_nonmanifold_vertices_gives_each_fan_its_vertex():
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 5]])  # vertex 0: a fan of two faces and a lone face
    Fs, origin = split_nonmanifold_vertices(F, 6)
    assert Fs[0, 0] == Fs[1, 0] != Fs[2, 0] and origin[Fs[2, 0]] == 0 and len(origin) == 7
    assert np.array_equal(origin[Fs], F)
    Fm, origin = split_nonmanifold_vertices(sphere(2)[1], len(sphere(2)[0]))
    assert np.array_equal(Fm, sphere(2)[1]) and len(origin) == len(sphere(2)[0])


@needs_meshfix
def test_pymeshfix_output_mapped_back_to_original_numbering():
    V0, F0 = holed_sphere()
    V1, F1, result = pymeshfix_fill(V0, F0)
    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)
    assert result["originals_removed"] == 0 and result["vertices_dropped"] == 0 and result["closed_holes"] == 2
    checks = mesh_checks(V0, F0, V1, F1)
    assert checks["boundary_edges_left"] == 0 and checks["nonmanifold_edges"] == 0
    with pytest.raises(ValueError, match="mode must be 'fill' or 'repair'"):
        pymeshfix_fill(V0, F0, mode="smooth")


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2 ** 31 - 1), drop=st.integers(0, 3))
def test_map_back_undoes_any_renumbering(seed, drop):
    V, F = sphere(2)
    rng = np.random.default_rng(seed)
    V0, F0 = V[:-1], F[~(F == len(V) - 1).any(axis=1)]  # an original mesh with a hole around the last vertex
    new = F[(F == len(V) - 1).any(axis=1)]
    # a filler's output: everything renumbered, faces shuffled and rotated, ``drop`` original faces deleted
    perm = rng.permutation(len(V))
    inv = np.argsort(perm)
    out_faces = np.concatenate([F0[drop:], new])
    out_faces = np.roll(out_faces, rng.integers(3), axis=1)[rng.permutation(len(out_faces))]
    V1, F1, info = map_back(V0, F0, V[perm], inv[out_faces])
    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)
    assert info["originals_removed"] == drop
    assert len(V1) == len(V) and np.allclose(V1[-1], V[-1])
    canon = lambda A: {tuple(np.roll(f, -int(np.argmin(f)))) for f in A.tolist()}  # noqa: E731
    expect = np.where(new == len(V) - 1, len(V0), new)
    assert canon(F1[len(F0):]) == canon(expect)


def test_parse_fillers_selects_anchors_by_name():
    fillers = parse_fillers("cgal_liepa:continuity=2,pymeshfix")
    assert [(f.filter, f.params) for f in fillers] == [("cgal_liepa", {"maxholesize": "all", "continuity": 2}),
                                                       ("pymeshfix", {"maxholesize": "all"})]
    assert [f.filter for f in parse_fillers("anchors")] == ["cgal_liepa", "pymeshfix"]
    with pytest.raises(ValueError, match="third-party: cgal_liepa, pymeshfix"):
        parse_fillers("cgal")


def test_missing_package_skips_with_a_note(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(anchors.importlib.util, "find_spec", lambda name, *a: None if name == "CGAL" else real(name, *a))
    assert "package 'cgal' not installed" in missing_package("cgal_liepa")
    result = run_comparison([MeshCase("s", *sphere(3))], holes=1, sizes=("small",), filters="cgal_liepa",
                            progress=False)
    assert result.runs[0]["status"] == "skipped"
    assert [r["closed"] for r in result.holes] == [False]
    lines = failures(result)
    assert len(lines) == 1 and "not installed" in lines[0]  # one note, not one per hole
    assert "Skipped (package not installed): `cgal_liepa`" in to_markdown(report_blocks(result, []))


@needs_cgal
@needs_meshfix
def test_anchors_in_a_comparison_are_measured_like_the_others():
    result = run_comparison([MeshCase("s", *sphere(4))], holes=2, sizes=("small", "medium"),
                            filters="anchors,meshing_close_holes:maxholesize=all", progress=False)
    assert {r["filler"]: r["status"] for r in result.runs} == {
        "cgal_liepa": "ok", "pymeshfix": "ok", "meshing_close_holes (maxholesize=all)": "ok"}
    by = {}
    for r in result.holes:
        assert r["closed"] and r["intersecting_new_faces"] == 0 and r["originals_changed"] == 0
        by.setdefault(r["filler"], []).append(r["dist_patch_to_gt_mean_permille"])
    assert all(r.get("seconds") is not None for r in result.holes if r["filler"] == "cgal_liepa")
    # Liepa's faired patches follow the sphere: closer than MeshLab's flat fill
    assert np.mean(by["cgal_liepa"]) < np.mean(by["meshing_close_holes (maxholesize=all)"])
