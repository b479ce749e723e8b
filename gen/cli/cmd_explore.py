"""``npstereo explore``: which configuration for my device? Quality x logic x memory x
clock of a grid, every evaluation a task on Dask distributed.

Writes ``explore.json`` (every point, the Pareto front, the recommendation, the device
table), ``explore.md`` and ``pareto.png`` into ``--out``; :mod:`npstereo.gen.explore.explorer`
does the work, :mod:`npstereo.gen.explore.engine` runs it (an embedded LocalCluster, or
``--scheduler``).
"""

import json
import math
import sys
import time
from pathlib import Path

from ...golden.data import load_middlebury
from ...golden.synthetic import synthetic_pair
from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES
from ...params import COST_TERMS, LINE_BUFFERS, MAX_SUBPIXEL_BITS, TRANSFORMS, UserError
from ..atomic import write_text
from ..explore.engine import check_engine_arguments, cluster
from ..explore.explorer import Grid, configurations, explore
from ..flow.capacity import DEVICES
from ..flow.tools import tool_versions
from ..matching import Condition, condition_images
from ..reports.plots import pareto_plot
from .arguments import STEREO_DEFAULTS, add_engine_arguments, add_lr_arguments, \
    add_synthesis_arguments, check_output_folder

__all__ = ["DESCRIPTION", "add_arguments", "run", "conditions", "load_scenes", "write_outputs"]

DESCRIPTION = ("Evaluate a grid of configurations on a scene (correct matches, clean and "
               "degraded) and in synthesis for a device (logic, registers, memory bits, logic "
               "depth; nextpnr Fmax with --pnr), every evaluation a task on Dask distributed; "
               "write explore.json, explore.md and pareto.png with the Pareto front and a "
               "recommendation.")


def _aggregation(text):
    """An aggregation value as given: an integer, or a name (``sgm``) passed on as is."""
    try:
        return int(text)
    except ValueError:
        return text


def _on_off(values):
    """An off/on axis (``--median``, ``--fifth-path``): off without the option, on with the
    bare flag, else as listed."""
    if values is None:
        return (False,)
    return tuple(value == "on" for value in values) if values else (True,)


def _cost_terms(values):
    """The cost-term axis: ``none`` is the census cost alone (None)."""
    return tuple(None if value == "none" else value for value in values)


def conditions(noise, bayer, seed):
    """Clean first, then noise and the Bayer stand-in where asked for."""
    chosen = [Condition(seed=seed)]
    if noise:
        chosen.append(Condition(noise=noise, seed=seed))
    if bayer:
        chosen.append(Condition(bayer=True, seed=seed))
    return chosen


def load_scenes(pair, chosen):
    """``{condition label: (left, right, ground truth)}`` of ``pair``."""
    if pair.ground_truth is None:
        raise UserError(f"dataset {pair.name} has no ground truth to evaluate against")
    return {c.label: (*condition_images(pair, c), pair.ground_truth) for c in chosen}


def _number(value, digits=0, suffix=""):
    return "-" if value is None else f"{value:,.{digits}f}{suffix}"


def _quality_cells(point, labels):
    """Correct matches under each condition, and the clean mean error of the correct pixels
    (what a sub-pixel fraction brings down; a result cached before it was measured: -)."""
    return [_number(point["quality"][label].get("correct"), 2) for label in labels] + [
        _number(point["quality"][labels[0]].get("mean_error"), 3)]


def _device_table(dev):
    lines = [f"{dev.part} (`--device {dev.name}`), measured by the `{dev.target}` synthesis"
             + (f"; {dev.note}" if dev.note else "") + ".", "",
             "| resource | capacity | unit | reference |", "|---|---:|---|---|"]
    lines += [f"| {r.name} | {r.capacity:,} | {r.unit} | {r.reference} |"
              for r in dev.resources]
    lines.append(f"| block RAM bits | {dev.block_ram_bits:,} | bit | from the row above |")
    if dev.memory_bits != dev.block_ram_bits:
        lines.append(f"| memory bits | {dev.memory_bits:,} | bit | block RAM and LUTRAM (64 "
                     "bits each): what a core's memories are checked against before synthesis |")
    return lines


