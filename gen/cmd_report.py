"""``npstereo report``: FPGA resources and clock of generated cores, beside the paper's.

One configuration (``--transform ... --width ... --height ...``) prints a table per target;
``--paper`` runs the paper's sweep (four transforms x blocks 7..19 at 450 x 375, D = 100,
R = 10) and writes markdown, JSON and PNG plots. Results are cached by configuration, HDL
source and tool versions, so a rerun only synthesises what changed.
"""

import gc
import hashlib
import json
import math
import os
import sys
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from ..golden.params import TRANSFORMS, StereoParams, UserError
from .atomic import atomic_path, write_text
from .cmd_match import add_matching_arguments, params_from_args
from .synth import TARGETS, synthesise, tool_versions

__all__ = ["add_parser", "run", "PAPER_LOGIC", "PAPER_MEMORY", "PAPER_CLOCK", "PAPER_BLOCKS",
           "cycles_per_frame", "expected_memory_bits", "evaluate"]

#: Block sizes of the paper's figures 13 and 14.
PAPER_BLOCKS = (7, 9, 11, 13, 15, 17, 19)
#: Stratix II logic elements (Fig. 13); None where the design did not fit and no figure exists.
PAPER_LOGIC = {
    "rank": (10174, 13514, 17475, 21999, 23554, 28686, 34053),
    "ext-rank": (17624, 24673, 33179, 43406, 52356, 64524, 79015),
    "census": (17713, 26788, 38006, 51370, 62998, 79664, 97824),
    "ext-census": (80598, 131616, 148213, 205448, 272068, 348133, None),
}
#: Blocks where the paper's ext. census did not fit the EP2S180 (figure value still given).
PAPER_DID_NOT_FIT = {("ext-census", b) for b in (11, 13, 15, 17, 19)}
_RANK_MEMORY = (557056, 589824, 622592, 655360, 688128, 720896, 753664)
_CENSUS_MEMORY = (688128, 720896, 753664, 786432, 819200, 851968, 884736)
#: Memory bits (Fig. 14).
PAPER_MEMORY = {"rank": _RANK_MEMORY, "ext-rank": _RANK_MEMORY,
                "census": _CENSUS_MEMORY, "ext-census": _CENSUS_MEMORY}
#: The paper's clock in MHz, given only at the ends of the sweep.
PAPER_CLOCK = {7: 100.0, 19: 50.0}
PAPER_SIZE = (450, 375)
PAPER_DISPARITIES, PAPER_ROUNDS = 100, 10

_HDL_DIR = Path(__file__).resolve().parent.parent / "hdl"
_PARAMS_FILE = Path(__file__).resolve().parent.parent / "golden" / "params.py"


def cycles_per_frame(params):
    """Clocks per frame: (W x H pixels + flush positions) x R rounds.

    The flush is the core's latency in positions: after the last pixel it feeds that many
    dummy positions until the frame's last output word is out.
    """
    from amaranth.hdl import UnusedElaboratable

    from ..hdl.core import NpStereoCore
    # The core is built only to ask its latency; it is never elaborated, which Amaranth
    # would otherwise warn about when the objects are collected.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnusedElaboratable)
        core = NpStereoCore(params)
        latency = core.latency
        del core
        gc.collect()
    return (params.width * params.height + latency) * params.rounds


def expected_memory_bits(params):
    """Bits the core's memories must hold, from the architecture (docs/resources.md).

    Two image line buffers of B-1 lines of 8-bit pixels, and (aggregation A > 1) the cost
    line buffer of A-1 lines of D costs per column.
    """
    lines = 2 * params.width * 8 * (params.block - 1)
    costs = params.width * (params.aggregation - 1) * params.disparities * params.cost_bits
    return lines + costs


def _source_hash():
    """Digest of the HDL sources: the fast path to a configuration's Verilog digest."""
    digest = hashlib.sha256()
    for path in sorted(_HDL_DIR.rglob("*.py")) + [_PARAMS_FILE]:
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]


