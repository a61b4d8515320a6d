"""The ``meshlab-holefill`` command: fill holes, list holes and filters, run .mlx scripts."""
from __future__ import annotations

import argparse
import json
import os
import sys

from .meshlab.meshset_io import load_meshset
from .meshlab.registration import parse_text_value, shown_value


def _params_from_unknown(unknown):
    """Turn ``--name value`` pairs left over by argparse into filter keyword arguments."""
    params = {}
    i = 0
    while i < len(unknown):
        key = unknown[i]
        if not key.startswith("--"):
            raise ValueError(f"unexpected argument {key!r}; filter parameters are given as --name value")
        name = key[2:].replace("-", "_")
        if "=" in name:
            name, value = name.split("=", 1)
            i += 1
        elif i + 1 < len(unknown):
            value = unknown[i + 1]
            i += 2
        else:
            raise ValueError(f"parameter {key} has no value")
        params[name] = parse_text_value(value)
    return params


EXIT_OK, EXIT_STRICT, EXIT_ERROR = 0, 1, 2
EXIT_CODES_HELP = ("exit status: 0 when the run completed, even with holes skipped or failed (they are listed); "
                   "1 with --strict when any hole to be filled failed; 2 on an error (unreadable or bad input, "
                   "unknown filter or parameter, bad value, an output that cannot be written)")
REPORT_FORMATS = (".json", ".csv")


class _HoleProgress:
    """``progress(hole_id, total)`` for the filters: a tqdm bar per filter on an interactive stderr."""

    def __init__(self, enabled):
        self.enabled, self.bar = enabled, None

    def __call__(self, hole, total):
        if not self.enabled:
            return
        if self.bar is None or self.bar.n >= self.bar.total:  # the next filter of a script
            self.close()
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc="filling holes", unit="hole", file=sys.stderr, leave=False)
        self.bar.update(1)
        self.bar.set_postfix_str(f"hole {hole}", refresh=False)

    def close(self):
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def _stderr_is_interactive():
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class _Reporting:
    """--quiet / --verbose: a progress bar when stderr is a terminal; with --verbose a log line per hole."""

    def __init__(self, args):
        import logging

        from .meshlab.progress import reporting

        self.bar = _HoleProgress(enabled=not args.quiet and _stderr_is_interactive())
        self._context = reporting(self.bar)
        self._logger, self._handler, self._level = logging.getLogger("meshlab_holefill"), None, None
        if args.verbose and not args.quiet:
            self._handler = logging.StreamHandler(sys.stderr)
            self._handler.setFormatter(logging.Formatter("meshlab-holefill: %(message)s"))

    def __enter__(self):
        import logging

        if self._handler is not None:
            self._level = self._logger.level
            self._logger.addHandler(self._handler)
            self._logger.setLevel(logging.INFO)
        self._context.__enter__()
        return self

    def __exit__(self, *exc):
        self._context.__exit__(*exc)
        self.bar.close()
        if self._handler is not None:
            self._logger.removeHandler(self._handler)
            self._logger.setLevel(self._level)
        return False


def _check_report_path(path):
    if os.path.splitext(path)[1].lower() not in REPORT_FORMATS:
        raise ValueError(f"--report '{path}': give a .json or .csv file")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder) or not os.access(folder, os.W_OK):
        raise ValueError(f"--report '{path}': folder '{folder}' does not exist or is not writable")


def _failed_holes(results):
    return sum(r.get("failed_holes", 0) for r in results)


def cmd_fill(args, extra):
    from .meshlab.meshset_io import check_mesh_output_path
    from .meshlab.registration import apply_filter

    params = _params_from_unknown(extra)
    check_mesh_output_path(args.output)  # before the work, not after it
    if args.report:
        _check_report_path(args.report)
    ms = load_meshset(args.input)
    with _Reporting(args):
        result = apply_filter(ms, args.filter, **params)
    ms.save_current_mesh(args.output)
    if args.report:
        write_hole_report(args.report, result, {"input": args.input, "output": args.output, "filter": args.filter,
                                                "params": {k: _plain(v) for k, v in params.items()}})
    if args.json:
        print(json.dumps(result, indent=2, default=float))
    elif not args.quiet:
        print(_hole_status_table(result))
    return EXIT_STRICT if args.strict and _failed_holes([result]) else EXIT_OK


