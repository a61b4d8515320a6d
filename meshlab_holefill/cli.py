"""The ``meshlab-holefill`` command: fill holes, list holes and filters, run .mlx scripts."""
from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from .meshlab.meshset_io import load_meshset
from .meshlab.registration import parse_text_value, shown_value


def _params_from_unknown(unknown):
    """Turn ``--name value`` pairs left over by argparse into filter keyword arguments."""
    params = {}
    i = 0
    while i < len(unknown):
        key = unknown[i]
        if not key.startswith("--"):
            raise SystemExit(f"unexpected argument {key!r}; filter parameters are given as --name value")
        name = key[2:].replace("-", "_")
        if "=" in name:
            name, value = name.split("=", 1)
            i += 1
        elif i + 1 < len(unknown):
            value = unknown[i + 1]
            i += 2
        else:
            raise SystemExit(f"parameter {key} has no value")
        params[name] = parse_text_value(value)
    return params


def cmd_fill(args, extra):
    from .meshlab.registration import apply_filter

    ms = load_meshset(args.input)
    result = apply_filter(ms, args.filter, **_params_from_unknown(extra))
    ms.save_current_mesh(args.output)
    if args.json:
        print(json.dumps(result, indent=2, default=float))
    else:
        print(_hole_status_table(result))
    return 0 if result.get("failed_holes", 0) == 0 else 1


def _hole_status_table(result):
    lines = [f"{'hole':>4} {'edges':>6} {'status':>8} {'new V':>6} {'new F':>6} {'sec':>7}  reason"]
    for h in result.get("holes", []):
        lines.append(f"{h['hole']:>4} {h['boundary_edges']:>6} {h['status']:>8} {h.get('new_vertices', ''):>6} "
                     f"{h.get('new_faces', ''):>6} {h.get('seconds', float('nan')):>7.3f}  {h.get('reason', '')}")
    summary = {k: v for k, v in result.items() if k != "holes"}
    lines.append(", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in summary.items()))
    return "\n".join(lines)


def cmd_holes(args, extra):
    from .core.holes import OUTLINE_RATIO, boundary_loops, loop_measures, outline_ratios

    ms = load_meshset(args.input)
    m = ms.current_mesh()
    V, F = m.vertex_matrix(), m.face_matrix()
    loops = boundary_loops(F)
    outlines = outline_ratios(V, F, loops) >= OUTLINE_RATIO if loops else []
    print(f"{m.label()}: {m.vertex_number()} vertices, {m.face_number()} faces, {len(loops)} boundary loops")
    print(f"{'hole':>4} {'edges':>6} {'perimeter':>11} {'diameter':>10} {'planarity':>9}  notes")
    for i, loop in enumerate(loops):
        meas = loop_measures(V[loop.vertices])
        notes = []
        if loop.pinched:
            notes.append("pinched (non-manifold vertex)")
        if not loop.closed:
            notes.append("open chain")
        if outlines[i]:
            notes.append("outline of a whole component (island or outer border, not a hole)")
        print(f"{i:>4} {meas['edges']:>6} {meas['perimeter']:>11.4g} {meas['diameter']:>10.4g} "
              f"{meas['planarity']:>9.4f}  {', '.join(notes)}")
    return 0


def cmd_filters(args, extra):
    from .meshlab.registration import FILTERS, filter_help

    names = [args.name] if args.name else sorted(FILTERS)
    for name in names:
        if name not in FILTERS:
            from .meshlab.registration import print_filter_parameter_list

            print_filter_parameter_list(name)
            continue
        print(f"== {name}")
        print(filter_help(name))
        print()
    return 0


def build_parser():
    parser = argparse.ArgumentParser(prog="meshlab-holefill",
                                     description="Hole-filling filters for pymeshlab (four papers + MeshLab's Close Holes).")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("fill", help="fill the holes of a mesh with one filter; extra --name value pairs are parameters")
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--filter", default="meshing_close_holes_min_angle_bilateral",
                   help="filter name (ours or any pymeshlab filter, e.g. meshing_close_holes)")
    p.add_argument("--json", action="store_true", help="print the whole result dictionary as JSON")
    p.set_defaults(func=cmd_fill)
    p = sub.add_parser("holes", help="table of boundary loops: edges, perimeter, diameter, planarity")
    p.add_argument("input")
    p.set_defaults(func=cmd_holes)
    p = sub.add_parser("filters", help="list the filters with their parameters, defaults and help")
    p.add_argument("name", nargs="?")
    p.set_defaults(func=cmd_filters)
    # Further subcommands (run, compare) register themselves here.
    for register in _SUBCOMMANDS:
        register(sub)
    return parser