def verilog_digest(text):
    """Digest of generated Verilog without its header comment (which names versions)."""
    body = "\n".join(line for line in text.splitlines() if not line.startswith("//"))
    return hashlib.sha256(body.encode()).hexdigest()[:24]


def _digest_memo(params, cache):
    if cache is None:
        return None
    name = hashlib.sha256(f"{_source_hash()} {params!r}".encode()).hexdigest()[:24]
    return Path(cache) / "verilog" / f"{name}.txt"


def configuration_digest(params, cache=None):
    """Digest of the Verilog that ``params`` generates, memoised per HDL source version.

    A synthesis result depends on the Verilog and the tools, nothing else: keying the
    cache on the Verilog keeps results across HDL changes that generate the same netlist
    (a wrapper, a comment) and drops them after any change that does not. Generating
    a large core takes up to half a minute, so the digest is remembered in ``cache``
    under the source digest.
    """
    return _design(params, cache)[0]


def _design(params, cache):
    """``(digest, verilog)``; ``verilog`` is None when the digest came from the memo."""
    memo = _digest_memo(params, cache)
    if memo is not None and memo.exists():
        return memo.read_text().strip(), None
    from .verilog import core_verilog
    verilog = core_verilog(params)
    digest = verilog_digest(verilog)
    if memo is not None:
        write_text(memo, digest + "\n")
    return digest, verilog


