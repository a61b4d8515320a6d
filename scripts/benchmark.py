#!/usr/bin/env python
"""Benchmark every registered hole filler against MeshLab's Close Holes: the standard suite.

The suite: pymeshlab's closed sample meshes (bunny.obj, bone.ply, cow.obj, airplane.obj) and
an analytic sphere and torus get holes with ground truth cut (``--holes`` per mesh, sizes
small/medium/large cycling, compact and irregular shapes alternating); the bunny scan's
natural holes (bunny10k_textured.obj) and the face range scan (rangemaps/face000.ply) are
filled as they are; the CAD-like cases of ``evaluation.creased`` (creased_box, bevelled_box,
cylinder_rims, union: holes a crease runs through; interpenetrating: holes next to where
overlapping parts cross) have their own holes; bunny_212k (the bunny Loop-subdivided once, about
212k faces) has three holes of 150-375 boundary edges with ground truth ("real-size"); cow_noisy (cow.obj
Loop-subdivided twice, about 93k faces, its vertices moved along their normals by Gaussian noise of 0.3 mean
edge lengths, as a range scan's error lies along the line of sight) has four holes of about 20-250 boundary
edges with jagged borders ("noisy"). CGAL's Liepa fill (``cgal_liepa``) and MeshFix
(``pymeshfix``) run as anchors when installed. The report (tables, charts, one picture per hole) goes to ``OUT/suite``.

``--scaling`` adds the scaling run: the same holes (same centres, same boundary sizes) in the
bunny subdivided to about 50k, 200k, 800k and 3M faces, per-hole seconds against mesh size; at the
largest size the min-angle filter and MeshLab's Close Holes run ``--scaling-repeats`` times,
alternating, and the ratio of their median whole runs is reported.
``--papers`` adds the "papers vs. ours" table (Brunton, Hu, Xu, Xie & Zou Table 1).
``--update-readme`` replaces the README's Results section with this run's summary.

    .venv/bin/python scripts/benchmark.py [--filters a,b] [--out bench_out] [--seed 0] [--cases bunny.obj,sphere]
                                          [--scaling] [--papers] [--refusals] [--compile-cost] [--update-readme]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np
import pymeshlab

import meshlab_holefill
from meshlab_holefill.meshlab import load_filter_kernels
from meshlab_holefill.evaluation.analytic import ANALYTIC_SURFACES, analytic_area, analytic_distance, analytic_mesh
from meshlab_holefill.evaluation.comparison import BASELINE, MeshCase, parse_fillers, prepare_case, run_comparison
from meshlab_holefill.evaluation.creased import CREASED_CASES, creased_case
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.isolation import IsolatedRunner
from meshlab_holefill.evaluation.noisy import normal_noise
from meshlab_holefill.evaluation.papers import hpde_sphere
from meshlab_holefill.evaluation.report.labels import filler_colors, short_label
from meshlab_holefill.evaluation.report.tables import markdown_table, summary_blocks, to_markdown
from meshlab_holefill.evaluation.report.write import write_report
from meshlab_holefill.meshlab.mesh_files import load_mesh, mesh_arrays

SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")
CLOSED = ["bunny.obj", "bone.ply", "cow.obj", "airplane.obj", "sphere", "torus"]
NATURAL = ["bunny10k_textured.obj", "face000.ply"]
# CAD-like meshes with holes a crease runs through, and interpenetrating parts (evaluation.creased)
CREASED = list(CREASED_CASES)
# A scan-sized mesh with holes of 200-375 boundary edges (ground truth kept): the bunny Loop-subdivided once
REAL_SIZE = ["bunny_212k"]
# A scan-like mesh: noise along the normals (evaluation.noisy), holes with jagged borders
NOISY = ["cow_noisy"]
NOISE_SIGMA = 0.3  # mean edge lengths
CASES = CLOSED + NATURAL + CREASED + REAL_SIZE + NOISY
REAL_SIZE_HOLES = ("irregular", "large", "irregular")  # targets 250, 150, 250 boundary edges
# Ours with defaults; three measured variants (Xu et al.'s Table 1 membrane comparison, Hu's optional
# fairing as in its filters/ preset, curve unfolding on the paper's unfolded domain alone); MeshLab's Close Holes
# with its defaults and with every hole allowed.
# CGAL's Liepa fill and MeshFix as open anchors (skipped with a note when not installed).
DEFAULT_FILTERS = ("ours,lssvm_poisson:laplacian_prediction=zero:poisson_boundary=dirichlet,min_angle_bilateral:fairing=thinplate:iterations=0:smoothing=10,"
                   "curve_unfolding:domain=unfolding,differential_evolution:layouts=smoothest,anchors,baseline")


def load_case(name):
    """The suite's meshes as MeshCase (analytic distance functions for the sphere and torus)."""
    analytic = area = None
    if name in CREASED_CASES:
        return creased_case(name)
    if name == "bunny_212k":
        return real_size_case()
    if name == "cow_noisy":
        return noisy_case()
    if name in ANALYTIC_SURFACES:
        V, F = analytic_mesh(name)
        analytic, area = analytic_distance(name), analytic_area(name)
    else:
        V, F = load_mesh(os.path.join(SAMPLES, "rangemaps", name) if name == "face000.ply" else os.path.join(SAMPLES, name))
    return MeshCase(name, V, F, analytic=analytic, surface_area=area)


