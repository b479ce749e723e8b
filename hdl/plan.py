"""Hardware facts of a configuration, as pure functions of the parameters.

What gen/, sim/ and the tests need to know about a core -- the output word width, the
latency, the cycles per frame, the memory bits, whether it can be built at all -- and the
register plans and latencies that the components themselves use for their ``latency``
attributes. Nothing here constructs or elaborates a component, so a caller can ask for a
number without building the design; and since the components read their plans from here,
the numbers cannot drift from what they build (``tests/test_hdl_plan.py`` also measures
them on the elaborated hardware).
"""

from ..params import ParameterError
from .trees import DEFAULT_EVERY, popcount_plan, register_plan

__all__ = ["MAX_WIDTH", "MAX_BLOCK", "MAX_DISPARITIES", "check_buildable", "output_width",
           "transform_plan", "cost_plan", "min_tree_plan", "input_latency",
           "aggregation_latency", "aggregation_offset", "calculation_latency",
           "LR_CLOCK_LATENCY", "lr_latency",
           "latency", "cycles_per_frame", "memory_bits"]

#: Widest frame the hardware is generated for. 8192 covers 8K video (7680); the line
#: buffers are W deep and the cost line buffer W * R, so a wider frame only grows memories
#: no FPGA of the paper's class holds next to the logic (census 9x9, D = 100 at 8192:
#: 12.5 Mbit), while generation time grows with the depth of every memory.
MAX_WIDTH = 8192
#: Largest transform window. The paper sweeps 7 .. 19; at 31 x 31 the census transform is
#: 960 bits and the right-transform ring of D = 100 already holds 96,000 flip-flops (the
#: ext. census 19 x 19, 288,000 of them, does not fit the paper's EP2S180), and generation
#: time grows with B^2 per cost unit.
MAX_BLOCK = 31
#: Largest disparity range. The ring, the L/R check's slots and its D:1 partner
#: multiplexer grow linearly with D (the paper: 100); 256 is the most an 8-bit disparity
#: word holds.
MAX_DISPARITIES = 256


def check_buildable(params):
    """Raise :class:`ParameterError` unless the hardware can be generated for ``params``.

    The golden model runs any size; the hardware needs the frame size and stays within
    :data:`MAX_WIDTH`, :data:`MAX_BLOCK` and :data:`MAX_DISPARITIES`, checked before
    anything is built so that an oversized request fails at once instead of elaborating
    for minutes.
    """
    if params.width is None or params.height is None:
        raise ParameterError("the hardware needs the image size: give width and height "
                             "(--width and --height)")
    if params.width > MAX_WIDTH:
        raise ParameterError(f"image width must be <= {MAX_WIDTH} for the hardware, "
                             f"not {params.width}")
    if params.block > MAX_BLOCK:
        raise ParameterError(f"block size must be <= {MAX_BLOCK} for the hardware, "
                             f"not {params.block}")
    if params.disparities > MAX_DISPARITIES:
        raise ParameterError(f"disparities must be <= {MAX_DISPARITIES} for the hardware, "
                             f"not {params.disparities}")


