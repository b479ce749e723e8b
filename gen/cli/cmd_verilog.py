"""``npstereo verilog``: write the synthesizable Verilog of one core."""

import sys

from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES, MAX_WIDTH, check_buildable
from ...hdl.verilog import core_verilog
from ..atomic import write_text
from .arguments import add_hardware_arguments, add_matching_arguments, check_output_file, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run"]

DESCRIPTION = ("Elaborate the streaming stereo core (npstereo_core, AXI4-Stream video ports) "
               "for one configuration and write it as Verilog.")


def run(args):
    out = check_output_file(args.out)
    # Validated before any elaboration: a bad or oversized configuration never starts
    # the generator.
    params = params_from_args(args).with_size(args.width, args.height)
    check_buildable(params)
    # The largest cores within the limits take minutes to elaborate: say what is going on.
    print(f"generating {params.describe()} ...", file=sys.stderr, flush=True)
    write_text(out, core_verilog(params))
    print(f"{params.describe()}: {out}")


def add_arguments(parser):
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES, subpixel=True)
    add_hardware_arguments(parser)
    parser.add_argument("--width", type=int, required=True,
                        help=f"image width W, at most {MAX_WIDTH}")
    parser.add_argument("--height", type=int, required=True, help="image height H")
    parser.add_argument("--out", required=True, help="Verilog file to write")
    parser.set_defaults(run=run)
