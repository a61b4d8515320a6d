"""evaluation.comparison: prepared cases (ground truth, island outlines), fillers, failing runs, patch info."""
from __future__ import annotations

import numpy as np
import pytest

import meshlab_holefill
from meshlab_holefill.core.holes import boundary_halfedges, boundary_loops
from meshlab_holefill.core.outlines import outline_mask, outline_ratios
from meshlab_holefill.evaluation.comparison import (Filler, MeshCase, _patch_info, as_case, parse_fillers, prepare_case,
                                                    run_comparison)
from meshlab_holefill.meshlab.mesh_files import load_mesh, meshset_from_arrays

from conftest import sample
from evaluation_meshes import grid, sphere


def test_prepared_ground_truth_closes_the_mesh():
    V, F = sphere(4)
    case = prepare_case(MeshCase("s", V, F), holes=2, sizes=("small", "medium"), seed=1)
    assert case.kind == "cut holes" and len(case.holes) == 2
    for hole in case.holes:
        gV, gF = hole.ground_truth
        assert np.allclose(gV[: len(case.V0)], case.V0)
        he, _ = boundary_halfedges(np.concatenate([case.F0, gF]))
        assert not np.isin(he, hole.loop).all(axis=1).any()  # the ground truth closes its hole exactly


def test_given_holes_that_remove_nothing_are_refused_by_name():
    V, F = sphere(2)
    with pytest.raises(ValueError, match="case 'empty': removed marks no face"):
        prepare_case(MeshCase("empty", V, F, removed=np.zeros(len(F), bool)))


def test_parse_fillers():
    fillers = parse_fillers("min_angle_bilateral:iterations=2:fairing=none,meshing_close_holes:maxholesize=all,"
                            "refinehole=true")
    assert fillers[0].filter == "meshing_close_holes_min_angle_bilateral"
    assert fillers[0].params == {"iterations": 2, "fairing": "none"}
    assert fillers[1].params == {"maxholesize": "all", "refinehole": True}
    default = parse_fillers(None)
    assert {f.filter for f in default} == set(meshlab_holefill.filter_list()) | {"meshing_close_holes", "cgal_liepa", "pymeshfix"}
    assert len(parse_fillers(None, refinehole=True)) == len(default) + 1
    with pytest.raises(ValueError, match="unknown filter 'no_such_filter'"):
        parse_fillers("no_such_filter")


def test_failing_filter_is_reported_and_others_run():
    V, F = sphere(3)
    fillers = [Filler("broken", "meshing_close_holes_min_angle_bilateral", {"no_such_param": 1}),
               Filler("close all", "meshing_close_holes", {"maxholesize": "all"})]
    result = run_comparison([MeshCase("s", V, F)], holes=2, sizes=("small",), filters=fillers, progress=False)
    runs = {r["filler"]: r for r in result.runs}
    assert runs["broken"]["status"] == "error" and "no_such_param" in runs["broken"]["error"]
    assert runs["close all"]["status"] == "ok" and runs["close all"]["closed_holes"] == 2
    assert all(not r["closed"] and r["reason"].startswith("error") for r in result.holes if r["filler"] == "broken")


def test_patch_info_becomes_info_columns():
    entry = {"hole": 3, "status": "closed", "seconds": 0.1, "new_faces": 9, "restarts": 2,
             "unfolding_seconds": 0.01, "method": "annealed", "history": [1, 2]}
    assert _patch_info(entry) == {"info_restarts": 2, "info_unfolding_seconds": 0.01, "info_method": "annealed"}
    assert _patch_info(None) == {}


def test_outline_ratios_separate_islands_from_holes():
    V, F = grid(12)
    centre = V[F].mean(axis=1)
    F = F[~np.all(np.abs(centre[:, :2] - 6.0) < 2.0, axis=1)]  # an interior hole
    k = len(V)
    V = np.concatenate([V, [[20, 0, 0], [21, 0, 0], [20, 1, 0]]])
    F = np.concatenate([F, [[k, k + 1, k + 2]]])  # a lone triangle (its outline is no hole)
    loops = boundary_loops(F)
    ratios = outline_ratios(V, F, loops)
    by_size = {len(lp): r for lp, r in zip(loops, ratios)}
    assert by_size[16] < 0.2  # the hole: 16 of 144 - 16 cells
    assert by_size[48] > 0.75  # the grid's own border outlines its component
    assert by_size[3] == pytest.approx(1.0)
    assert [len(lp) for lp, outline in zip(loops, outline_mask(V, F, loops)) if outline] == [48, 3]


def test_sphere_cap_hole_is_not_an_outline():
    V, F = sphere(3)
    F = F[V[F].mean(axis=1)[:, 2] < 0.7]
    assert outline_ratios(V, F, boundary_loops(F))[0] < 0.2



def test_as_case_reads_paths_meshes_meshsets_and_arrays():
    V, F = load_mesh(sample("bone.ply"))
    ms = meshset_from_arrays(V, F)
    cases = [as_case(sample("bone.ply")), as_case(ms, 1), as_case(ms.current_mesh(), 2), as_case((V, F.tolist()), 3)]
    assert [c.name for c in cases] == ["bone.ply", "mesh1", "mesh2", "mesh3"]
    for c in cases:
        assert np.array_equal(c.V, V) and np.array_equal(c.F, F) and c.F.dtype == np.int64
    with pytest.raises(TypeError, match="cannot compare on"):
        as_case(42)