_SUBCOMMANDS = []


def cmd_run(args, extra):
    from .meshlab.mlx.script import read_filter_script, run_filter_script, save_filter_script

    script = read_filter_script(args.script)  # all problems reported before the mesh is even loaded
    if args.check:
        for step in script.steps:
            params = ", ".join(f"{k}={shown_value(v)}" for k, v in step.kwargs.items())
            print(f"#{step.index} line {step.line}: {step.mlx_name!r} -> {step.filter}"
                  f"{' (meshlab_holefill)' if step.ours else ''}({params})")
        print(f"{script.source}: {len(script.steps)} filter(s), no problems")
        return 0
    if args.input is None or args.output is None:
        raise SystemExit("meshlab-holefill run: INPUT and OUTPUT are required (unless --check)")
    ms = load_meshset(args.input)
    results = run_filter_script(ms, script)
    ms.save_current_mesh(args.output)
    if args.record:
        save_filter_script(ms, args.record)
    if args.json:
        print(json.dumps(results, indent=2, default=float))
    else:
        for step, result in zip(script.steps, results):
            summary = ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}"
                                for k, v in result.items() if k != "holes")
            print(f"#{step.index} {step.mlx_name}" + (f": {summary}" if summary else ""))
    failed = sum(r.get("failed_holes", 0) for r in results)
    return 0 if failed == 0 else 1


def _register_run(sub):
    p = sub.add_parser("run", help="run a MeshLab .mlx filter script (built-in filters and ours) on a mesh")
    p.add_argument("script", help=".mlx file (MeshLab FilterScript XML)")
    p.add_argument("input", nargs="?")
    p.add_argument("output", nargs="?")
    p.add_argument("--check", action="store_true", help="only validate the script and list its steps")
    p.add_argument("--record", metavar="MLX", help="also write the filters applied as an .mlx script")
    p.add_argument("--json", action="store_true", help="print the result dictionaries as JSON")
    p.set_defaults(func=cmd_run)


_SUBCOMMANDS.append(_register_run)


def cmd_compare(args, extra):
    import shlex

    from .evaluation.compare import compare
    from .evaluation.report.tables import markdown_table as _md_table, summary_table
    from .evaluation.report.write import write_report

    result = compare(args.meshes, holes=args.holes, sizes=args.sizes.split(","), seed=args.seed,
                     filters=args.filters, refinehole=args.refinehole, timeout=args.timeout,
                     maxholesize=args.maxholesize, progress=not args.quiet)
    if args.report:
        options = [f"--report {args.report}", f"--holes {args.holes}", f"--sizes {args.sizes}", f"--seed {args.seed}"]
        options += [f"--filters {shlex.quote(f)}" for f in args.filters or []]
        options += ["--refinehole"] * args.refinehole + ["--no-pictures"] * args.no_pictures
        command = "meshlab-holefill compare " + " ".join([shlex.quote(m) for m in args.meshes] + options)
        write_report(result, args.report, pictures=not args.no_pictures, command=command)
        print(f"report: {args.report}/report.md ({result.wall_seconds:.1f} s)")
    print(_md_table(*summary_table(result)))
    return 0


