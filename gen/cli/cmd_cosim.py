"""``npstereo cosim``: one whole frame through the generated core in an HDL simulator.

Builds the core for the frame size, streams the frame through Verilator or Icarus Verilog
under cocotb (or through Amaranth's own simulator), compares every output pixel with the
golden model, writes both disparity maps as PNGs and prints the verdict. With
``--netlist FAMILY`` the simulated core is the netlist the project's synthesis flow maps
for that FPGA family (:mod:`npstereo.gen.flow.netlist`), with the family's cell models.
Exit code 1 on any mismatch, 2 on bad input.
"""

import re
import sys
import time
from pathlib import Path

from tqdm import tqdm

from ...golden.data import load_middlebury, to_gray
from ...golden.pipeline import disparity_map
from ...golden.subpixel import levels
from ...golden.synthetic import synthetic_pair
from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES, MAX_WIDTH, check_buildable
from ...hdl.verilog import TOP_NAME, core_verilog
from ...params import UserError
from ...sim.cosim import SIMULATORS, CosimError, run_frame
from ..flow.cell_models import FAMILIES
from ..flow.netlist import NetlistError, mapped_netlist
from ..images import save_disparity_png
from .arguments import add_hardware_arguments, add_matching_arguments, check_output_folder, \
    params_from_args
from .verdict import print_verdict

__all__ = ["DESCRIPTION", "add_arguments", "run", "parse_crop"]

DESCRIPTION = ("Generate the core for the frame size, stream one frame through an HDL "
               "simulator under cocotb (Verilator, Icarus) or through Amaranth's simulator, "
               "and compare every output pixel with the golden model; with --netlist, the "
               "core as synthesised for an FPGA family (gate level). Exit code 1 on any "
               "mismatch.")


def parse_crop(text, width, height):
    """``WxH`` -> (w, h), at most the image size."""
    match = re.fullmatch(r"(\d+)[xX](\d+)", text or "")
    if match is None:
        raise UserError(f"--crop must be WIDTHxHEIGHT (e.g. 64x32), not {text!r}")
    w, h = int(match[1]), int(match[2])
    if not (1 <= w <= width and 1 <= h <= height):
        raise UserError(f"--crop {text} must lie within the {width}x{height} image")
    return w, h


def _frame(args):
    if args.synthetic:
        pair = synthetic_pair(disparities=args.disparities, seed=args.seed)
    else:
        pair = load_middlebury(args.dataset)
    left, right = to_gray(pair.left), to_gray(pair.right)
    height, width = left.shape
    if args.crop is not None:
        w, h = parse_crop(args.crop, width, height)
        # The centre holds the scene's objects; corners are often featureless background.
        x, y = (width - w) // 2, (height - h) // 2
        left, right = left[y:y + h, x:x + w].copy(), right[y:y + h, x:x + w].copy()
    return pair.name, left, right


def _out_dir(value):
    if Path(value).exists() and not Path(value).is_dir():
        raise UserError(f"--out {value} exists and is not a directory")
    return check_output_folder(value)


def _netlist(args, params):
    """The core's mapped netlist for ``--netlist`` (cached), or None without it."""
    if args.netlist is None:
        return None
    print(f"synthesising the core for {args.netlist} (cached) ...", file=sys.stderr)
    return mapped_netlist(core_verilog(params), args.netlist, TOP_NAME)


def run(args):
    if args.netlist is not None and args.simulator == "amaranth":
        raise UserError("--netlist needs --simulator verilator or icarus: amaranth "
                        "simulates the Amaranth design, not a netlist")
    out = _out_dir(args.out)
    if args.clock_mhz <= 0:
        raise UserError(f"--clock-mhz must be > 0, not {args.clock_mhz}")
    base = params_from_args(args)
    name, left, right = _frame(args)
    params = base.with_size(left.shape[1], left.shape[0])
    check_buildable(params)
    golden = disparity_map(left, right, params).disparity
    pixels = params.width * params.height
    print(f"{args.simulator}: {name} {params.describe()}", file=sys.stderr)
    start = time.perf_counter()
    try:
        netlist = _netlist(args, params)
    except NetlistError as error:
        print(f"npstereo: cosim failed: {error}", file=sys.stderr)
        return 1
    if args.simulator != "amaranth":
        print("building the core and the simulation model (cached) ...", file=sys.stderr)
    with tqdm(total=pixels, desc=f"cosim {args.simulator}", unit="px", file=sys.stderr,
              leave=False) as bar:
        try:
            result = run_frame(args.simulator, params, left, right, progress=bar.update,
                               golden=golden,
                               core_text=None if netlist is None else netlist.verilog,
                               libraries=None if netlist is None else netlist.libraries)
        except CosimError as error:
            print(f"npstereo: cosim failed: {error}", file=sys.stderr)
            return 1
    seconds = time.perf_counter() - start
    _, comparison = result.frames[0]
    hardware_png, golden_png = out / "hardware.png", out / "golden.png"
    save_disparity_png(hardware_png, levels(result.disparity, params.subpixel_bits),
                       params.disparities - 1)
    save_disparity_png(golden_png, levels(golden, params.subpixel_bits), params.disparities - 1)
    print_verdict(comparison, result.cycles, pixels, args.clock_mhz)
    synthesis = "" if netlist is None else f"{netlist.seconds:.1f} s synthesis, "
    print(f"time:             {seconds:.1f} s ({synthesis}{result.build_seconds:.1f} s "
          "building)")
    print(f"maps:             {hardware_png} (hardware), {golden_png} (golden)")
    if netlist is not None:
        print(f"netlist:          {netlist.family}: {netlist.summary()}")
    return 0 if comparison.ok else 1


def add_arguments(parser):
    parser.add_argument("--simulator", required=True, choices=SIMULATORS,
                        help="verilator (fast), icarus, or amaranth (slow: small crops only)")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", help="Middlebury scene folder (e.g. .../teddy)")
    source.add_argument("--synthetic", action="store_true",
                        help="a seeded synthetic scene instead of a dataset")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic scene")
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES, subpixel=True)
    add_hardware_arguments(parser)
    parser.add_argument("--crop", help="simulate only the central WIDTHxHEIGHT pixels "
                        f"(the hardware takes at most {MAX_WIDTH} columns)")
    parser.add_argument("--netlist", choices=FAMILIES,
                        help="simulate the core as synthesised for this FPGA family by the "
                             "project's Yosys flow (ecp5: with the block-RAM output registers "
                             "packed), with the family's cell models; verilator or icarus")
    parser.add_argument("--clock-mhz", type=float, default=100.0,
                        help="clock for the implied frame rate (default 100)")
    parser.add_argument("--out", required=True,
                        help="folder for hardware.png and golden.png")
    parser.set_defaults(run=run)
