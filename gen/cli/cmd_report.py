"""``npstereo report``: FPGA resources and clock of generated cores, beside the paper's.

One configuration (``--transform ... --width ... --height ...``) prints a table per target;
``--paper`` runs the paper's sweep (four transforms x blocks 7..19 at 450 x 375, D = 100,
R = 10) and writes markdown, JSON and PNG plots; ``--camera`` the camera-rate
configurations (:mod:`npstereo.gen.reports.camera`), markdown and JSON. A sweep's
configurations are tasks on
Dask distributed (:mod:`npstereo.gen.explore.engine`: an embedded LocalCluster, or
``--scheduler``). Results are cached by configuration, generated Verilog and tool versions
(:mod:`npstereo.gen.reports.cache`), so a rerun only synthesises what changed.
"""

import dataclasses
import json
import math
import sys
from pathlib import Path

from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES, MAX_WIDTH, check_buildable
from ...params import TRANSFORMS, StereoParams, UserError
from ..atomic import write_text
from ..explore.engine import Task, TaskFailure, check_engine_arguments, cluster, run_tasks, \
    task_key
from ..flow.capacity import DEFAULT_DEVICE
from ..flow.nextpnr import BOX_R1_TIMING_WEIGHT, PLACEMENT_RANGES, Placement, out_of_range
from ..flow.tools import TARGETS, tool_versions
from ..reports.cache import earlier_reports, seed_cache, source_hash
from ..reports.camera import CAMERA_FORMATS, CAMERA_MATCHERS, CAMERA_ROUNDS, CAMERA_TRANSFORMS, \
    camera_configurations
from ..reports.paper_data import PAPER_BLOCKS, PAPER_DISPARITIES, PAPER_ROUNDS, PAPER_SIZE, \
    is_default_line_buffer, paper_configurations, sweep_targets
from ..reports.plots import camera_plot, sweep_plots
from ..reports.synthesis import failed_report, lookup, store_report, synthesis_job
from ..reports.tables import camera_markdown, format_table, sweep_markdown
from .arguments import add_engine_arguments, add_hardware_arguments, \
    add_matching_arguments, add_synthesis_arguments, check_output_file, check_output_folder, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run", "run_sweep", "synthesis_tasks", "sweep_pnr"]

DESCRIPTION = ("Synthesise generated cores with Yosys (Cyclone V, ECP5) and nextpnr; report "
               "logic, registers, RAM, memory bits, Fmax and frame rate.")


def _order(params):
    """A configuration's identity (a document's older reports may lack newer fields, which
    take their defaults)."""
    return repr(StereoParams(**params))


def _status_line(report):
    return ", ".join(f"{t} {_status(r)}" + (" (cached)" if r.get("cached") else "")
                     for t, r in report["results"].items())


def _status(result):
    """``ok``, or the status and its message (once: a fit verdict is its own status)."""
    status, message = result["status"], result.get("message", "")
    if status == "ok":
        return status
    return message if message.startswith(status) else f"{status} ({message})"


#: Each of :class:`~..flow.nextpnr.Placement`'s choices: its option, and what it is.
PLACEMENT_OPTIONS = {"seed": ("--seed", "nextpnr's placer seed"),
                     "timing_weight": ("--placer-timing-weight",
                                       "nextpnr's placer's weight of timing"),
                     "alt_weights": ("--router-alt-weights",
                                     "router2's alternate weights")}


def sweep_pnr(params, pnr):
    """Whether the paper sweep places and routes ``params``: with ``--pnr``, the line
    buffer ``auto`` chooses (the other variants are synthesised only: place and route is
    the sweep's longest part, and the default is what a user gets)."""
    return pnr and is_default_line_buffer(params)


def synthesis_tasks(configurations, targets, pnr, freq, timeout, cache, engine,
                    device=DEFAULT_DEVICE):
    """``(reports from the cache, tasks for the rest)`` of a sweep: one :class:`Task` per
    configuration not wholly in ``cache``: default line buffers first (what a user gets),
    then cheap cells first (ext. census takes many times longer than the other three),
    so that a sweep stopped early holds the cells that matter most. Only default line
    buffers are placed and routed (:func:`sweep_pnr`).
    """
    cached, tasks = [], []
    for p in sorted(configurations, key=lambda p: (not is_default_line_buffer(p),
                                                   p.transform == "ext-census", p.block,
                                                   p.stored_rows, p.lut_inputs)):
        p_targets = sweep_targets(p, targets)
        if not p_targets:
            continue
        p_pnr = sweep_pnr(p, pnr)
        report = lookup(p, p_targets, p_pnr, freq, cache, device)
        if report is not None:
            cached.append(report)
            continue
        key = task_key("synthesis", repr(p), list(p_targets), p_pnr, freq, timeout, engine,
                       device, source_hash())
        tasks.append(Task(key, synthesis_job, (p, p_targets, p_pnr, freq, timeout,
                                      None if cache is None else str(cache), engine, device),
                          p.describe()))
    return cached, tasks


