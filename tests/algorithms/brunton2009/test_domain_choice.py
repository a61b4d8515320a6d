"""Curve unfolding, domain='smoothest' (beyond the paper): the patch of the domain that bends least."""

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill import HoleFillError
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009.domain_choice import DOMAINS, smoothest_patch
from meshlab_holefill.evaluation.comparison import prepare_case
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core import examples
from meshlab_holefill.core.border_bend import border_bend
from meshlab_holefill.core.patch import Patch

from conftest import cut_disks, grid, mesh_arrays, sample, sphere_with_holes


def _bent_sheet_hole():
    """A round hole across the fold of a sheet bent by 90 degrees (a crease through the hole)."""
    V, F = grid(25, 25)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.3)
    up = V[:, 1] > 0.5
    V = np.c_[V[:, 0], np.where(up, 0.5, V[:, 1]), np.where(up, V[:, 1] - 0.5, 0.0)]
    return hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)


def test_smoothest_is_the_whole_fill_of_the_domain_whose_patch_bends_less():
    ctx = _bent_sheet_hole()
    chosen = cu.fill(ctx, domain="smoothest")
    own = {domain: cu.fill(ctx, domain=domain) for domain in DOMAINS}
    bends = chosen.info["border_bends"]
    for domain, patch in own.items():
        assert bends[domain] == border_bend(ctx, patch.vertices, patch.faces)
    winner = min(DOMAINS, key=bends.get)
    assert chosen.info["domain"] == winner
    assert np.array_equal(chosen.vertices, own[winner].vertices) and np.array_equal(chosen.faces, own[winner].faces)
    assert examples.is_disc_patch(chosen, ctx)


@pytest.mark.parametrize("name", ["creased_box", "bevelled_box", "cylinder_rims", "union"])
def test_smoothest_patches_of_cad_like_holes_are_no_farther_than_either_domains(name):
    """Coarse versions of the benchmark's creased cases, every hole crossed by a crease or rim: the kept
    patches' new vertices are as close to the removed surface as the better domain's, or closer."""
    from meshlab_holefill.array_api import fill_holes
    from meshlab_holefill.evaluation.creased import creased_case
    from meshlab_holefill.evaluation.metrics import closest_faces

    case = prepare_case(creased_case(name, 0.08))
    truths = [h.ground_truth for h in case.holes]

    def distance(domain):
        V, F, result = fill_holes(case.V0, case.F0, "curve_unfolding", domain=domain, workers=1)
        assert result["closed_holes"] == len(case.holes)
        new = V[len(case.V0):]
        return np.min([closest_faces(new, gV, gF)[0] for gV, gF in truths], axis=0).mean()

    d = {domain: distance(domain) for domain in ("unfolding", "development", "smoothest")}
    assert d["smoothest"] <= min(d["unfolding"], d["development"]) + 1e-12


def test_smoothest_keeps_the_unfolding_where_it_continues_a_curved_surface_better():
    # A large hole of a sphere: the development of a long loop on a curved surface drifts.
    V, F, _ = sphere_with_holes(subdiv=4, centers=((0, 0, 1),), radius=0.8)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=cu.RINGS)
    chosen = cu.fill(ctx, domain="smoothest")
    bends = chosen.info["border_bends"]
    assert chosen.info["domain"] == "unfolding" and bends["unfolding"] < bends["development"]
    unfolded = cu.fill(ctx, domain="unfolding")
    assert np.array_equal(chosen.vertices, unfolded.vertices) and np.array_equal(chosen.faces, unfolded.faces)
    # and it is the closer patch to the sphere
    developed = cu.fill(ctx, domain="development")
    off = {name: np.abs(np.linalg.norm(p.vertices, axis=1) - 1).mean() for name, p in
           (("unfolding", unfolded), ("development", developed))}
    assert off["unfolding"] < off["development"]


