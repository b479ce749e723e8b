"""What fits a board: the stored pair and the frame buffer in its block RAM beside the
core, and a map no larger than the screen.

The pair is one 16-bit word per pixel (:class:`~npstereo.hdl.stream.PixelPair`), the
frame buffer one output value (F fractional bits included) and its valid flag per pixel,
the colour ROM 24 bits for each of the (D - 1) 2^F + 1 values; all three, and the core's
memories, are counted in ECP5 DP16KD blocks as Yosys maps them
(:mod:`npstereo.gen.flow.block_rams`: a memory that LUT RAM or flip-flops hold for less
counts no block). This is an estimate made before anything is built: the synthesis report
(``yosys.log``) has Yosys' count.
"""

from dataclasses import dataclass

from ...params import UserError
from ..flow.block_rams import block_rams, core_block_rams

__all__ = ["Board", "BOARDS", "display_blocks", "largest_pair", "check_fit"]


@dataclass(frozen=True)
class Board:
    """A board npstereo builds for: its name on the command line, the FPGA, its DP16KD
    blocks (the figure of :mod:`npstereo.gen.flow.capacity`) and nextpnr's option for it."""

    name: str
    device: str
    blocks: int
    nextpnr: str        # nextpnr-ecp5's device option


BOARDS = {"ulx3s-85f": Board("ulx3s-85f", "LFE5U-85F", 208, "--85k")}


def display_blocks(pixels, params):
    """The pair's ROM and the frame buffer for ``pixels`` pixels, and the colour ROM."""
    colours = ((params.disparities - 1) << params.subpixel_bits) + 1
    return (block_rams(pixels, 16, rom=True)
            + block_rams(pixels, params.output_disparity_bits + 1)
            + block_rams(colours, 24, rom=True))


def largest_pair(board, params):
    """The most pixels a stored pair may have on ``board`` beside the core of ``params``
    (whose width it keeps): a multiple of 1024."""
    room = board.blocks - core_block_rams(params)
    pixels = 0
    while display_blocks(pixels + 1024, params) <= room:
        pixels += 1024
    return pixels


def check_fit(board, params, timing):
    """A one-line :class:`UserError` unless the pair of ``params``' size fits ``board``'s
    block RAM beside the core and the map fits the screen."""
    width, height = params.width, params.height
    if width > timing.h_active or height > timing.v_active:
        raise UserError(f"the stored pair is {width}x{height}: the map must fit the "
                        f"{timing.h_active}x{timing.v_active} screen")
    core = core_block_rams(params)
    needed = display_blocks(width * height, params) + core
    if needed > board.blocks:
        most = largest_pair(board, params)
        raise UserError(
            f"the stored pair {width}x{height} ({width * height:,} pixels) and its frame "
            f"buffer need {needed - core} DP16KD blocks, {needed} with the core: the "
            f"{board.device} of {board.name} has {board.blocks}; at most {most:,} pixels "
            f"with this core (e.g. 320x240; give a smaller --left/--right pair)")
    return needed
