"""Curve unfolding, stage by stage: edge ratio and minimum quality after each step of the filter.

For each hole cut with ground truth (as ``scripts/benchmark.py`` cuts them) the filter's own
``fill`` runs with its steps observed: the planar refinement (Sec. 3.3, in the plane, lengths
against the surrounding mean edge), the energy solve (E_AREA / E_DF), the tangential relaxation,
the swaps and the final patch (after the sliver repair). Printed per hole, with the minimum
quality the hole's corners force (``corner_quality_bound``) and the patch-to-ground-truth mean
distance (per mille of the bounding-box diagonal); means at the end.

    .venv/bin/python scripts/curve_unfolding_stages.py [--cases bunny.obj,sphere] [--holes 4] [--seed 0]
        [--param name=value ...]
"""
from __future__ import annotations

import argparse
import importlib.util
import os
import sys

import numpy as np

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.evaluation.comparison import prepare_case
from meshlab_holefill.evaluation.metrics import hausdorff_one_way
from meshlab_holefill.geometry.quality import edge_lengths, triangle_quality

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("benchmark", os.path.join(HERE, "benchmark.py"))
benchmark = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(benchmark)

STAGES = ("planar", "solve", "tangential", "final")


def _ratio_quality(X, F, reference):
    return float(edge_lengths(X, F).mean() / reference), float(triangle_quality(X, F).min())


def run_hole(V0, F0, hole, diag, params):
    loops = boundary_loops(F0)
    ctx = hole_context(V0, F0, loops[hole.loop_index], rings=cu.RINGS)
    near = np.flatnonzero(np.isin(F0, hole.loop).any(axis=1))
    reference = float(edge_lengths(V0, F0[near]).mean())
    seen, builds = {}, []
    original_refine, original_embed, original_tae = tri.refine_planar, tri.embed_patch, cu.triangulate_and_embed

    def refine(Q, edge_length, forbidden_chords=(), **kw):
        points, F = original_refine(Q, edge_length, forbidden_chords, **kw)
        builds.append({"planar": _ratio_quality(np.c_[points, np.zeros(len(points))], F, reference)})
        return points, F

    def embed(ctx_, s, F, energy="fairing", boundary=None, extra_faces=None, tangential=False):
        X = original_embed(ctx_, s, F, energy=energy, boundary=boundary, extra_faces=extra_faces)
        if builds:
            builds[-1]["solve"] = _ratio_quality(np.concatenate([ctx_.points[boundary], X]), F, reference)
        if tangential:
            X = original_embed(ctx_, s, F, energy=energy, boundary=boundary, extra_faces=extra_faces,
                               tangential=True)
        if builds:
            builds[-1]["tangential"] = _ratio_quality(np.concatenate([ctx_.points[boundary], X]), F, reference)
        return X

    def tae(ctx_, Q, keep, ears, *args, **kw):
        del builds[:]
        X, faces = original_tae(ctx_, Q, keep, ears, *args, **kw)
        if not seen and len(keep) == ctx_.size:  # the first domain's patch, stage by stage
            got = _ratio_quality(np.concatenate([ctx_.points, X]), faces, reference)
            for b in builds[::-1]:
                if b.get("tangential") == got:
                    seen.update(b)
                    break
        return X, faces

    tri.refine_planar, tri.embed_patch, cu.triangulate_and_embed = refine, embed, tae
    try:
        patch = cu.fill(ctx, **params)
    finally:
        tri.refine_planar, tri.embed_patch, cu.triangulate_and_embed = original_refine, original_embed, original_tae
    X = np.concatenate([ctx.points, patch.vertices])
    seen["final"] = _ratio_quality(X, patch.faces, reference)
    if hole.ground_truth is None:
        return seen, len(patch.faces), float("nan"), patch.info
    gV, gF = hole.ground_truth
    used = np.unique(gF)
    remap = np.full(len(gV), -1)
    remap[used] = np.arange(len(used))
    d = hausdorff_one_way(X, patch.faces, gV[used], remap[gF])["mean"]
    return seen, len(patch.faces), 1000.0 * d / diag, patch.info


def load_case(name):
    """benchmark.load_case, plus 'bunny_loop': bunny.obj after one Loop subdivision step."""
    if name != "bunny_loop":
        return benchmark.load_case(name)
    import pymeshlab
    from meshlab_holefill.evaluation.comparison import MeshCase
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(benchmark.SAMPLES, "bunny.obj"))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
    m = ms.current_mesh()
    return MeshCase(name, m.vertex_matrix(), m.face_matrix())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="bunny.obj,cow.obj,sphere,torus,airplane.obj,bone.ply")
    ap.add_argument("--holes", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sizes", default="small,medium,large")
    ap.add_argument("--param", action="append", default=[], help="fill() parameter name=value")
    args = ap.parse_args(argv)
    params = {}
    for item in args.param:
        name, value = item.split("=", 1)
        for conv in (int, float):
            try:
                value = conv(value)
                break
            except ValueError:
                pass
        params[name] = {"True": True, "False": False}.get(value, value)
    rows = []
    print(f"{'case':14s} {'hole':>4s} {'edges':>5s} {'bound':>5s} " + " ".join(f"{s:>12s}" for s in STAGES)
          + f" {'faces':>6s} {'dist':>6s}")
    for name in args.cases.split(","):
        prepared = prepare_case(load_case(name), holes=args.holes, seed=args.seed, sizes=args.sizes.split(","))
        for hole in prepared.holes:
            try:
                seen, faces, dist, info = run_hole(prepared.V0, prepared.F0, hole, prepared.diag, params)
            except Exception as exc:  # a failed hole is reported, not measured
                print(f"{name:14s} {hole.index:4d} {hole.boundary_edges:5d} failed: {exc}", flush=True)
                continue
            cells = " ".join(f"{seen[s][0]:5.3f}/{seen[s][1]:5.3f}" if s in seen else f"{'-':>12s}" for s in STAGES)
            bound = min(0.3, hole.quality_bound)
            print(f"{name:14s} {hole.index:4d} {hole.boundary_edges:5d} {bound:5.3f} {cells} {faces:6d} {dist:6.3f}"
                  + (" repaired" if info.get("ears_clipped") or info.get("unfolding") == "development" else "")
                  + (f" slivers:{info['sliver_rounds']}" if info.get("sliver_rounds") else "")
                  + (" CROSSES" if info.get("crossing_faces") else ""),
                  flush=True)
            rows.append((seen, bound, dist, faces))
    for s in STAGES:
        r = [x[0][s] for x in rows if s in x[0]]
        if r:
            unforced = [x[0][s][1] for x in rows if s in x[0] and x[1] >= 0.1]
            print(f"{s:11s} edge ratio mean {np.mean([a for a, _ in r]):.3f} "
                  f"[{min(a for a, _ in r):.3f}, {max(a for a, _ in r):.3f}]  min quality "
                  f"{min(b for _, b in r):.3f} (holes whose bound >= 0.1: {min(unforced) if unforced else float('nan'):.3f})")
    print(f"mean distance {np.nanmean([x[2] for x in rows]):.4f} per mille, faces {sum(x[3] for x in rows)}")


if __name__ == "__main__":
    sys.exit(main())