def _cache_key(params, target, pnr, freq, design):
    if target != "ecp5" or not pnr:
        pnr, freq = False, None  # only nextpnr depends on them
    text = json.dumps({"params": repr(params), "target": target, "pnr": pnr, "freq": freq,
                       "tools": tool_versions(), "verilog": design}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def seed_cache(sweep_json, cache):
    """Put the results of an earlier sweep document into the cache; returns how many.

    A sweep is committed with the repository (docs/resources/sweep.json) but the cache
    lives on one machine: this lets a fresh machine resume the sweep instead of
    synthesising for hours what the document already holds. A result is taken only for
    the same tool versions and the same generated Verilog (``verilog_sha`` of its report;
    a document without it must come from the current HDL sources).
    """
    try:
        document = json.loads(Path(sweep_json).read_text())
    except (OSError, ValueError):
        return 0
    if document.get("tools") != tool_versions():
        return 0
    same_sources = document.get("hdl_sources") == _source_hash()
    seeded = 0
    for report in document.get("reports", []):
        params = StereoParams(**report["params"])
        design = configuration_digest(params, cache)
        if report.get("verilog_sha", design if same_sources else None) != design:
            continue
        for target, result in report["results"].items():
            if result.get("status") not in ("ok", "failed"):
                continue
            if target == "ecp5" and "freq" not in result:
                continue  # an older result that did not record its nextpnr settings
            key = _cache_key(params, target, result.get("pnr", False), result.get("freq"),
                             design)
            path = Path(cache) / f"{key}.json"
            if not path.exists():
                stored = {k: v for k, v in result.items() if k != "cached"}
                write_text(path, json.dumps(stored, indent=1))
                seeded += 1
    return seeded


def evaluate(params, targets, pnr=False, freq=150.0, timeout=None, cache=None):
    """Synthesis figures of one configuration for each target, with cycles and frame rate.

    Results that are ``ok`` or ``failed`` are cached in ``cache`` (a folder) when given;
    timeouts are not, so a longer ``--timeout`` retries them.
    """
    from .verilog import TOP_NAME, core_verilog
    results = {}
    cycles = cycles_per_frame(params)
    design, verilog = _design(params, cache)
    for target in targets:
        path = None if cache is None else (
            Path(cache) / f"{_cache_key(params, target, pnr, freq, design)}.json")
        if path is not None and path.exists():
            results[target] = json.loads(path.read_text())
            results[target]["cached"] = True
            continue
        if verilog is None:
            verilog = core_verilog(params)
        result = synthesise(verilog, target, TOP_NAME, pnr=pnr, freq=freq, timeout=timeout)
        if target == "ecp5":
            result.update(pnr=pnr, freq=freq)
        if result["status"] == "ok" and result["memory_bits"] != expected_memory_bits(params):
            result["message"] = (f"memory bits {result['memory_bits']} differ from the "
                                 f"architecture's {expected_memory_bits(params)}")
        if result.get("fmax_mhz"):
            result["frames_per_second"] = result["fmax_mhz"] * 1e6 / cycles
        if path is not None and result["status"] != "timeout":
            write_text(path, json.dumps(result, indent=1))
        results[target] = dict(result, cached=False)
    return {"params": _params_dict(params), "verilog_sha": design, "cycles_per_frame": cycles,
            "expected_memory_bits": expected_memory_bits(params), "results": results}


def _params_dict(params):
    return {"transform": params.transform, "block": params.block,
            "disparities": params.disparities, "rounds": params.rounds,
            "aggregation": params.aggregation, "lr_threshold": params.lr_threshold,
            "width": params.width, "height": params.height}


def _number(value, digits=0):
    if value is None:
        return "-"
    return f"{value:,.{digits}f}"


def _row(target, result):
    if result["status"] != "ok":
        return [target, result["status"], result.get("message", "")]
    return [target, f"{result['logic']:,} {result['logic_unit']}", f"{result['registers']:,}",
            f"{result['block_rams']} {result['block_ram_kind']}", str(result["lut_rams"]),
            f"{result['memory_bits']:,}" + (f" (+{result['ffram_bits']:,} in FFs)"
                                             if result["ffram_bits"] else ""),
            _number(result["fmax_mhz"], 1), _number(result.get("frames_per_second"), 1),
            f"{result['seconds']:.0f}" + (" (cached)" if result.get("cached") else "")]


def format_table(report):
    """Plain-text table of one configuration's results."""
    header = ["target", "logic", "registers", "block RAM", "LUT RAM", "memory bits",
              "Fmax MHz", "frames/s", "seconds"]
    rows = [header] + [_row(t, r) for t, r in report["results"].items()]
    widths = [max(len(row[i]) for row in rows if i < len(row)) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows]
    notes = [f"cycles per frame {report['cycles_per_frame']:,}"]
    notes += [f"{t}: {r['message']}" for t, r in report["results"].items()
              if r["status"] == "ok" and r.get("message")]
    notes += [f"{t} critical path: {r['critical_path']}" for t, r in report["results"].items()
              if r.get("critical_path")]
    return "\n".join(lines + notes)


def _job(params, targets, pnr, freq, timeout, cache):
    """One sweep cell in a worker process; never raises, so the sweep goes on."""
    try:
        return evaluate(params, targets, pnr, freq, timeout, cache)
    except Exception as error:  # a crash in generation is a cell's result, not the sweep's
        return {"params": _params_dict(params), "cycles_per_frame": None,
                "expected_memory_bits": expected_memory_bits(params),
                "results": {t: {"target": t, "status": "failed", "fmax_mhz": None,
                                "message": f"{type(error).__name__}: {error}"[:200]}
                            for t in targets}}


def paper_configurations():
    """The paper's sweep, smallest first so a partial run covers the most configurations."""
    width, height = PAPER_SIZE
    return [StereoParams(transform=t, block=b, disparities=PAPER_DISPARITIES,
                         rounds=PAPER_ROUNDS, width=width, height=height)
            for b in PAPER_BLOCKS for t in TRANSFORMS]


def run_sweep(configurations, targets, pnr, freq, timeout, cache, jobs, progress=None):
    """Evaluate configurations in ``jobs`` processes, with a progress bar on stderr.

    ``progress(reports)`` is called with the reports so far after each configuration, so
    a long sweep leaves its partial results behind.
    """
    from tqdm import tqdm
    reports = []
    with ProcessPoolExecutor(max_workers=jobs) as pool, \
            tqdm(total=len(configurations), desc="synthesis", unit="config",
                 file=sys.stderr) as bar:
        # Cheap cells first: ext. census takes many times longer than the other three,
        # and a sweep stopped early should hold as many cells as possible.
        submitted = sorted(configurations, key=lambda p: (p.transform == "ext-census", p.block))
        futures = {pool.submit(_job, p, targets, pnr, freq, timeout, cache): p
                   for p in submitted}
        for future in as_completed(futures):
            report = future.result()
            p = futures[future]
            status = ",".join(r["status"] for r in report["results"].values())
            bar.set_postfix_str(f"{p.transform} {p.block}x{p.block}: {status}")
            bar.update()
            reports.append(report)
            if progress is not None:
                progress(_in_order(reports, configurations))
    return _in_order(reports, configurations)


def _in_order(reports, configurations):
    order = {(p.transform, p.block): i for i, p in enumerate(configurations)}
    return sorted(reports, key=lambda r: order[(r["params"]["transform"],
                                                r["params"]["block"])])


def _cell(result, key):
    if result is None:
        return "not run"
    if result["status"] != "ok":
        return result["status"]
    return _number(result.get(key), 1 if key == "fmax_mhz" else 0)


def _ratio(ours, paper):
    if ours is None or paper is None:
        return "-"
    return f"{ours / paper:.2f}"


def sweep_markdown(reports):
    """Markdown table of the sweep: ours beside the paper, ratios ours / paper."""
    lines = ["| transform | block | Cyclone V ALUTs | paper LEs | ratio | registers | M10K | "
             "memory bits | paper bits | ratio | ECP5 LUT4 | ECP5 Fmax MHz | paper MHz |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for report in reports:
        p = report["params"]
        index = PAPER_BLOCKS.index(p["block"])
        cv = report["results"].get("cyclonev")
        e5 = report["results"].get("ecp5")
        logic = PAPER_LOGIC[p["transform"]][index]
        memory = PAPER_MEMORY[p["transform"]][index]
        ok = cv is not None and cv["status"] == "ok"
        paper_logic = "-" if logic is None else f"{logic:,}" + (
            " (did not fit)" if (p["transform"], p["block"]) in PAPER_DID_NOT_FIT else "")
        lines.append("| " + " | ".join([
            p["transform"], f"{p['block']}x{p['block']}", _cell(cv, "logic"), paper_logic,
            _ratio(cv["logic"], logic) if ok else "-", _cell(cv, "registers"),
            _cell(cv, "block_rams"), _cell(cv, "memory_bits"), f"{memory:,}",
            _ratio(cv["memory_bits"], memory) if ok else "-", _cell(e5, "logic"),
            _cell(e5, "fmax_mhz"), _number(PAPER_CLOCK.get(p["block"]), 0)]) + " |")
    failures = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']} "
                f"{t}: {res['status']}: {res.get('message', '')}"
                for r in reports for t, res in r["results"].items() if res["status"] != "ok"]
    paths = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']}: "
             f"{res['critical_path']}" for r in reports for res in r["results"].values()
             if res.get("critical_path")]
    seconds = [f"- {r['params']['transform']} {r['params']['block']}x{r['params']['block']} "
               f"{t}: {res['seconds']:.0f} s"
               + (f" ({res['yosys_time_split']})" if res.get("yosys_time_split") else "")
               for r in reports
               for t, res in r["results"].items() if "seconds" in res]
    text = "\n".join(lines) + "\n"
    if failures:
        text += "\nFailed or timed out:\n\n" + "\n".join(failures) + "\n"
    if paths:
        text += "\nECP5 critical paths:\n\n" + "\n".join(paths) + "\n"
    return text + "\nSynthesis time per configuration (uncached run):\n\n" + "\n".join(seconds) + "\n"