def real_size_case(seed=0):
    """The bunny Loop-subdivided once (about 212k faces) with three holes of 150-375 boundary edges.

    The holes are cut once (``cut_holes``, irregular and compact shapes) and handed to the
    comparison as given holes, so every filler fills the same large holes of a scan-sized mesh.
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "bunny.obj"))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=REAL_SIZE_HOLES, seed=seed)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    return MeshCase("bunny_212k", V, F, removed=removed, given_class="real-size")


def noisy_case(seed=0):
    """cow.obj Loop-subdivided twice (about 93k faces), moved by :func:`normal_noise` (``NOISE_SIGMA``), four holes cut.

    The holes (about 20, 60, 150 and 250 boundary edges) are cut once, after the noise, and handed
    to the comparison as given holes of class "noisy": the ground truth is the noisy surface.
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    V = normal_noise(V, F, NOISE_SIGMA, seed=seed)
    _, holes = cut_holes(V, F, sizes=("small", "medium", "large", "irregular"), seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    return MeshCase("cow_noisy", V, F, removed=removed, given_class="noisy")


# ----------------------------------------------------------------------------- scaling run

SCALING_SIZES = ("small", "medium", "large")
SPEED_CASE_SIZES = ("medium", "large", "irregular")  # targets 60, 150, 250 boundary edges


def scaling_run(fillers, seed=0, levels=4, timeout=600.0, out=None, sizes=SCALING_SIZES, first_level=0, repeats=1):
    """The same holes in the bunny at about 50k, 200k, 800k and 3M faces (Loop subdivision).

    The holes are grown from the same centres with the same boundary-size targets at every
    level, so each filter faces holes of the same boundary complexity in ever larger meshes.
    ``sizes`` are cut_holes.SIZE_CLASSES keys (all holes compact); levels before
    ``first_level`` are subdivided but not run (the speed case runs level 1 only). With
    ``repeats`` > 1 the largest level's min-angle run and MeshLab's Close Holes (all holes) run
    that many times in all, alternating (:func:`whole_run_ratio`).

    Returns
    -------
    list of dict rows: faces, filter, run seconds, per-hole seconds (filters that report them)
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "bunny.obj"))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=sizes, shapes=["compact"] * len(sizes), seed=seed)
    centers = np.array([h.center for h in holes])
    rows = []
    for level in range(levels):
        if level:
            ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
        if level < first_level:
            continue
        V_level, F_level = mesh_arrays(ms)
        case = MeshCase(f"bunny_{len(F_level) // 1000}k", V_level, F_level)
        t0 = time.perf_counter()
        _, cut_h = cut_holes(case.V, case.F, sizes=sizes, shapes=["compact"] * len(sizes), centers=centers, seed=seed)
        removed = np.zeros(len(case.F), bool)
        removed[np.concatenate([h.face_indices for h in cut_h])] = True
        prepared = prepare_case(MeshCase(case.name, case.V, case.F, removed=removed))
        cut_seconds = time.perf_counter() - t0
        result = run_comparison(None, cases=[prepared], filters=fillers, timeout=timeout, full_metrics=False,
                                progress=True)
        for run in result.runs:
            hole_rows = [r for r in result.holes if r["filler"] == run["filler"]]
            per_hole = [r.get("seconds") for r in hole_rows if r.get("closed") and r.get("seconds") is not None]
            rows.append({"faces": int(len(prepared.F0)), "filler": run["filler"], "status": run["status"],
                         "run_seconds": run["seconds"], "memory_mb": run.get("memory_mb"),
                         "closed": run.get("closed_holes"),
                         "hole_edges": [h.boundary_edges for h in prepared.holes],
                         "hole_seconds": per_hole if len(per_hole) == len(hole_rows) else None,
                         "cut_seconds": cut_seconds})
        if level == levels - 1 and repeats > 1:
            _repeat_whole_runs(rows, prepared, fillers, repeats, timeout)
        print(f"# scaling: {len(prepared.F0)} faces done", file=sys.stderr)
    if out:
        scaling_plot(rows, os.path.join(out, "scaling.png"))
    return rows


WHOLE_RUN_PAIR = ("meshing_close_holes_min_angle_bilateral", f"{BASELINE} (all holes)")


def _repeat_whole_runs(rows, prepared, fillers, repeats, timeout):
    """Run the min-angle filter and MeshLab's Close Holes (all holes) again on ``prepared``, alternating;
    each one's whole-run seconds are added to its row as ``repeat_seconds`` (the first run included)."""
    pair = [f for f in fillers if (f.filter == WHOLE_RUN_PAIR[0] and not f.params) or f.label == WHOLE_RUN_PAIR[1]]
    level_rows = {r["filler"]: r for r in rows if r["faces"] == len(prepared.F0)}
    for f in pair:
        level_rows[f.label]["repeat_seconds"] = [level_rows[f.label]["run_seconds"]]
    for _ in range(repeats - 1):
        for f in pair:
            result = run_comparison(None, cases=[prepared], filters=[f], timeout=timeout, full_metrics=False)
            level_rows[f.label]["repeat_seconds"].append(result.runs[0]["seconds"])


def whole_run_ratio(rows):
    """The largest level's whole-run ratio, min-angle over MeshLab's Close Holes (all holes), from the
    medians of the repeated runs: one sentence for README Results, or None without repeats."""
    top = max((r["faces"] for r in rows), default=None)
    timed = {r["filler"]: r["repeat_seconds"] for r in rows if r["faces"] == top and "repeat_seconds" in r}
    if len(timed) != 2:
        return None
    ours, meshlab = (float(np.median(timed[label])) for label in WHOLE_RUN_PAIR)
    runs = ", ".join(f"{t:.2f}" for t in timed[WHOLE_RUN_PAIR[0]])
    theirs = ", ".join(f"{t:.2f}" for t in timed[WHOLE_RUN_PAIR[1]])
    return (f"At {top:,} faces the min-angle whole run takes {ours:.2f} s and MeshLab's Close Holes (all holes) "
            f"{meshlab:.2f} s, medians of {len(timed[WHOLE_RUN_PAIR[0]])} alternating runs ({runs} s against "
            f"{theirs} s): {ours / meshlab:.2f}x.")


def scaling_plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(dict.fromkeys(r["filler"] for r in rows))
    colors = filler_colors(labels)
    fig, ax = plt.subplots(figsize=(8, 5))
    for lab in labels:
        rs = [r for r in rows if r["filler"] == lab and r["status"] == "ok"]
        faces = [r["faces"] for r in rs]
        ax.plot(faces, [r["run_seconds"] for r in rs], ls="--", marker="o", color=colors[lab], alpha=0.6,
                label=f"{short_label(lab)}: whole run")
        if all(r["hole_seconds"] for r in rs) and rs:
            ax.plot(faces, [sum(r["hole_seconds"]) for r in rs], ls="-", marker="s", color=colors[lab], lw=2,
                    label=f"{short_label(lab)}: filling the holes")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("mesh faces")
    ax.set_ylabel("seconds (3 holes)")
    ax.set_title("Same holes in ever larger meshes: filling time vs. whole filter run")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def scaling_table(rows):
    header = ["faces", "filter", "closed", "seconds filling the holes", "seconds whole run", "rest (O(n) search, I/O)",
              "peak MB"]
    table = []
    for r in rows:
        fill = sum(r["hole_seconds"]) if r["hole_seconds"] else None
        memory = r.get("memory_mb")
        table.append([f"{r['faces']:,}", f"`{short_label(r['filler'])}`", f"{r['closed']}/{len(r['hole_edges'])}",
                      "–" if fill is None else f"{fill:.3f}", f"{r['run_seconds']:.2f}",
                      "–" if fill is None else f"{r['run_seconds'] - fill:.2f}",
                      "–" if memory is None else f"{memory:.0f}"])
    return header, table


# ------------------------------------------------------------------------- papers vs. ours

PAPERS = {
    "brunton": ("meshing_close_holes_curve_unfolding", "Brunton et al. 2009, Table 1 (bunny, natural holes)"),
    "hu": ("meshing_close_holes_min_angle_bilateral", "Hu et al. 2012, Table 1 (quality statistics)"),
    "xu": ("meshing_close_holes_lssvm_poisson", "Xu et al. 2013, Table 1 (distance to the analytic surface)"),
    "xie": ("meshing_close_holes_differential_evolution", "Xie & Zou 2013, Table 1 sphere row (Eq. 17)"),
}


def _rows(result, filler, case=None):
    return [r for r in result.holes if r["filler"] == filler and (case is None or r["case"] == case)]


def _sum(rows, key):
    return sum(r.get(key) or 0 for r in rows if r.get("closed"))


def papers_table(result, command, seed=0, timeout=600.0):
    """Markdown of the papers' figures next to ours (rows of unregistered filters say so)."""
    registered = set(meshlab_holefill.filter_list())
    lines = ["Paper figures next to ours, measured by `" + command + "`. Our meshes are not the papers' "
             "(their models are not public, except the bunny and the analytic sphere); machines differ.", ""]

    def missing(key):
        return PAPERS[key][0] not in registered or not _rows(result, PAPERS[key][0])

    # Brunton Table 1
    name, title = PAPERS["brunton"]
    lines += [f"**{title}** — `{name}`", "",
              "| | model vertices n | hole boundary vertices m | holes closed | unfolding + embedding (s) |",
              "|---|---|---|---|---|",
              "| paper (Pentium D, C++) | 1494 | 79 (5 holes) | 5/5 | 2 + 1 |"]
    if missing("brunton"):
        lines.append("| ours | not registered (or not run) | | | |")
    else:
        rs = _rows(result, name, "bunny10k_textured.obj")
        case = next(c for c in result.cases if c["case"] == "bunny10k_textured.obj")
        unfold, embed = _sum(rs, "info_unfolding_seconds"), _sum(rs, "info_embedding_seconds")
        lines.append(f"| ours (bunny10k_textured.obj, 1 run) | {case['vertices']} | "
                     f"{sum(r['boundary_edges'] for r in rs)} ({len(rs)} holes) | "
                     f"{sum(1 for r in rs if r['closed'])}/{len(rs)} | {unfold:.3f} + {embed:.3f} |")
        lines += ["", "Per hole (annealing restarts, seconds of unfolding and of embedding):", "",
                  "| hole | boundary edges | closed | restarts | unfolding (s) | embedding (s) |", "|---|---|---|---|---|---|"]
        for r in rs:
            lines.append(f"| {r['hole']} | {r['boundary_edges']} | {'yes' if r['closed'] else 'no'} | "
                         f"{r.get('info_restarts', '–')} | {r.get('info_unfolding_seconds', 0):.3f} | "
                         f"{r.get('info_embedding_seconds', 0):.3f} |")
    # Hu Table 1
    name, title = PAPERS["hu"]
    lines += ["", f"**{title}** — `{name}`", "",
              "| model | new vertices | new triangles | min quality | max quality | mean quality |", "|---|---|---|---|---|---|",
              "| paper a | 59 | 133 | 0.5271 | 0.9999 | 0.9198 |", "| paper b | 100 | 254 | 0.5700 | 0.9998 | 0.9234 |",
              "| paper c | 46 | 104 | 0.4817 | 0.9998 | 0.9815 |", "| paper d | 100 | 316 | 0.4817 | 1.0000 | 0.9248 |",
              "| paper e | 131 | 356 | 0.4839 | 1.0000 | 0.9411 |"]
    if missing("hu"):
        lines.append("| ours | not registered (or not run) | | | | |")
    else:
        for c in result.cases:
            rs = [r for r in _rows(result, name, c["case"]) if r.get("closed")]
            if not rs:
                continue
            faces = _sum(rs, "faces")
            mean_q = sum(r["quality_mean"] * r["faces"] for r in rs) / max(faces, 1)
            lines.append(f"| ours: {c['case']} ({len(rs)} holes) | {_sum(rs, 'new_vertices')} | {faces} | "
                         f"{min(r['quality_min'] for r in rs):.4f} | {max(r['quality_max'] for r in rs):.4f} | "
                         f"{mean_q:.4f} |")
    # Xu Table 1
    name, title = PAPERS["xu"]
    lines += ["", f"**{title}** — `{name}`; error = average distance / sqrt(analytic surface area)", "",
              "| | surface | new vertices | triangles | average distance | error |", "|---|---|---|---|---|---|",
              "| paper, ref. [17] | head model (mm) | 28 | 69 | 0.05 mm | 0.0015 |",
              "| paper, LS-SVM + Poisson | head model (mm) | 31 | 75 | 0.042 mm | 0.00142 |"]
    areas = {"sphere": 4 * np.pi, "torus": 4 * np.pi ** 2 * 0.4}
    xu_rows = [f.label for f in result.fillers if f.filter in (name,)] if not missing("xu") else []
    if not xu_rows:
        lines.append("| ours | not registered (or not run) | | | | |")
    for lab in xu_rows + [f.label for f in result.fillers if f.filter == BASELINE][-1:]:
        for case, area in areas.items():
            rs = [r for r in _rows(result, lab, case) if r.get("closed") and r.get("analytic_dist_mean") is not None]
            if rs:
                nv = _sum(rs, "new_vertices")
                d = sum(r["analytic_dist_mean"] * r["new_vertices"] for r in rs) / max(nv, 1)
                lines.append(f"| ours: `{short_label(lab)}` | {case} (unit radius), {len(rs)} holes | {nv} | "
                             f"{_sum(rs, 'faces')} | {d:.5f} | {d / np.sqrt(area):.6f} |")
    # Xie & Zou Table 1, sphere row
    name, title = PAPERS["xie"]
    lines += ["", f"**{title}** — `{name}`", "",
              "| | NP | NOT | NHT | MPE | APE | RT (s) |", "|---|---|---|---|---|---|---|",
              "| paper (MATLAB, 2.8 GHz) | 1600 | 3040 | 1210 | 1.77E-02 | 7.35E-03 | 9.3 |"]
    if name not in registered:
        lines.append("| ours | not registered | | | | | |")
    else:
        with IsolatedRunner() as runner:
            reply = runner.run({"kind": "call", "function": "meshlab_holefill.evaluation.papers.hpde_sphere.sphere_experiment",
                                "kwargs": {"seed": seed}}, timeout)
        if reply["status"] == "ok":
            v = reply["value"]
            lines.append(f"| ours (`sphere_experiment(seed={seed})`) | {v['NP']} | {v['NOT']} | {v['NHT']} | "
                         f"{v['MPE']:.2E} | {v['APE']:.2E} | {v['seconds']:.2f} |")
        else:
            lines.append(f"| ours | {reply['status']}: {reply.get('error')} | | | | | |")
        lines += xie_all_fillers(result.fillers, seed, timeout)
    return "\n".join(lines) + "\n"


def xie_all_fillers(fillers, seed, timeout):
    """Eq. 17 (MPE/APE over the new vertices of both holes) on the paper's sphere, for every filler."""
    V, F = hpde_sphere.uv_sphere()
    removed = np.zeros(len(F), bool)
    for hole in hpde_sphere.SPHERE_HOLES:
        removed |= hpde_sphere.ellipse_hole(V, F, *hole)
    res = run_comparison(None, cases=[prepare_case(MeshCase("paper sphere", V, F, removed=removed))],
                         filters=fillers, timeout=timeout, progress=False)
    out = []
    for f in fillers:
        rs = [r for r in res.holes if r["filler"] == f.label]
        closed = [r for r in rs if r.get("closed")]
        if len(closed) < len(rs) or any(r.get("eq17_distance_sum") is None for r in closed):
            why = (f"{len(closed)}/{len(rs)} holes closed" if len(closed) < len(rs)
                   else "no new vertices: Eq. 17 undefined")
            out.append(f"| same sphere, `{short_label(f.label)}` | | | | {why} | | |")
            continue
        mx = max(r["eq17_abs_coordinate_max"] for r in closed)
        k = sum(r["new_vertices"] for r in closed)
        run = next(r for r in res.runs if r["filler"] == f.label)
        out.append(f"| same sphere, `{short_label(f.label)}` (all new vertices) | {len(V)} | {len(F)} | "
                   f"{int(removed.sum())} | {max(r['eq17_distance_max'] for r in closed) / mx:.2E} | "
                   f"{sum(r['eq17_distance_sum'] for r in closed) / (k * mx):.2E} | {run['seconds']:.2f} |")
    return out


# ----------------------------------------------------------------------------------- main

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


# ------------------------------------------------------------------------ speed against CGAL

def speed_table(result, anchor="cgal_liepa"):
    """Per-hole fill seconds of every filler against CGAL's Liepa fill, on the holes with ground truth.

    Each filler is timed on the holes that it and the anchor both closed (the filters' own per-hole
    time, measured in the same run and worker harness); the ratio is its total over the anchor's.
    """
    rows = [r for r in result.holes if r.get("ground_truth")]
    anchor_rows = {(r["case"], r["hole"]): r for r in rows if r["filler"] == anchor and r.get("closed")
                   and r.get("seconds") is not None}
    if not anchor_rows:
        return None
    out = []
    for label in dict.fromkeys(r["filler"] for r in rows):
        mine = [r for r in rows if r["filler"] == label and r.get("closed") and r.get("seconds") is not None
                and (r["case"], r["hole"]) in anchor_rows]
        if not mine:
            continue
        seconds = sum(r["seconds"] for r in mine)
        base = sum(anchor_rows[(r["case"], r["hole"])]["seconds"] for r in mine)
        slowest = max(mine, key=lambda r: r["seconds"])
        out.append([f"`{short_label(label)}`", str(len(mine)), f"{seconds:.2f}", f"{base:.2f}",
                    f"{seconds / base:.1f}" if base > 0 else "–",
                    f"{slowest['seconds']:.2f} ({slowest['case']}, {slowest['boundary_edges']} edges)"])
    return (["filler", "holes", "seconds", f"`{anchor}` seconds", "× CGAL", "slowest hole"], out)


# --------------------------------------------------------------------------- one core each

def one_core_speed(cases, holes, seed, repeats=3, anchor="cgal_liepa"):
    """Per-hole seconds of each filter (defaults, ``workers=1``) and of the anchor on the same holes, one core each.

    The anchor fills one hole at a time in one thread. With one worker per core two holes are
    filled at once and share the machine, which makes each one's seconds longer (on the suite's
    holes the min-angle filter's sum grows about 1.5x), so here the filters too fill one hole at
    a time, in this process, on the cases with ground truth (cut and given holes). The fillers
    alternate ``repeats`` times (the order rotated each time); per filler, the median of its
    totals over the holes that it and the anchor both closed, and the ratio of the medians.

    Returns
    -------
    (header, rows) for :func:`markdown_table`, or None when the anchor is not installed or no
    case has holes with ground truth
    """
    from meshlab_holefill.array_api import algorithm_names, fill_holes
    from meshlab_holefill.evaluation.anchors import missing_package, run_anchor

    if missing_package(anchor):
        return None
    prepared = [pc for pc in (prepare_case(c, holes=holes, seed=seed) for c in cases)
                if pc.holes and all(h.ground_truth is not None for h in pc.holes)]
    if not prepared:  # only natural holes among the cases: nothing to compare on
        return None
    names = algorithm_names()
    warm_V, warm_F = prepared[0].V0, prepared[0].F0
    for name in names:  # kernels loaded before the first timing
        fill_holes(warm_V, warm_F, name, workers=1)

    def per_hole(name, pc):
        """{hole index: seconds} of the holes ``name`` closed in case ``pc``."""
        everything = max(h.boundary_edges for h in pc.holes) + 1
        if name == anchor:
            result = run_anchor(anchor, pc.V0, pc.F0, {"maxholesize": everything})[2]
        else:
            result = fill_holes(pc.V0, pc.F0, name, workers=1, maxholesize=everything)[2]
        return {i: h["seconds"] for i, h in enumerate(result["holes"]) if h.get("status") == "closed"}

    fillers = names + [anchor]
    times = {name: [] for name in fillers}  # per repeat: {(case, hole): seconds}
    for r in range(repeats):
        for name in fillers[r % len(fillers):] + fillers[:r % len(fillers)]:
            times[name].append({(k, i): t for k, pc in enumerate(prepared) for i, t in per_hole(name, pc).items()})
    both = {name: set.intersection(*(set(run) for run in times[name] + times[anchor])) for name in names}  # closed in every run
    rows = []
    for name in names:
        mine = float(np.median([sum(run[h] for h in both[name]) for run in times[name]]))
        base = float(np.median([sum(run[h] for h in both[name]) for run in times[anchor]]))
        rows.append([f"`{name}`", str(len(both[name])), f"{mine:.2f}", f"{base:.2f}", f"{mine / base:.2f}"])
    header = ["filter", "holes", f"seconds (median of {repeats})", f"`{anchor}` seconds (median of {repeats})",
              "× CGAL"]
    return header, rows


# ------------------------------------------------------------------------ holes on all cores

def workers_speedup(filters=("meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
                             "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution"),
                    mesh=os.path.join(SAMPLES, "rangemaps", "face000.ply"), counts=(1, 2), repeats=3):
    """Whole-run seconds of each filter on a scan with ``workers`` = 1 and 2, and whether the meshes are equal.

    Each filter's kernels are loaded first (their one-time cost is in ``--compile-cost``); the
    worker counts then alternate ``repeats`` times and the medians are reported.
    """
    rows = []
    for name in filters:
        load_filter_kernels(name)
        seconds, meshes = {c: [] for c in counts}, []
        for _ in range(repeats):
            for workers in counts:
                ms = pymeshlab.MeshSet()
                ms.load_new_mesh(mesh)
                t = time.perf_counter()
                res = getattr(ms, name)(workers=workers)
                seconds[workers].append(time.perf_counter() - t)
                m = ms.current_mesh()
                meshes.append((m.vertex_matrix(), m.face_matrix(), res["closed_holes"]))
        same = all(np.array_equal(a, b) for other in meshes[1:] for a, b in zip(meshes[0][:2], other[:2]))
        medians = [float(np.median(seconds[c])) for c in counts]
        rows.append([f"`{short_label(name)}`", str(meshes[0][2])] + [f"{x:.2f}" for x in medians]
                    + [f"{medians[0] / medians[-1]:.2f}", "yes" if same else "**no**"])
    header = ["filter", "holes closed"] + [f"workers={c} (s, median of {repeats})" for c in counts] + ["speed-up", "same mesh"]
    return header, rows


# ------------------------------------------------------------------------------ refused loops

def spherical_cap(subdivisions=7, height=0.3):
    """A cap of the unit icosphere (``subdivisions`` levels), ``height`` high: an open scan-like sheet.

    Its area is 1.1 times the area its rim spans, so its one loop outlines the whole mesh.
    """
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdivisions)
    V, F = mesh_arrays(ms)
    keep = V[F].mean(axis=1)[:, 2] > 1 - height
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F[keep].astype(np.int32)))
    ms.meshing_remove_unreferenced_vertices()
    return mesh_arrays(ms)