def run_sweep(configurations, targets, pnr, freq, timeout, cache, client, progress=None,
              engine=None, earlier=None):
    """Evaluate configurations as tasks on ``client``'s Dask cluster, with a progress bar
    on stderr and a line per finished configuration.

    What the cache holds is not submitted. ``progress(reports)`` is called with the
    reports so far before the first task and after each configuration, so a long sweep
    leaves its partial results behind; a configuration still to run is among them with the
    targets the cache holds of it, and for the others what ``earlier`` (reports of an
    earlier sweep document that still hold, by ``repr`` of their configuration) recorded
    (a timeout is not cached), marked ``earlier``; absent where neither has it.
    """
    reports, tasks = synthesis_tasks(configurations, targets, pnr, freq, timeout, cache,
                                     engine)
    for report in reports:
        print(f"{StereoParams(**report['params']).describe()}: {_status_line(report)}",
              file=sys.stderr)
    # What the cache already holds of the configurations still to run (a target another
    # sweep measured): in the document until their task finishes, so a sweep stopped early
    # shows every figure there is.
    partial = {task.key: _still_to_run(task.args[0], task.args[1], pnr, freq, cache,
                                       (earlier or {}).get(repr(task.args[0])))
               for task in tasks}

    def so_far():
        return _in_order(reports + [r for r in partial.values() if r is not None],
                         configurations)

    def finished(task, report, write):
        if isinstance(report, TaskFailure):  # the task killed its workers
            report = failed_report(task.args[0], task.args[1], report.message)
        store_report(report, cache, sweep_pnr(StereoParams(**report["params"]), pnr), freq)
        write(f"{task.label}: {_status_line(report)}")
        reports.append(report)
        partial.pop(task.key)
        if progress is not None:
            progress(so_far())

    if progress is not None and tasks:
        progress(so_far())
    run_tasks(client, tasks, "synthesis", on_result=finished)
    return _in_order(reports, configurations)


def _still_to_run(params, targets, pnr, freq, cache, before):
    """The document's report of a configuration whose task has not finished: what the
    cache holds of it, the rest from the earlier document's report ``before``."""
    report = lookup(params, targets, sweep_pnr(params, pnr), freq, cache, partial=True)
    if before is None:
        return report
    results = {t: dict(before["results"][t], earlier=True) for t in targets
               if t in before["results"]}
    results.update({} if report is None else report["results"])
    return dict(report or before, results=results) if results else None


def _in_order(reports, configurations):
    order = {_order(dataclasses.asdict(p)): i for i, p in enumerate(configurations)}
    return sorted(reports, key=lambda r: order[_order(r["params"])])


#: What each sweep is called in its folder, and how its markdown is written (the paper's
#: sweep also draws its plots).
SWEEPS = {"paper": ("sweep", sweep_markdown), "camera": ("camera", camera_markdown)}


def _write_sweep(reports, out, sweep="paper"):
    """Write the sweep's JSON, markdown and plots (after every configuration)."""
    name, markdown = SWEEPS[sweep]
    document = {"tools": tool_versions(), "hdl_sources": source_hash(), "reports": reports}
    write_text(out / f"{name}.json", json.dumps(document, indent=1) + "\n")
    write_text(out / f"{name}.md", markdown(reports))
    written = [out / f"{name}.json", out / f"{name}.md"]
    return written + (sweep_plots if sweep == "paper" else camera_plot)(reports, out)


def add_arguments(parser):
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES, subpixel=True)
    add_hardware_arguments(parser)
    parser.add_argument("--width", type=int,
                        help=f"image width, at most {MAX_WIDTH} (required without --paper)")
    parser.add_argument("--height", type=int, help="image height (required without --paper)")
    parser.add_argument("--target", choices=TARGETS + ("all",), default="cyclonev",
                        help="synthesis target (default cyclonev)")
    add_synthesis_arguments(parser, "configuration and target")
    parser.add_argument("--seed", type=int, default=None,
                        help="nextpnr's placer seed for one configuration with --pnr "
                             "({} to {}; default nextpnr's own): another placement "
                             .format(*PLACEMENT_RANGES["seed"]) +
                             "of the same netlist, for the run-to-run spread of the clock")
    parser.add_argument("--placer-timing-weight", type=int, default=None, metavar="N",
                        help="the weight of timing in nextpnr's placer for one configuration "
                             "with --pnr ({} to {}; ".format(*PLACEMENT_RANGES["timing_weight"]) +
                             f"default {BOX_R1_TIMING_WEIGHT} for a box core at R = 1, "
                             "nextpnr's own, 10, otherwise): another placement, "
                             "docs/synthesis-flow.md")
    parser.add_argument("--router-alt-weights", action="store_true",
                        help="route one configuration with --pnr by router2's alternate "
                             "weights (--router2-alt-weights): another route of the same "
                             "placement, docs/synthesis-flow.md")
    parser.add_argument("--json", type=Path, help="write the results as JSON")
    width, height = PAPER_SIZE
    parser.add_argument("--paper", action="store_true",
                        help=f"the paper's sweep: {len(TRANSFORMS)} transforms x blocks "
                             f"{PAPER_BLOCKS[0]}..{PAPER_BLOCKS[-1]}, {width}x{height}, "
                             f"D={PAPER_DISPARITIES}, R={PAPER_ROUNDS}")
    sizes = ", ".join(f"{w}x{h} D={'/'.join(map(str, d))}" for w, h, d in CAMERA_FORMATS)
    blocks = "/".join(f"{b}x{b}" for _, b in CAMERA_TRANSFORMS)
    parser.add_argument("--camera", action="store_true",
                        help=f"the camera-rate sweep: census {blocks} at {sizes}, " +
                             ", ".join(f"{CAMERA_MATCHERS[a]} at R={'/'.join(map(str, r))}"
                                       for a, r in CAMERA_ROUNDS.items()))
    add_engine_arguments(parser)
    parser.add_argument("--out", type=Path, default=Path("docs/resources"),
                        help="output folder of --paper and --camera (default docs/resources)")
    parser.set_defaults(run=run)