def explore_markdown(document):
    """``explore.md``: the grid's table, the recommendation, the device and the run."""
    dev = DEVICES[document["device"]["name"]]
    labels = document["conditions"]
    unit = dev.logic_resource.name
    ram = dev.resources[2].name
    lines = [f"# Design space on {dev.part}", "",
             f"Scene {document['scene']}; hardware {document['width']}x{document['height']}, "
             f"D={document['disparities']}; frames/s at "
             + ("nextpnr's Fmax." if document["pnr"] else
                f"an assumed {document['clock_mhz']:g} MHz clock (no place and route).")
             + " Correct matches: |d - gt| <= 1 over pixels with known ground truth and "
               "x >= D, invalid counted wrong. ◆ marks the Pareto front (no other point "
               "has more correct matches with less logic).", "",
             "| configuration | " + " | ".join(f"correct {label} (%)" for label in labels)
             + f" | mean error {labels[0]} (levels) | {unit} (%) | FF | memory bits "
               f"| {ram} (%) | LUT levels | Fmax MHz | frames/s | device | front |",
             "|---|" + "---:|" * (len(labels) + 1)
             + "---:|---:|---:|---:|---:|---:|---:|---|---|"]
    for i, p in enumerate(document["points"]):
        use = p["utilisation"] or {}
        mark = "◆" if p["pareto"] else ""
        if i == document["recommendation"]:
            mark += " recommended"
        lines.append("| " + " | ".join([
            p["label"], *_quality_cells(p, labels),
            "-" if p["logic"] is None else f"{p['logic']:,} ({use.get(unit, 0):.1f})",
            _number(p["registers"]), _number(p["memory_bits"]),
            "-" if p["used"] is None else f"{p['used'][ram]:,} ({use.get(ram, 0):.1f})",
            _number(p["logic_levels"], 1), _number(p["fmax_mhz"], 1),
            _number(p["frames_per_second"], 1), p["verdict"], mark]) + " |")
    choice = document["recommendation"]
    lines += ["", "## Recommendation", ""]
    if choice is None:
        lines.append(f"None: {document['recommendation_reason']}.")
    else:
        p = document["points"][choice]
        lines.append(f"**{p['label']}** ({document['recommendation_reason']}): "
                     f"{p['quality'][labels[0]]['correct']:.2f} % correct (clean), "
                     f"{p['logic']:,} {unit}, {p['memory_bits']:,} memory bits, "
                     f"{_number(p['frames_per_second'], 1)} frames/s.")
    lines += ["", "![Pareto plot](pareto.png)", "", "## Device", ""] + _device_table(dev)
    tasks = document["tasks"]
    lines += ["", "## Run", "",
              f"{len(document['points'])} configurations, {tasks['submitted']} tasks "
              f"submitted, {len(tasks['computed'])} evaluations computed (the rest from the "
              f"cache), {len(tasks['failed'])} failed; {document['seconds']:.0f} s wall "
              f"time on {document['engine']}."]
    if document["skipped"]:
        lines += ["", "Skipped combinations:", ""] + [f"- {s}" for s in document["skipped"]]
    if tasks["failed"]:
        lines += ["", "Failed:", ""] + [f"- {f}" for f in tasks["failed"]]
    return "\n".join(lines) + "\n"


def _short_labels(points):
    """Labels of only the axes that vary across the grid (transform and block always)."""
    params = [p["params"] for p in points]
    varying = [key for key in ("rounds", "aggregation", "line_buffer", "cost_term",
                               "fifth_path", "median", "subpixel_bits")
               if len({p[key] for p in params}) > 1]
    short = {"rounds": "R", "aggregation": "A", "line_buffer": "", "subpixel_bits": "F"}
    switches = {"median": ("median", "no median"), "fifth_path": ("5 paths", "4 paths")}

    def value(p, key):
        if key in switches:
            return switches[key][0] if p[key] else switches[key][1]
        if key == "cost_term":
            return f"+{p[key]}" if p[key] else "no term"
        return f"{short[key]}{'=' if short[key] else ''}{p[key]}"
    return [" ".join([p["transform"], str(p["block"])] + [value(p, k) for k in varying])
            for p in params]


