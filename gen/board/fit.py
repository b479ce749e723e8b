"""What fits a board: the stored pair and the frame buffer in its block RAM beside the
core, and a map no larger than the screen.

The pair is one 16-bit word per pixel (:class:`~npstereo.hdl.stream.PixelPair`), the
frame buffer one output value (F fractional bits included) and its valid flag per pixel,
the colour ROM 24 bits for each of the (D - 1) 2^F + 1 values; all three, and the core's
memories (:func:`npstereo.hdl.plan_memories.memories`), are counted in ECP5 DP16KD blocks, each
memory in the block shape that needs the fewest (16K x 1 .. 1K x 18). Memories of fewer
than :data:`LUT_RAM_DEPTH` words go to LUT RAM and count no block. This is an estimate
made before anything is built: the synthesis report (``yosys.log``) has Yosys' count.
"""

import math
from dataclasses import dataclass

from ...hdl.plan_memories import memories
from ...params import UserError

__all__ = ["Board", "BOARDS", "blocks", "display_blocks", "core_blocks", "largest_pair",
           "check_fit"]

#: DP16KD shapes (words, bits), true dual port.
DP16KD_SHAPES = ((16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18))
#: Shallower memories are mapped to LUT RAM or registers by Yosys' synth_ecp5.
LUT_RAM_DEPTH = 64


@dataclass(frozen=True)
class Board:
    """A board npstereo builds for: its name on the command line, the FPGA, its DP16KD
    blocks (the figure of :mod:`npstereo.gen.flow.capacity`) and nextpnr's option for it."""

    name: str
    device: str
    blocks: int
    nextpnr: str        # nextpnr-ecp5's device option


BOARDS = {"ulx3s-85f": Board("ulx3s-85f", "LFE5U-85F", 208, "--85k")}


def blocks(depth, width):
    """DP16KD blocks of one memory of ``depth`` words of ``width`` bits."""
    if depth < LUT_RAM_DEPTH:
        return 0
    return min(math.ceil(depth / words) * math.ceil(width / bits)
               for words, bits in DP16KD_SHAPES)


def display_blocks(pixels, params):
    """The pair's ROM and the frame buffer for ``pixels`` pixels, and the colour ROM."""
    colours = ((params.disparities - 1) << params.subpixel_bits) + 1
    return (blocks(pixels, 16) + blocks(pixels, params.output_disparity_bits + 1)
            + blocks(colours, 24))


def core_blocks(params):
    return sum(use.count * blocks(use.depth, use.width) for use in memories(params))


def largest_pair(board, params):
    """The most pixels a stored pair may have on ``board`` beside the core of ``params``
    (whose width it keeps): a multiple of 1024."""
    room = board.blocks - core_blocks(params)
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
    core = core_blocks(params)
    needed = display_blocks(width * height, params) + core
    if needed > board.blocks:
        most = largest_pair(board, params)
        raise UserError(
            f"the stored pair {width}x{height} ({width * height:,} pixels) and its frame "
            f"buffer need {needed - core} DP16KD blocks, {needed} with the core: the "
            f"{board.device} of {board.name} has {board.blocks}; at most {most:,} pixels "
            f"with this core (e.g. 320x240; give a smaller --left/--right pair)")
    return needed