def refusal_times(filters=("meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
                           "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution")):
    """Whole-run seconds of each filter on a mesh whose only loop it refuses: a spherical cap.

    The cap's rim outlines its whole component (an island outline), which the filters skip by
    default; the run's time is how long the refusal takes, mesh transfer included (each filter first
    runs once on a small cap, untimed, so imports and compiled kernels are loaded).
    """
    V, F = spherical_cap()
    small = spherical_cap(subdivisions=3)
    edges = None
    rows = []
    for name in filters:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=small[0], face_matrix=small[1].astype(np.int32)))
        getattr(ms, name)()
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
        t = time.perf_counter()
        res = getattr(ms, name)()
        seconds = time.perf_counter() - t
        hole = res["holes"][0]
        edges = hole.get("boundary_edges", edges)
        rows.append([f"`{short_label(name)}`", hole["status"], f"{seconds:.2f}", hole.get("reason", "").split(":")[0]])
    header = ["filter", "status", "whole run (s)", "reason"]
    return f"{len(F):,} faces, one loop of {edges} edges", header, rows


# ------------------------------------------------------------------------------ compile cost

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--filters", default=DEFAULT_FILTERS,
                    help="fillers as for `meshlab-holefill compare --filters` (default: all of ours, the measured "
                         "variants, meshing_close_holes twice)")
    ap.add_argument("--out", default="bench_out")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--holes", type=int, default=4, help="holes cut per closed mesh")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds before a run is killed (default 60: "
                                                                 "keeps the suite under 10 minutes)")
    ap.add_argument("--refinehole", action="store_true", help="also meshing_close_holes with refinehole=True")
    ap.add_argument("--no-pictures", action="store_true")
    ap.add_argument("--scaling", action="store_true", help="also the scaling run (50k..3M faces)")
    ap.add_argument("--no-suite", action="store_true", help="skip the standard suite (e.g. only --scaling)")
    ap.add_argument("--scaling-levels", type=int, default=4)
    ap.add_argument("--scaling-repeats", type=int, default=3,
                    help="runs of the min-angle filter and MeshLab's Close Holes (all holes) at the largest scaling "
                         "level, alternating; their medians give the whole-run ratio (default 3)")
    ap.add_argument("--papers", action="store_true", help="also the papers-vs-ours table")
    ap.add_argument("--speed-case", action="store_true",
                    help="also the speed case: holes of ~50/200/250 edges in a ~200k-face mesh")
    ap.add_argument("--update-readme", action="store_true",
                    help="replace the README's Results section with this run's tables")
    ap.add_argument("--batch", action="store_true",
                    help="also batch throughput (files per minute) with 1 and 2 dask workers, and the speed-up")
    ap.add_argument("--workers", action="store_true", help="also face000.ply with workers=1 and 2")
    ap.add_argument("--one-core", action="store_true",
                    help="also every filter against CGAL's Liepa fill on the suite's cut holes, one hole at a time each")
    ap.add_argument("--compile-cost", action="store_true",
                    help="also the one-time cost of compiling the kernels (cold, empty numba cache) and the warm load")
    ap.add_argument("--refusals", action="store_true",
                    help="also the time each filter takes to refuse a loop that outlines its whole mesh")
    ap.add_argument("--batch-files", type=int, default=24, help="files in the batch throughput run (default 24)")
    args = ap.parse_args(argv)
    command = ".venv/bin/python scripts/benchmark.py " + " ".join(argv if argv is not None else sys.argv[1:])
    command = command.strip()
    fillers = parse_fillers(args.filters or None, args.refinehole)
    t0 = time.perf_counter()
    os.makedirs(args.out, exist_ok=True)
    load_at_start = os.getloadavg()[0]  # other jobs on the machine slow every timing below
    text, result = f"Measured by `{command}` on {time.strftime('%Y-%m-%d')} ({os.cpu_count()} cores).\n", None
    if not args.no_suite:
        cases = [load_case(c) for c in args.cases.split(",") if c]
        result = run_comparison(cases, holes=args.holes, seed=args.seed, filters=fillers, timeout=args.timeout)
        suite_dir = os.path.join(args.out, "suite")
        write_report(result, suite_dir, pictures=not args.no_pictures, command=command)
        suite_seconds = time.perf_counter() - t0
        print(f"# suite: {suite_seconds:.1f} s (report in {suite_dir})", file=sys.stderr)
        text = (f"Measured by `{command}` on {time.strftime('%Y-%m-%d')} ({os.cpu_count()} cores, load average "
                f"{load_at_start:.1f} at the start): {suite_seconds:.0f} s for the suite including the report. Meshes: "
                + ", ".join(f"{c['case']} ({len(c['holes'])} {c['kind']})" for c in result.cases)
                + f". Full report: `{suite_dir}/report.md` (tables, charts, a picture of every hole).\n\n"
                + to_markdown(summary_blocks(result)))
        speed = speed_table(result)
        if speed is not None:
            text += ("\n\n**Speed against CGAL** (the filters' own per-hole seconds on the cut holes that both they and "
                     "`cgal_liepa` closed, same run; the filters with `workers` = one per core, two holes at once):\n\n" + markdown_table(*speed) + "\n")
        if args.one_core:
            single = one_core_speed(cases, args.holes, args.seed)
            if single is not None:
                text += ("\n**One core each** (the same holes, every filter with its defaults and `workers=1` in one "
                         "process, CGAL's Liepa fill one hole at a time, alternating three times; per-hole seconds "
                         "summed, medians):\n\n" + markdown_table(*single) + "\n")
            else:
                text += ("\n**One core each**: skipped (CGAL's Python bindings, package `cgal` of the `bench` extra, "
                         "are not installed, or no case has cut or given holes).\n")
    # timing runs: each filter once, with its defaults (variants only change accuracy)
    plain = [f for f in fillers if not f.params or f.filter == BASELINE]
    if args.scaling:
        rows = scaling_run(plain, args.seed, args.scaling_levels, max(args.timeout, 180.0), args.out,
                           repeats=args.scaling_repeats)
        with open(os.path.join(args.out, "scaling.json"), "w") as fh:
            json.dump(rows, fh, indent=1)
        text += ("\n**Scaling** (the same three holes, ~20/60/150 boundary edges, in the bunny subdivided; "
                 "'filling the holes' is the sum of the filters' own per-hole times (holes are filled two at a "
                 "time, `workers` = one per core, so the sum can exceed the whole run; 'rest' is then negative), the "
                 "rest is the O(n) boundary search, mesh transfer and merge; 'peak MB' is the worker's peak resident memory while it builds the "
                 "MeshSet and runs the filter, above its memory before):\n\n" + markdown_table(*scaling_table(rows)) + f"\n\nPlot: `{args.out}/scaling.png`.\n")
        ratio = whole_run_ratio(rows)
        if ratio:
            text += "\n" + ratio + "\n"
    if args.speed_case:
        rows = scaling_run(plain, args.seed, 2, max(args.timeout, 180.0), None, SPEED_CASE_SIZES, first_level=1)
        with open(os.path.join(args.out, "speed_case.json"), "w") as fh:
            json.dump(rows, fh, indent=1)
        edges = "/".join(str(e) for e in rows[0]["hole_edges"]) if rows else "?"
        text += (f"\n**Speed case** (three holes of about 50, 200 and 250 boundary edges, here {edges}, in the "
                 "bunny Loop-subdivided once; reference for `min_angle_bilateral`: whole run under 1.5 s):\n\n"
                 + markdown_table(*scaling_table(rows)) + "\n")
    if args.workers:
        text += ("\n**Holes on all cores** (face000.ply, whole run of each filter in one process, its kernels "
                 "loaded first, `workers=1` and `workers=2` alternating three times, medians):\n\n" + markdown_table(*workers_speedup()) + "\n")
    if args.compile_cost:
        text += ("\n**Compiling the kernels** (`meshlab-holefill compile` with an empty numba cache, as after an "
                 "install, then again with the cache current; each filter's process seconds, compiling included, "
                 "one process per core, filters taken in the table's order; a kernel two filters share is compiled by "
                 "the first that needs it):\n\n" + markdown_table(*compile_cost()) + "\n")
    if args.refusals:
        what, header, rows = refusal_times()
        text += (f"\n**Refused loops** (a spherical cap, {what}: the rim outlines the whole mesh, so the "
                 "filters refuse it; whole run of each filter at its defaults):\n\n" + markdown_table(header, rows) + "\n")
    if args.papers and result is not None:
        papers = papers_table(result, command, args.seed, max(args.timeout, 180.0))
        with open(os.path.join(args.out, "papers.md"), "w") as fh:
            fh.write(papers)
        text += "\n**Papers vs. ours**\n\n" + papers
    if args.batch:
        text += ("\n**Batch throughput** (`meshlab_holefill.batch` on a running LocalCluster, copies of the bunny scan "
                 "with its 5 natural holes, `meshing_close_holes_min_angle_bilateral` defaults):\n\n"
                 + batch_throughput(args.out, args.batch_files) + "\n")
    with open(os.path.join(args.out, "benchmark.md"), "w") as fh:
        fh.write(text + "\n")
    if args.update_readme:
        update_readme(text)
    print(text)
    print(f"# total: {time.perf_counter() - t0:.1f} s", file=sys.stderr)


def update_readme(text, path=os.path.join(os.path.dirname(__file__), "..", "README.md")):
    """Replace what stands between the README's results markers."""
    with open(path) as fh:
        readme = fh.read()
    start, end = "<!-- results:start -->", "<!-- results:end -->"
    head, rest = readme.split(start, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as fh:
        fh.write(head + start + "\n" + text.strip() + "\n" + end + tail)


if __name__ == "__main__":
    main()
