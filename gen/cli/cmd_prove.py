"""``npstereo prove``: the core's AXI4-Stream properties, proved with SymbiYosys."""

import re
import sys

from ...hdl.plan import check_buildable
from ...hdl.verilog import core_verilog
from ..atomic import write_text
from ..flow.formal import (GROUPS, MAX_PROVE_BLOCK, MAX_PROVE_DISPARITIES,
                           MAX_PROVE_PIXELS, PROPERTIES, check_provable, prove)
from ...params import UserError
from .arguments import add_hardware_arguments, add_matching_arguments, check_output_folder, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run"]

DESCRIPTION = ("Generate the core (npstereo_core, as npstereo verilog) and prove its "
               "AXI4-Stream properties with SymbiYosys: output held under backpressure, "
               "W x H words per frame with tuser/tlast, recovery after misframing, no output "
               "without input, reset from any state (docs/verification.md). Exit 0 when "
               "every property is proven or holds to the bound, 1 when one fails or is not "
               "decided.")

#: Small by default: every clock of a bounded check is a copy of the core for the solver.
DEFAULTS = {"block": 3, "disparities": 2, "rounds": 1}


def run(args):
    out = check_output_folder(args.out)
    base = params_from_args(args)
    width = base.first_valid_column + 1 if args.width is None else args.width
    params = base.with_size(width, args.height)
    check_buildable(params)
    check_provable(params)
    if args.depth is not None and args.depth < 1:
        raise UserError(f"--depth must be >= 1, not {args.depth}")
    if args.timeout <= 0:
        raise UserError(f"--timeout must be > 0 seconds, not {args.timeout:g}")
    out.mkdir(parents=True, exist_ok=True)
    core = out / "core.v"
    write_text(core, core_verilog(params))

    def progress(group, mode, depth):
        what = "induction (PDR)" if mode == "prove" else f"bounded, depth {depth}"
        print(f"proving {group}: {what} ...", file=sys.stderr, flush=True)

    verdicts = prove(core, params, out, depth=args.depth, timeout=args.timeout,
                     groups=tuple(dict.fromkeys(args.checks)), progress=progress)
    print(f"{params.describe()}: {out}")
    for verdict in verdicts:
        print(f"{verdict.name:15s} {verdict.detail}  -- {verdict.text}")
    lines = [f"{v.name}\t{v.status}\t{v.detail}" for v in verdicts]
    write_text(out / "verdict.tsv", "".join(f"{line}\n" for line in lines))
    return 0 if all(v.status in ("proven", "bounded") for v in verdicts) else 1


def add_arguments(parser):
    add_matching_arguments(parser, max_block=MAX_PROVE_BLOCK,
                           max_disparities=MAX_PROVE_DISPARITIES, subpixel=True)
    add_hardware_arguments(parser)
    parser.set_defaults(**DEFAULTS)
    # The shared options' help names StereoParams' defaults: name prove's own instead.
    for action in parser._actions:
        if action.dest in DEFAULTS and action.help:
            action.help = re.sub(r"\(default [^)]*\)", f"(default {DEFAULTS[action.dest]})",
                                 action.help)
    parser.add_argument("--width", type=int, default=None,
                        help=f"frame width W (default the smallest the configuration takes, "
                             f"D + max(1, (A-1)/2); W x H <= {MAX_PROVE_PIXELS})")
    parser.add_argument("--height", type=int, default=2, help="frame height H (default 2)")
    parser.add_argument("--depth", type=int, default=None,
                        help="clocks the bounded checks unroll (default: past the first line "
                             "of output words; the solver's time grows steeply with it)")
    parser.add_argument("--timeout", type=float, default=120.0,
                        help="seconds per group of checks; a bounded check stopped by it is "
                             "bounded to the depth it reached (default 120)")
    parser.add_argument("--checks", nargs="+", choices=tuple(GROUPS), default=list(GROUPS),
                        help="groups of checks to run (default all): "
                             + "; ".join(f"{name}: {', '.join(p.name for p in PROPERTIES if p.group == name)}"
                                         for name in GROUPS))
    parser.add_argument("--out", required=True,
                        help="folder for the core, the .sby files, logs and counterexamples")
    parser.set_defaults(run=run)