def _register_compare(sub):
    p = sub.add_parser("compare", help="compare hole fillers on meshes (holes with ground truth cut into closed "
                                       "meshes) and write a report")
    p.add_argument("meshes", nargs="+", metavar="MESH")
    p.add_argument("--report", metavar="DIR", help="write report.md/.html, results.json/.csv and pictures here")
    p.add_argument("--holes", type=int, default=4, help="holes cut into each closed mesh (default 4)")
    p.add_argument("--sizes", default="small,medium,large", help="hole size classes, cycled (small~20, medium~60, "
                                                                   "large~150 boundary edges)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--filters", action="append",
                   help="fillers, comma-separated, each NAME or NAME:param=value[:param=value]; 'ours', 'baseline'; "
                        "maxholesize=all covers every hole (default: all of ours + meshing_close_holes twice)")
    p.add_argument("--refinehole", action="store_true", help="also run meshing_close_holes with refinehole=True")
    p.add_argument("--timeout", type=float, default=300.0, help="seconds before a run is killed (default 300)")
    p.add_argument("--maxholesize", type=int, default=1000, help="largest natural hole evaluated (boundary edges)")
    p.add_argument("--no-pictures", action="store_true", help="tables only")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_compare)


_SUBCOMMANDS.append(_register_compare)


def cmd_batch(args, extra):
    from .batching import BatchInterrupted, batch

    params = _params_from_unknown(extra)
    try:
        report = batch(args.inputs, args.out, filter=args.filter, mlx=args.mlx, scheduler=args.scheduler,
                       n_workers=args.workers, memory_limit=args.memory_limit, timeout=args.timeout,
                       format=args.format, force=args.force, progress=False if args.quiet else None, **params)
    except BatchInterrupted as stop:
        print(f"meshlab-holefill: interrupted; report of the finished files: {stop.report.paths['summary']}",
              file=sys.stderr)
        return 130
    if not args.quiet:
        counts = ", ".join(f"{n} {status}" for status, n in report.counts.items() if n)
        print(f"{len(report.files)} files: {counts} ({report.seconds:.1f} s); report: {report.paths['summary']}")
        for record in report.failed:
            print(f"failed: {record['input']}: {record.get('error')}")
    return 1 if args.strict and report.failed else 0


def _register_batch(sub):
    from .batching import OUTPUT_FORMATS

    p = sub.add_parser("batch", help="repair many files on dask (a local cluster, or yours with --scheduler); "
                                     "extra --name value pairs are filter parameters",
                       description="Fill the holes of many mesh files, one dask task per file. Files whose "
                                   "output is up to date (same input content, filter and parameters) are skipped; "
                                   "a file that crashes or kills its worker is retried once, then reported failed. Filter "
                                   "parameters (--name value) go after the inputs.")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="mesh files, folders (searched recursively) or globs")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: repaired meshes, a .json result beside each, batch.json/.csv, summary.md")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--filter", help="filter name (ours or any pymeshlab filter; default "
                                       "meshing_close_holes_min_angle_bilateral)")
    what.add_argument("--mlx", metavar="SCRIPT", help="run a MeshLab .mlx filter script instead of one filter")
    p.add_argument("--format", choices=OUTPUT_FORMATS, help="output format (default: each input's own)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="a running dask scheduler, e.g. tcp://host:8786 "
                                                          "(default: a local cluster)")
    p.add_argument("--workers", type=int, help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--memory-limit", default="auto", help="per-worker memory limit of the local cluster, e.g. 4GiB")
    p.add_argument("--timeout", type=float, help="seconds per file before it is stopped and reported failed")
    p.add_argument("--force", action="store_true", help="redo files whose output is up to date")
    p.add_argument("--strict", action="store_true", help="exit with status 1 when any file failed")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary on the terminal")
    p.set_defaults(func=cmd_batch)


_SUBCOMMANDS.append(_register_batch)


def main(argv=None):
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra and args.command not in ("fill", "batch"):
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    try:
        return args.func(args, extra)
    except BrokenPipeError:  # output piped into `head` and the like: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (ValueError, OSError) as exc:
        print(f"meshlab-holefill: error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # pymeshlab raises its own exception types (not ValueError)
        if type(exc).__module__.startswith("pymeshlab"):
            print(f"meshlab-holefill: error: {exc}", file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":
    sys.exit(main())