def _plain(value):
    """A parameter value for a JSON report (pymeshlab's value types as text)."""
    from .meshlab.registration import shown_value

    return value if isinstance(value, (bool, int, float, str)) else shown_value(value)


HOLE_COLUMNS = ["hole", "boundary_edges", "status", "reason", "size_class", "new_vertices", "new_faces", "seconds",
                "centroid_x", "centroid_y", "centroid_z", "perimeter", "diameter", "area", "planarity", "pinched"]


def write_hole_report(path, result, about):
    """The per-hole report of one filter run: ``.json`` (the run and every hole dict) or ``.csv`` (a row per hole).

    The CSV has the common columns first (``HOLE_COLUMNS``; the centroid split in x, y, z), then any
    algorithm-specific entries in order of appearance (lists written as JSON).
    """
    import csv

    if path.lower().endswith(".json"):
        doc = dict(about, **{k: v for k, v in result.items() if k != "holes"}, holes=result.get("holes", []))
        with open(path, "w") as f:
            json.dump(doc, f, indent=2, default=float)
        return
    rows, extra = [], []
    for h in result.get("holes", []):
        row = {k: v for k, v in h.items() if k != "centroid"}
        if "centroid" in h:
            row.update(zip(("centroid_x", "centroid_y", "centroid_z"), h["centroid"]))
        for key in row:
            if key not in HOLE_COLUMNS and key not in extra:
                extra.append(key)
        rows.append({k: json.dumps(v) if isinstance(v, (list, dict)) else v for k, v in row.items()})
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, HOLE_COLUMNS + extra, restval="")
        writer.writeheader()
        writer.writerows(rows)