def _sweep(args):
    """Which sweep the arguments ask for: "paper", "camera" or None (one configuration)."""
    if args.paper and args.camera:
        raise UserError("--paper and --camera are two sweeps: choose one")
    return "paper" if args.paper else "camera" if args.camera else None


def _check(args):
    check_engine_arguments(args.workers, args.scheduler)
    sweep = _sweep(args)
    if sweep is None and (args.scheduler is not None or args.workers is not None):
        raise UserError("--scheduler and --workers are for --paper or --camera: one "
                        "configuration is synthesised here")
    if not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UserError(f"--timeout must be a positive number of seconds, not {args.timeout:g}")
    if not (args.freq > 0 and math.isfinite(args.freq)):
        raise UserError(f"--freq must be a positive clock in MHz, not {args.freq:g}")
    if args.pnr and args.target == "cyclonev":
        raise UserError("--pnr places and routes for ecp5: use --target ecp5 or all")
    for field, (option, what) in PLACEMENT_OPTIONS.items():
        value = getattr(args, _placement_dest(option))
        if value is None or value is False:
            continue
        message = out_of_range(field, value, option) if field in PLACEMENT_RANGES else None
        if message is not None:
            raise UserError(message)
        if not args.pnr:
            raise UserError(f"{option} is {what}: it needs --pnr")
        if sweep is not None:
            raise UserError(f"{option} places one configuration: drop --{sweep}")
    if args.json is not None:
        if args.json.is_dir():
            raise UserError(f"--json {args.json} is a folder, not a file")
        check_output_file(args.json, "--json")
    if args.paper and (args.width is not None or args.height is not None):
        width, height = PAPER_SIZE
        raise UserError(f"--paper uses the paper's {width}x{height} frames: drop "
                        "--width/--height")
    if args.camera and (args.width is not None or args.height is not None):
        raise UserError("--camera uses the camera formats' frames: drop --width/--height")
    if sweep is not None:
        check_output_folder(args.out)


def _placement_dest(option):
    return option[2:].replace("-", "_")


def _placement(args):
    """The placer's choices the options give (checked by :func:`_check`)."""
    return Placement(**{field: getattr(args, _placement_dest(option))
                        for field, (option, _) in PLACEMENT_OPTIONS.items()})


def run(args):
    _check(args)
    targets = TARGETS if args.target == "all" else (args.target,)
    cache = None if args.no_cache else args.cache
    sweep = _sweep(args)
    if sweep is not None:
        configurations = paper_configurations() if args.paper else camera_configurations()
        document_path = args.out / f"{SWEEPS[sweep][0]}.json"
        earlier = {}
        if cache is not None:
            seeded = seed_cache(document_path, cache)
            if seeded:
                print(f"resuming: {seeded} results taken from {document_path}",
                      file=sys.stderr)
            earlier = {repr(p): report for p, _, report
                       in earlier_reports(document_path, cache)}
    else:
        if args.width is None or args.height is None:
            raise UserError("--width and --height are required (or use --paper or --camera)")
        configurations = [params_from_args(args).with_size(args.width, args.height)]
        check_buildable(configurations[0])
    if sweep is not None:
        with cluster(args.scheduler, args.workers) as client:
            reports = run_sweep(configurations, targets, args.pnr, args.freq, args.timeout,
                                cache, client, engine=args.yosys,
                                progress=lambda done: _write_sweep(done, args.out, sweep),
                                earlier=earlier)
    else:
        reports = [synthesis_job(configurations[0], targets, args.pnr, args.freq,
                                 args.timeout, cache, args.yosys,
                                 placement=_placement(args))]
        print(f"{configurations[0].describe()}: {_status_line(reports[0])}", file=sys.stderr)
    document = {"tools": tool_versions(), "reports": reports}
    if sweep is not None:
        for path in _write_sweep(reports, args.out, sweep):
            print(f"wrote {path}")
    else:
        print(format_table(reports[0]))
    if args.json:
        write_text(args.json, json.dumps(document, indent=1) + "\n")
    # A core too big for the device is an answer, not a failure of the tool.
    failed = [r for report in reports for r in report["results"].values()
              if r["status"] not in ("ok", "does not fit")]
    return 1 if failed and sweep is None else 0