def write_outputs(document, out):
    """Write ``explore.json``, ``explore.md`` and ``pareto.png`` (each atomically)."""
    out = Path(out)
    dev = DEVICES[document["device"]["name"]]
    write_text(out / "explore.json", json.dumps(document, indent=1) + "\n")
    write_text(out / "explore.md", explore_markdown(document))
    colour = (("fmax_mhz", "Fmax MHz (nextpnr)") if document["pnr"] else
              ("logic_levels", "LUT levels of the deepest path (synthesis; no --pnr)"))
    pareto_plot(out / "pareto.png", document["points"], _short_labels(document["points"]),
                document["pareto"], document["recommendation"], dev, *colour,
                f"{dev.part}: correct matches against logic, {document['scene']}, "
                f"{document['width']}x{document['height']} D={document['disparities']} "
                f"(size: memory bits)")
    return [out / "explore.json", out / "explore.md", out / "pareto.png"]


def _check(args):
    check_engine_arguments(args.workers, args.scheduler)
    dev = DEVICES[args.device]
    if args.pnr and dev.nextpnr is None:
        ecp5 = ", ".join(name for name, d in DEVICES.items() if d.nextpnr)
        raise UserError(f"--pnr places and routes ECP5 parts ({ecp5}), not {args.device}")
    for option, value in (("--timeout", args.timeout), ("--freq", args.freq),
                          ("--clock", args.clock)):
        if not (value > 0 and math.isfinite(value)):
            raise UserError(f"{option} must be a positive number, not {value:g}")
    if args.min_fps is not None and not (args.min_fps > 0 and math.isfinite(args.min_fps)):
        raise UserError(f"--min-fps must be a positive number, not {args.min_fps:g}")
    if args.noise < 0:
        raise UserError(f"--noise must be a variance >= 0, not {args.noise:g}")
    check_output_folder(args.out)
    return dev


def run(args):
    dev = _check(args)
    grid = Grid(transforms=tuple(args.transform), blocks=tuple(args.block),
                rounds=tuple(args.rounds), aggregations=tuple(args.aggregation),
                line_buffers=tuple(args.line_buffer), disparities=args.disparities,
                width=args.width, height=args.height,
                lr_threshold=None if args.no_lr_check else args.lr_threshold,
                lut_inputs=dev.lut_inputs, medians=_on_off(args.median),
                subpixel_bits=tuple(args.subpixel_bits),
                fifth_paths=_on_off(args.fifth_path),
                cost_terms=_cost_terms(args.cost_term))
    configs, skipped = configurations(grid)
    pair = (synthetic_pair(args.width, args.height, args.disparities, args.seed)
            if args.synthetic else load_middlebury(args.dataset))
    scenes = load_scenes(pair, conditions(args.noise, args.bayer, args.seed))
    cache = None if args.no_cache else args.cache
    for line in skipped:
        print(f"skipped {line}", file=sys.stderr)
    started = time.monotonic()
    with cluster(args.scheduler, args.workers) as client:
        engine = (f"the Dask scheduler at {args.scheduler}" if args.scheduler else
                  f"an embedded LocalCluster of {len(client.scheduler_info()['workers'])} "
                  "workers")
        result = explore(client, configs, scenes, dev, pnr=args.pnr, freq=args.freq,
                         timeout=args.timeout, cache=cache, engine=args.yosys,
                         clock=args.clock, min_fps=args.min_fps)
    document = {"device": {"name": dev.name, "part": dev.part, "target": dev.target,
                           "block_ram_bits": dev.block_ram_bits,
                           "memory_bits": dev.memory_bits,
                           "resources": [r.__dict__ for r in dev.resources]},
                "scene": pair.name, "conditions": list(scenes), "width": args.width,
                "height": args.height, "disparities": args.disparities, "pnr": args.pnr,
                "clock_mhz": args.clock, "min_fps": args.min_fps, "skipped": skipped,
                "tools": tool_versions(), "engine": engine,
                "seconds": round(time.monotonic() - started, 1), **result}
    written = write_outputs(document, args.out)
    choice = result["recommendation"]
    if choice is None:
        print(f"no recommendation: {result['recommendation_reason']}")
    else:
        point = result["points"][choice]
        print(f"recommended for {dev.part}: {point['label']} "
              f"({point['quality'][next(iter(scenes))]['correct']:.2f} % correct, "
              f"{point['logic']:,} {dev.logic_resource.name}, {point['verdict']})")
    print(f"{len(configs)} configurations, {len(result['tasks']['computed'])} evaluations "
          f"computed, {document['seconds']:.0f} s; wrote " + ", ".join(map(str, written)))
    return 1 if result["tasks"]["failed"] else 0