def _hole_status_table(result):
    lines = [f"{'hole':>4} {'edges':>6} {'status':>8} {'class':>7} {'new V':>6} {'new F':>6} {'sec':>7}  reason"]
    for h in result.get("holes", []):
        lines.append(f"{h['hole']:>4} {h['boundary_edges']:>6} {h['status']:>8} {h.get('size_class', ''):>7} "
                     f"{h.get('new_vertices', ''):>6} {h.get('new_faces', ''):>6} {h.get('seconds', float('nan')):>7.3f}"
                     f"  {h.get('reason', '')}")
    summary = {k: v for k, v in result.items() if k not in ("holes", "layer_note")}
    lines.append(", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in summary.items()))
    if result.get("layer_note"):
        lines.append(f"note: {result['layer_note']}")
    return "\n".join(lines)


def cmd_holes(args, extra):
    from .core.holes import boundary_loops, vertex_face_incidence
    from .core.outlines import loops_measured, outlines_one_face

    ms = load_meshset(args.input)
    m = ms.current_mesh()
    V, F = m.vertex_matrix(), m.face_matrix()
    loops = boundary_loops(F)  # the numbering of the filters' per-hole results ("hole")
    incidence = vertex_face_incidence(F, len(V)) if loops else None
    print(f"{m.label()}: {m.vertex_number()} vertices, {m.face_number()} faces, {len(loops)} boundary loops")
    print(f"{'hole':>4} {'edges':>6} {'class':>7} {'perimeter':>11} {'diameter':>10} {'area':>10} {'planarity':>9} "
          f"{'centroid':>32}  notes")
    measured = loops_measured(V, F, loops, incidence)
    for i, loop in enumerate(loops):
        notes = []
        if loop.pinched:
            notes.append("pinched (non-manifold vertex)")
        if not loop.closed or len(loop) < 3:
            notes.append("open chain" if not loop.closed else "degenerate loop")
            print(f"{i:>4} {loop.edge_count:>6} {'':>7} {'':>11} {'':>10} {'':>10} {'':>9} {'':>32}  {', '.join(notes)}")
            continue
        meas, size_class = measured[i]
        outline = size_class == "outline"
        if outlines_one_face(loop):
            notes.append("outline of a single face (its three edges are border edges, not a hole)")
        elif outline:
            notes.append("outline of a whole component (island or outer border, not a hole)")
        centroid = "(" + ", ".join(f"{c:.4g}" for c in meas["centroid"]) + ")"
        print(f"{i:>4} {loop.edge_count:>6} {'outline' if outline else 'hole':>7} {meas['perimeter']:>11.4g} "
              f"{meas['diameter']:>10.4g} {meas['area']:>10.4g} {meas['planarity']:>9.4f} {centroid:>32}  "
              f"{', '.join(notes)}")
    return EXIT_OK


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


def _add_run_options(p):
    p.add_argument("--strict", action="store_true", help="exit with status 1 when any hole to be filled failed")
    talk = p.add_mutually_exclusive_group()
    talk.add_argument("--quiet", "-q", action="store_true", help="no progress bar, no table (errors only)")
    talk.add_argument("--verbose", "-v", action="store_true", help="also a log line per hole on stderr")


def build_parser():
    from ._version import __version__

    parser = argparse.ArgumentParser(prog="meshlab-holefill",
                                     description="Hole-filling filters for pymeshlab (four papers + MeshLab's Close Holes).",
                                     epilog="fill and run: " + EXIT_CODES_HELP)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("fill", help="fill the holes of a mesh with one filter; extra --name value pairs are parameters",
                       description="Fill the holes of INPUT with one filter and save OUTPUT (checked writable "
                                   "first). Filter parameters go as --name value (e.g. --maxholesize 500, "
                                   "--maxholediameter 5%).", epilog=EXIT_CODES_HELP, allow_abbrev=False)
    p.add_argument("input")
    p.add_argument("output", help="the filled mesh; its extension chooses the format (.ply, .obj, .stl, .off, ...)")
    p.add_argument("--filter", default="meshing_close_holes_min_angle_bilateral",
                   help="filter name (ours or any pymeshlab filter, e.g. meshing_close_holes)")
    p.add_argument("--json", action="store_true", help="print the whole result dictionary as JSON")
    p.add_argument("--report", metavar="FILE", help="write the per-hole report: FILE.json (the result) or FILE.csv "
                                                     "(a row per hole)")
    _add_run_options(p)
    p.set_defaults(func=cmd_fill)
    p = sub.add_parser("holes", help="table of boundary loops, numbered as in the filters' results: edges, size "
                                     "class, perimeter, diameter, area, planarity, centroid")
    p.add_argument("input")
    p.set_defaults(func=cmd_holes)
    p = sub.add_parser("filters", help="list the filters with their parameters, defaults and help")
    p.add_argument("name", nargs="?")
    p.set_defaults(func=cmd_filters)
    p = sub.add_parser("compile", help="compile the filters' kernels ahead of their first use (numba's cache; "
                                       "once after an install or an update)")
    p.add_argument("--processes", type=int, default=None, help="processes compiling at once (default: one per core)")
    p.add_argument("--quiet", "-q", action="store_true", help="no table")
    p.set_defaults(func=cmd_compile)
    # Further subcommands (run, compare) register themselves here.
    for register in _SUBCOMMANDS:
        register(sub)
    return parser


_SUBCOMMANDS = []


def cmd_compile(args, extra):
    from .array_api import compile_kernels

    if args.processes is not None and args.processes < 1:
        raise ValueError(f"--processes must be at least 1, got {args.processes}")
    seconds = compile_kernels(args.processes)
    if not args.quiet:
        for label, value in seconds.items():
            print(f"{label:<70} {value:7.1f} s")
    return 0


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
        raise ValueError("run: INPUT and OUTPUT are required (unless --check)")
    from .meshlab.meshset_io import check_mesh_output_path

    check_mesh_output_path(args.output)
    ms = load_meshset(args.input)
    with _Reporting(args):
        results = run_filter_script(ms, script)
    ms.save_current_mesh(args.output)
    if args.record:
        save_filter_script(ms, args.record)
    if args.json:
        print(json.dumps(results, indent=2, default=float))
    elif not args.quiet:
        for step, result in zip(script.steps, results):
            summary = ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}"
                                for k, v in result.items() if k not in ("holes", "layer_note"))
            print(f"#{step.index} {step.mlx_name}" + (f": {summary}" if summary else ""))
            failed = [h for h in result.get("holes", []) if h.get("status") == "failed"]
            for h in failed:
                print(f"   hole {h['hole']} ({h['boundary_edges']} edges) failed: {h.get('reason', '')}")
    return EXIT_STRICT if args.strict and _failed_holes(results) else EXIT_OK