def _sphere_without(z_below):
    """pymeshlab's unit sphere (subdiv 3) keeping only the faces whose centroids lie below z = ``z_below``."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    m = ms.current_mesh()
    V, F = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
    F = F[V[F].mean(axis=1)[:, 2] < z_below]
    return hole_context(V, F, boundary_loops(F)[0], rings=cu.RINGS)


def test_the_development_competes_only_for_a_loop_round_less_than_a_full_turn_of_curvature():
    from meshlab_holefill.algorithms.brunton2009.domain_choice import development_is_candidate
    from meshlab_holefill.geometry.development import boundary_gap_angles, enclosed_curvature

    m = 12
    for K, competes in ((2 * np.pi - 0.05, True), (2 * np.pi + 0.05, False), (-2 * np.pi - 0.05, False), (0.0, True)):
        gaps = np.full(m, ((m - 2) * np.pi + K) / m)
        assert enclosed_curvature(gaps) == pytest.approx(K) and development_is_candidate(gaps) == competes
    # More than a hemisphere removed (K = 2 pi (1 + 0.3) = 8.2): the unfolding alone, filled once.
    ctx = _sphere_without(-0.3)
    assert enclosed_curvature(boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)) > 2 * np.pi
    chosen = cu.fill(ctx, domain="smoothest")
    unfolded = cu.fill(ctx, domain="unfolding")
    assert chosen.info["domain"] == "unfolding" and "border_bends" not in chosen.info
    assert np.array_equal(chosen.vertices, unfolded.vertices) and np.array_equal(chosen.faces, unfolded.faces)
    # Less than a hemisphere (K = 4.4): both domains compete.
    assert "border_bends" in cu.fill(_sphere_without(0.3), domain="smoothest").info


def _flat_fan(ctx, height=0.0, crossing=0):
    k = ctx.size
    centre = ctx.points.mean(axis=0, keepdims=True) + [0, 0, height]
    return Patch(vertices=centre, faces=np.array([[k, i, (i + 1) % k] for i in range(k)]),
                 info={"crossing_faces": crossing})


def test_smoothest_prefers_a_patch_that_crosses_nothing_and_survives_one_failed_domain():
    V, F = grid(9, 9)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.25)
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=2)
    flat, lifted = _flat_fan(ctx), _flat_fan(ctx, height=0.3)
    assert smoothest_patch(ctx, {"unfolding": lifted, "development": flat}.get).info["domain"] == "development"
    flat_crossing = _flat_fan(ctx, crossing=2)
    assert smoothest_patch(ctx, {"unfolding": lifted, "development": flat_crossing}.get).info["domain"] == "unfolding"

    def development_fails(domain):
        if domain == "development":
            raise HoleFillError("no domain")
        return lifted

    kept = smoothest_patch(ctx, development_fails)
    assert kept.info["domain"] == "unfolding" and kept.info["border_bends"]["development"] is None

    def both_fail(domain):
        raise HoleFillError(f"{domain} failed")

    with pytest.raises(HoleFillError, match="unfolding failed"):
        smoothest_patch(ctx, both_fail)


def large_hole(name, seed, hole):
    """(V, F, HoleContext) of one hole of ``scripts/large_holes.py``: the sample Loop-subdivided twice, that hole cut."""
    from meshlab_holefill.core.holes import boundary_loops, hole_context
    from meshlab_holefill.evaluation.cut_holes import cut_holes

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample(name))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=["irregular", "irregular", "large"], seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[holes[hole].face_indices] = True
    F = F[~removed]
    return V, F, hole_context(V, F, max(boundary_loops(F), key=len), rings=cu.RINGS)


def test_where_the_unfolding_is_the_development_the_smoothest_domain_fills_the_hole_once(monkeypatch):
    """A 154-edge hole of bone.ply Loop-subdivided twice (``scripts/large_holes.py``, seed 1): the annealing
    gives up and falls back to the development, so both domains are one; the second is not filled again."""
    _, _, ctx = large_hole("bone.ply", seed=1, hole=2)
    unfolding, development = cu.fill(ctx, domain="unfolding"), cu.fill(ctx, domain="development")
    assert unfolding.info["unfolding"] == "development"  # the annealing's fallback
    assert np.array_equal(unfolding.vertices, development.vertices)
    calls = []
    embed = cu.triangulate_and_embed
    monkeypatch.setattr(cu, "triangulate_and_embed", lambda *a, **kw: calls.append(1) or embed(*a, **kw))
    patch = cu.fill(ctx)
    once = len(calls)
    calls.clear()
    cu.fill(ctx, domain="unfolding")
    assert once == len(calls) > 0
    assert np.array_equal(patch.vertices, unfolding.vertices) and np.array_equal(patch.faces, unfolding.faces)
    assert patch.info["domain"] == "unfolding" and patch.info["sa_steps"] == unfolding.info["sa_steps"]
