"""``npstereo board``: a bitstream that shows depth on a board's video output.

A stereo pair stored in block RAM streams through one core; its colour-mapped disparity
map goes out at 640x480 60 Hz on the board's DVI/HDMI port (:mod:`npstereo.gen.board`).
Before the flow runs, the board top is simulated under Verilator for one whole frame and
compared, pixel for pixel, with the golden model's colour-mapped map: the frame written as
``frame.png``. The core holds one configuration, chosen here (the buttons do nothing).
"""

import shutil
import sys
import time

from amaranth_boards.ulx3s import ULX3S_85F_Platform

from ...golden.data import check_same_size, load_middlebury, read_image, to_gray
from ...golden.pipeline import disparity_map
from ...golden.synthetic import DEFAULT_DISPARITIES, synthetic_pair
from ...hdl.plan import MAX_BLOCK, MAX_DISPARITIES, check_buildable
from ...params import UserError
from ..atomic import write_bytes, write_text
from ..board.display import DepthDisplay
from ..board.fit import BOARDS, check_fit
from ..board.flow import NAME, BuildError, build_bitstream, clock_report
from ..board.ulx3s import ULX3STop
from ..board.verify import capture_verilator, compare
from ..board.video import VGA_640X480, expected_frame
from ..images import save_gray_png
from .arguments import add_hardware_arguments, add_matching_arguments, check_output_folder, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run"]

DESCRIPTION = ("Build a bitstream for a board: a stereo pair stored in block RAM (the "
               "synthetic scene by default) through one core, its colour-mapped disparity "
               "map on the DVI/HDMI port at 640x480 60 Hz. Writes the .bit, the timing "
               "report and frame.png, the frame the board shows, after simulating the board "
               "top for one whole frame against the golden model (Verilator).")

#: The board's defaults: the synthetic scene's disparity range, four rounds.
BOARD_DEFAULTS = {"disparities": DEFAULT_DISPARITIES, "rounds": 4}


def _pair(args):
    """(name, left, right): gray images of the chosen source."""
    if args.dataset and (args.left or args.right):
        raise UserError("give --dataset or --left and --right, not both")
    if bool(args.left) != bool(args.right):
        raise UserError("--left and --right go together: give both images")
    if args.dataset:
        pair = load_middlebury(args.dataset)
        left, right = pair.gray()
        return pair.name, left, right
    if args.left:
        left = to_gray(read_image(args.left, "left image"))
        right = to_gray(read_image(args.right, "right image"))
        check_same_size(left, right)
        return "pair", left, right
    pair = synthetic_pair(seed=args.seed)
    left, right = pair.gray()
    return pair.name, left, right


def run(args):
    # Everything that can be refused is refused before any work (and nothing is written).
    board, timing = BOARDS[args.board], VGA_640X480
    out = check_output_folder(args.out)
    name, left, right = _pair(args)
    height, width = left.shape
    params = params_from_args(args).with_size(width, height)
    check_buildable(params)
    blocks = check_fit(board, params, timing)

    began = time.monotonic()
    golden = disparity_map(left, right, params).disparity
    frame = expected_frame(golden, params.disparities, timing, bits=params.subpixel_bits)
    print(f"{board.name}: {params.describe()} on {name} ({width}x{height}), "
          f"about {blocks} of {board.blocks} DP16KD blocks; the core's configuration is "
          f"fixed in the bitstream (the buttons are not used)")
    save_gray_png(out / "frame.png", frame)

    check = _verify(params, left, right, timing, frame)
    print(f"board top under Verilator, one {timing.h_active}x{timing.v_active} frame: "
          f"{check.message()}")
    if not check.ok:
        return 1

    work = out / "build"
    platform = ULX3S_85F_Platform()
    seconds = build_bitstream(platform, ULX3STop(DepthDisplay(params, left, right, timing)),
                              work, board.nextpnr, timeout=args.timeout)
    clocks, crossings = clock_report(work / "report.json")
    lines = [f"{board.name}: {params.describe()} on {name} ({width}x{height})",
             f"yosys {seconds['yosys']:.0f} s, nextpnr {seconds['nextpnr']:.0f} s, "
             f"ecppack {seconds['ecppack']:.0f} s",
             f"{'clock':<36} {'achieved MHz':>12} {'constraint MHz':>15}"]
    lines += [f"{clock:<36} {achieved:12.2f} {constraint:15.2f}"
              for clock, achieved, constraint in clocks]
    lines += [f"{source} -> {target}: {delay:.2f} ns (budget {budget:.2f} ns)"
              for source, target, delay, budget in crossings]
    lines.append(f"nextpnr log: {work / 'nextpnr.log'}")
    late = [f"{s} -> {t} {d:.2f} ns" for s, t, d, b in crossings if d > b]
    write_text(out / "timing.txt", "\n".join(lines) + "\n")
    if late:
        raise BuildError(f"a path between the clocks is longer than the faster clock's "
                         f"period: {', '.join(late)} ({out / 'timing.txt'})")
    write_bytes(out / f"{board.name}.bit", (work / f"{NAME}.bit").read_bytes())
    shutil.copyfile(work / "report.json", out / "nextpnr-report.json")
    print("\n".join(lines[1:-1]))
    print(f"{out / (board.name + '.bit')}, {out / 'timing.txt'}, {out / 'frame.png'} "
          f"({time.monotonic() - began:.0f} s)")
    return 0


def _verify(params, left, right, timing, frame):
    print("simulating the board top under Verilator (a first build takes a few minutes) ...",
          file=sys.stderr, flush=True)
    capture, _ = capture_verilator(DepthDisplay(params, left, right, timing), timing)
    return compare(frame, capture, timing)


def add_arguments(parser):
    parser.add_argument("board", choices=sorted(BOARDS), help="the board")
    parser.add_argument("--out", required=True, help="output folder")
    source = parser.add_argument_group("the stored pair (default: the synthetic scene)")
    source.add_argument("--dataset", help="Middlebury scene folder")
    source.add_argument("--left", help="left image (with --right)")
    source.add_argument("--right", help="right image (with --left)")
    source.add_argument("--seed", type=int, default=0, help="synthetic scene seed (default 0)")
    add_matching_arguments(parser, max_block=MAX_BLOCK, max_disparities=MAX_DISPARITIES,
                           defaults=BOARD_DEFAULTS, subpixel=True)
    add_hardware_arguments(parser)
    parser.add_argument("--timeout", type=float, default=7200.0,
                        help="seconds for the whole flow before giving up (default 7200)")
    parser.set_defaults(run=run)