def _register_run(sub):
    p = sub.add_parser("run", help="run a MeshLab .mlx filter script (built-in filters and ours) on a mesh",
                       description="Run a MeshLab .mlx filter script on a mesh and save the result.",
                       epilog=EXIT_CODES_HELP, allow_abbrev=False)
    p.add_argument("script", help=".mlx file (MeshLab FilterScript XML)")
    p.add_argument("input", nargs="?")
    p.add_argument("output", nargs="?")
    p.add_argument("--check", action="store_true", help="only validate the script and list its steps")
    p.add_argument("--record", metavar="MLX", help="also write the filters applied as an .mlx script")
    p.add_argument("--json", action="store_true", help="print the result dictionaries as JSON")
    _add_run_options(p)
    p.set_defaults(func=cmd_run)


_SUBCOMMANDS.append(_register_run)


def cmd_compare(args, extra):
    import shlex

    from .evaluation.compare import compare
    from .evaluation.report.tables import markdown_table as _md_table, summary_table

    command = None
    if args.report:
        options = [f"--report {args.report}", f"--holes {args.holes}", f"--sizes {args.sizes}", f"--seed {args.seed}"]
        options += [f"--filters {shlex.quote(f)}" for f in args.filters or []]
        options += ["--refinehole"] * args.refinehole + ["--no-pictures"] * args.no_pictures
        options += [f"--pictures {args.pictures}"] * (args.pictures is not None)
        command = "meshlab-holefill compare " + " ".join([shlex.quote(m) for m in args.meshes] + options)
    try:
        result = compare(args.meshes, report=args.report, pictures=not args.no_pictures, max_pictures=args.pictures,
                         command=command, holes=args.holes, sizes=args.sizes.split(","), seed=args.seed,
                         filters=args.filters, refinehole=args.refinehole, timeout=args.timeout,
                         maxholesize=args.maxholesize, progress=False if args.quiet else None)
    except ModuleNotFoundError as exc:  # the report's dependencies, checked before any run
        print(f"meshlab-holefill: error: {exc}", file=sys.stderr)
        return 2
    if args.report:
        print(f"report: {args.report}/report.md ({result.wall_seconds:.1f} s)")
    print(_md_table(*summary_table(result)))
    return 0


def _register_compare(sub):
    p = sub.add_parser("compare", help="compare hole fillers on meshes (holes with ground truth cut into closed "
                                       "meshes) and write a report")
    p.add_argument("meshes", nargs="+", metavar="MESH")
    p.add_argument("--report", metavar="DIR", help="write report.md/.html, results.json/.csv and pictures here "
                                                   "(pictures need matplotlib: pip install \"meshlab_holefill[bench]\")")
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
    p.add_argument("--pictures", type=int, metavar="N", help="picture at most N holes per mesh, those with the most "
                                                             "boundary edges (default: every hole)")
    p.add_argument("--quiet", action="store_true", help="no progress bar (shown only when stderr is a terminal)")
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
