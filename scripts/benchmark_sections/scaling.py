"""The scaling run: the same holes in the bunny subdivided to 50k-3M faces, and the speed case."""
from __future__ import annotations

import os
import sys
import time

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.comparison import BASELINE, MeshCase, prepare_case, run_comparison
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.report.labels import filler_colors, short_label
from meshlab_holefill.meshlab.mesh_files import mesh_arrays
from .cases import SAMPLES


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
                         "stage_seconds": run.get("stage_seconds"), "cut_seconds": cut_seconds})
        if level == levels - 1 and repeats > 1:
            _repeat_whole_runs(rows, prepared, fillers, repeats, timeout)
        print(f"# scaling: {len(prepared.F0)} faces done", file=sys.stderr)
    if out:
        scaling_plot(rows, os.path.join(out, "scaling.png"))
    return rows


WHOLE_RUN_PAIR = ("meshing_close_holes_min_angle_bilateral", f"{BASELINE} (all holes)")


def whole_run_pair(fillers):
    """The fillers of :data:`WHOLE_RUN_PAIR` among ``fillers``: the min-angle filter at its defaults, MeshLab's
    Close Holes (all holes)."""
    return [f for f in fillers if (f.filter == WHOLE_RUN_PAIR[0] and not f.params) or f.label == WHOLE_RUN_PAIR[1]]


def _repeat_whole_runs(rows, prepared, fillers, repeats, timeout):
    """Run the min-angle filter and MeshLab's Close Holes (all holes) again on ``prepared``, alternating;
    each one's whole-run seconds are added to its row as ``repeat_seconds`` (the first run included)."""
    pair = whole_run_pair(fillers)
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


#: Whole-mesh stages of a filter's run (``stage_seconds`` of its result) that the stage table lists.
STAGES = ("read layer", "edge table", "boundary loops", "hole selection", "kernels", "holes", "attributes",
          "write layer")


def stage_table(rows, filler=WHOLE_RUN_PAIR[0]):
    """Where ``filler``'s whole run goes at each mesh size: seconds of each of :data:`STAGES`, then the whole run."""
    header = ["faces"] + list(STAGES) + ["whole run"]
    table = []
    for r in rows:
        stages = r.get("stage_seconds")
        if r["filler"] != filler or not stages:
            continue
        table.append([f"{r['faces']:,}"] + [f"{stages.get(name, 0.0):.3f}" for name in STAGES]
                     + [f"{r['run_seconds']:.2f}"])
    return header, table
