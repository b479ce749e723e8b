"""``npstereo verilog``: write the synthesizable Verilog of one core."""

from pathlib import Path

from ..golden.params import ParameterError, UserError
from .atomic import write_text
from .cmd_match import add_matching_arguments, params_from_args
from .verilog import core_verilog

__all__ = ["add_parser", "run"]


def run(args):
    out = Path(args.out)
    if out.is_dir():
        raise UserError(f"--out {args.out} is a directory")
    # Validated before any elaboration: a bad combination never starts the generator.
    params = params_from_args(args).with_size(args.width, args.height)
    if params.width is None or params.height is None:
        raise ParameterError("--width and --height are required to generate hardware")
    write_text(out, core_verilog(params))
    print(f"{params.describe()}: {out}")


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "verilog", help="generate the Verilog of a stereo core",
        description="Elaborate the streaming stereo core (npstereo_core, AXI4-Stream video "
                    "ports) for one configuration and write it as Verilog.")
    add_matching_arguments(parser)
    parser.add_argument("--width", type=int, required=True, help="image width W")
    parser.add_argument("--height", type=int, required=True, help="image height H")
    parser.add_argument("--out", required=True, help="Verilog file to write")
    parser.set_defaults(run=run)