def sweep_plots(reports, out):
    """PNG plots: logic, memory and (if placed and routed) clock against block size."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colours = dict(zip(TRANSFORMS, ("tab:blue", "tab:orange", "tab:green", "tab:red")))
    panels = [("logic", "cyclonev", "logic", PAPER_LOGIC,
               "logic (ours: Cyclone V ALUTs, paper: Stratix II LEs)"),
              ("memory", "cyclonev", "memory_bits", PAPER_MEMORY, "memory bits")]
    if any(r["results"].get("ecp5", {}).get("fmax_mhz") for r in reports):
        panels.append(("fmax", "ecp5", "fmax_mhz", None, "clock MHz (ours: ECP5 nextpnr)"))
    written = []
    for name, target, key, paper, label in panels:
        figure, axes = plt.subplots(figsize=(7, 4.5))
        for transform in TRANSFORMS:
            points = [(r["params"]["block"], r["results"][target][key]) for r in reports
                      if r["params"]["transform"] == transform
                      and r["results"].get(target, {}).get("status") == "ok"
                      and r["results"][target].get(key) is not None]
            if points:
                axes.plot(*zip(*points), "o-", color=colours[transform], label=f"{transform} (ours)")
            if paper is not None:
                values = [(b, v) for b, v in zip(PAPER_BLOCKS, paper[transform]) if v is not None]
                axes.plot(*zip(*values), "x--", color=colours[transform], alpha=0.6,
                          label=f"{transform} (paper)")
        if name == "fmax":
            axes.plot(list(PAPER_CLOCK), list(PAPER_CLOCK.values()), "ks--", label="paper")
        if name == "logic":
            axes.set_yscale("log")  # ext. census is ten times the others
        axes.set_xlabel("block size B")
        axes.set_ylabel(label)
        axes.set_xticks(PAPER_BLOCKS)
        axes.grid(alpha=0.3)
        axes.legend(fontsize=7, ncol=2)
        axes.set_title(f"{label}, 450x375, D=100, R=10")
        figure.tight_layout()
        target_path = Path(out) / f"{name}.png"
        with atomic_path(target_path) as tmp:
            figure.savefig(tmp, dpi=110)
        plt.close(figure)
        written.append(target_path)
    return written


def _write_sweep(reports, out):
    """Write the sweep's JSON, markdown and plots (after every configuration)."""
    document = {"tools": tool_versions(), "hdl_sources": _source_hash(), "reports": reports}
    write_text(out / "sweep.json", json.dumps(document, indent=1) + "\n")
    write_text(out / "sweep.md", sweep_markdown(reports))
    return [out / "sweep.json", out / "sweep.md"] + sweep_plots(reports, out)


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "report", help="FPGA resources and clock of a core (Yosys, nextpnr)",
        description="Synthesise generated cores with Yosys (Cyclone V, ECP5) and nextpnr; "
                    "report logic, registers, RAM, memory bits, Fmax and frame rate.")
    add_matching_arguments(parser)
    parser.add_argument("--width", type=int, help="image width (required without --paper)")
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
    parser.add_argument("--jobs", type=int, default=1, help="parallel syntheses (default 1)")
    parser.add_argument("--out", type=Path, default=Path("docs/resources"),
                        help="output folder of --paper (default docs/resources)")
    parser.add_argument("--cache", type=Path,
                        default=Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
                        / "npstereo" / "report", help="result cache folder")
    parser.add_argument("--no-cache", action="store_true", help="synthesise everything again")
    parser.set_defaults(run=run)


def _check(args):
    if args.jobs < 1:
        raise UserError(f"--jobs must be >= 1, not {args.jobs}")
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
        if cache is not None:
            seeded = seed_cache(args.out / "sweep.json", cache)
            if seeded:
                print(f"resuming: {seeded} results taken from {args.out / 'sweep.json'}",
                      file=sys.stderr)
    else:
        if args.width is None or args.height is None:
            raise UserError("--width and --height are required (or use --paper)")
        configurations = [params_from_args(args).with_size(args.width, args.height)]
    reports = run_sweep(configurations, targets, args.pnr, args.freq, args.timeout, cache,
                        args.jobs, progress=(lambda done: _write_sweep(done, args.out))
                        if args.paper else None)
    document = {"tools": tool_versions(), "reports": reports}
    if args.paper:
        for path in _write_sweep(reports, args.out):
            print(f"wrote {path}")
    else:
        print(format_table(reports[0]))
    if args.json:
        write_text(args.json, json.dumps(document, indent=1) + "\n")
    failed = [r for report in reports for r in report["results"].values() if r["status"] != "ok"]
    return 1 if failed and not args.paper else 0