def add_arguments(parser):
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", metavar="DIR", help="Middlebury scene folder")
    source.add_argument("--synthetic", action="store_true",
                        help="the synthetic scene at --width x --height (seeded by --seed)")
    parser.add_argument("--transform", nargs="*", choices=TRANSFORMS, default=list(TRANSFORMS),
                        help="transforms of the grid (default all four)")
    parser.add_argument("--block", nargs="*", type=int, default=[STEREO_DEFAULTS["block"]],
                        help=f"block sizes B of the grid, odd >= 3, at most {MAX_BLOCK} "
                             f"(default {STEREO_DEFAULTS['block']})")
    parser.add_argument("--rounds", nargs="*", type=int, default=[STEREO_DEFAULTS["rounds"]],
                        help=f"calculation rounds R of the grid, each dividing D "
                             f"(default {STEREO_DEFAULTS['rounds']})")
    parser.add_argument("--aggregation", nargs="*", type=_aggregation,
                        default=[STEREO_DEFAULTS["aggregation"]],
                        help=f"aggregation windows A of the grid, odd >= 1 "
                             f"(default {STEREO_DEFAULTS['aggregation']})")
    parser.add_argument("--line-buffer", nargs="*", choices=LINE_BUFFERS,
                        default=[STEREO_DEFAULTS["line_buffer"]],
                        help=f"rows above kept as transforms or costs "
                             f"(default {STEREO_DEFAULTS['line_buffer']})")
    parser.add_argument("--median", nargs="*", choices=("off", "on"),
                        help="the 3x3 median of the output (docs/semantics.md): --median "
                             "alone puts it on every configuration, --median off on "
                             "compares both (default off)")
    parser.add_argument("--fifth-path", nargs="*", choices=("off", "on"),
                        help="SGM's fifth path, right to left along the row (docs/sgm.md; "
                             "needs sgm among the --aggregation values, box configurations "
                             "are taken once without it): --fifth-path alone puts it on "
                             "every SGM configuration, --fifth-path off on compares both "
                             "(default off)")
    parser.add_argument("--cost-term", nargs="*", choices=("none", *COST_TERMS),
                        default=["none"],
                        help=f"terms added to the census cost of the SGM configurations: "
                             f"none or {', '.join(COST_TERMS)} (docs/semantics.md); "
                             f"--cost-term none ad3 compares both (default none)")
    parser.add_argument("--subpixel-bits", nargs="*", type=int, metavar="F",
                        default=[STEREO_DEFAULTS["subpixel_bits"]],
                        help=f"fractional bits F of the grid, 0 .. {MAX_SUBPIXEL_BITS}; "
                             f"quality scores the fractional disparities "
                             f"(default {STEREO_DEFAULTS['subpixel_bits']})")
    parser.add_argument("--disparities", type=int, default=STEREO_DEFAULTS["disparities"],
                        help=f"disparity range D, at most {MAX_DISPARITIES} "
                             f"(default {STEREO_DEFAULTS['disparities']})")
    add_lr_arguments(parser)
    parser.add_argument("--width", type=int, required=True,
                        help="frame width of the hardware (and of the synthetic scene)")
    parser.add_argument("--height", type=int, required=True,
                        help="frame height of the hardware (and of the synthetic scene)")
    parser.add_argument("--device", required=True, choices=list(DEVICES),
                        help="the device the cores must fit (docs/explore.md lists them)")
    parser.add_argument("--clock", type=float, default=100.0,
                        help="clock in MHz for frames/s without --pnr (default 100, the "
                             "paper's clock at 7x7)")
    parser.add_argument("--min-fps", type=float,
                        help="frames/s the recommendation must reach")
    parser.add_argument("--noise", type=float, default=0.0, metavar="VAR",
                        help="also measure quality under gaussian noise of this variance")
    parser.add_argument("--bayer", action="store_true",
                        help="also measure quality on the Bayer stand-in")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the synthetic scene and the noise (default 0)")
    add_synthesis_arguments(parser, "synthesis")
    add_engine_arguments(parser)
    parser.add_argument("--out", type=Path, required=True, help="output folder")
    parser.set_defaults(run=run)