def output_width(params):
    """Width of ``m_axis_tdata``: disparity bits plus the valid flag, in whole bytes."""
    return 8 * -(-(params.disparity_bits + 1) // 8)


# Register plans of the datapath units (lists of bool, see trees.register_plan) -----------

def _unit_plan(tree, params, every, depth):
    """Register plan of a unit over the k neighbours: ``tree`` "popcount" (of k bits),
    "sum" (of k values) or None (one value); ``depth`` levels of logic in front of it
    count against the register spacing, and the result is registered (``every`` > 0)."""
    registered = every > 0
    if tree == "popcount":
        return popcount_plan(params.neighbours, every, depth, registered)
    return register_plan(params.neighbours if tree == "sum" else 1, every, depth, registered)


def transform_plan(params, every=DEFAULT_EVERY):
    """Register plan of ``params.transform``; ``sum()`` of it is the transform's latency.

    One level of logic (a comparison or an absolute difference) sits in front of every
    tree and counts against the register spacing. Census and ext. census have no tree:
    that level, then the output register.
    """
    tree = {"rank": "popcount", "ext-rank": "sum"}.get(params.transform)
    return _unit_plan(tree, params, every, 1)


def cost_plan(params, every=DEFAULT_EVERY):
    """Register plan of the matching cost; ``sum()`` of it is the cost unit's latency.

    The census cost's XOR in front of the popcount is one LUT level, far shorter than an
    adder level, and is not counted against the spacing; the absolute differences of the
    other costs are. Rank and ext. rank costs are one absolute difference.
    """
    tree = {"census": "popcount", "ext-census": "sum"}.get(params.transform)
    return _unit_plan(tree, params, every, 0 if params.transform == "census" else 1)


def min_tree_plan(params, every=DEFAULT_EVERY):
    """Register plan of the partition's WTA over D/R aggregated costs."""
    return register_plan(params.per_round, every)


# Latencies of the stages -------------------------------------------------------------------

def input_latency(params):
    """Positions from a pixel's entry to the window centred on it: r rows and r columns
    (the window is complete after the advance of the pixel r rows and r columns later)."""
    return params.radius * params.width + params.radius


#: Clocks of the vertical aggregation: the cost line buffer's address register, its read,
#: its data register and the registered column sums; then the registered row sum.
_VERTICAL_CLOCKS, _HORIZONTAL_CLOCKS = 4, 1


def aggregation_latency(params):
    """Register stages (clocks) from the costs to their A x A sums; 0 for A = 1.

    The sums that leave with a position's costs are those of the window centred a rows
    and a columns earlier (:func:`aggregation_offset`).
    """
    return _VERTICAL_CLOCKS + _HORIZONTAL_CLOCKS if params.agg_radius else 0


def aggregation_offset(params):
    """Positions the aggregation window's centre trails the newest costs: a rows and a
    columns."""
    return params.agg_radius * (params.width + 1)


def calculation_latency(params, every=DEFAULT_EVERY):
    """``(positions, clocks)`` of the calculation stage.

    Positions from the window centred on a pixel to the rounds of its costs: the
    transform's registers and the position register each load on an advance, and the
    rounds run in the position after the last of them. Then clocks from a round to its
    partition winner: the cost unit, the aggregation's register stages and the minimum
    tree.
    """
    positions = sum(transform_plan(params, every)) + 2
    clocks = (sum(cost_plan(params, every)) + aggregation_latency(params)
              + sum(min_tree_plan(params, every)))
    return positions, clocks


#: Clocks from the L/R check's result to its registered output (the partner lookup and
#: the consistency test are registered once more before the output queue).
LR_CLOCK_LATENCY = 1


def lr_latency(params):
    """Positions the left winners wait for every possible partner's dR: D + 1 (0 without
    the check); the result then leaves in the first round of that position."""
    return params.disparities + 1 if params.lr_check else 0


def latency(params, every=DEFAULT_EVERY):
    """Flush positions of a frame: without stalls a frame takes (W x H + latency) x R
    clocks (:func:`cycles_per_frame`).

    A pixel enters in the last round of its position. Its output word is produced in the
    position ``input_latency`` + the calculation stage's positions + the aggregation's
    centre offset + ``lr_latency`` later, in the clock the calculation stage's clocks and
    ``LR_CLOCK_LATENCY`` after that position's first round (plus R - 1 without the check,
    whose result leaves in the last round instead of the first). After a frame's last word
    the core takes the next frame's first pixel in the next last round from the following
    clock on (the enable is a register): the positions up to that one are the flush.
    """
    positions, clocks = calculation_latency(params, every)
    positions += input_latency(params) + aggregation_offset(params) + lr_latency(params)
    produced = clocks + LR_CLOCK_LATENCY + (0 if params.lr_check else params.rounds - 1)
    rounds = params.rounds
    return positions + -(-(produced + 2 - 2 * rounds) // rounds)


def cycles_per_frame(params, every=DEFAULT_EVERY):
    """Clocks per frame without stalls: (W x H pixels + flush positions) x R rounds.

    After the frame's last pixel the core feeds :func:`latency` dummy positions until the
    frame's last output word is out; the next frame's first pixel waits for that.
    """
    return (params.width * params.height + latency(params, every)) * params.rounds


def memory_bits(params):
    """Bits the core's memories must hold (docs/hardware.md, "Memories").

    Two image line buffers of B-1 lines of 8-bit pixels, and (aggregation A > 1) the cost
    line buffer of A-1 lines of D costs per column.
    """
    lines = 2 * params.width * 8 * (params.block - 1)
    costs = params.width * (params.aggregation - 1) * params.disparities * params.cost_bits
    return lines + costs
