"""Hardware facts of a configuration, as pure functions of the parameters.

What gen/, sim/ and the tests need to know about a core -- the output word width, the
latency, the cycles per frame, the memories and their bits, whether it can be built at all
-- and the register plans and clock offsets that the components themselves use for their
``latency`` attributes and their internal timing. Nothing here constructs or elaborates a
component, so a caller can ask for a number without building the design; and since the
components read their plans from here, the numbers cannot drift from what they build
(``tests/test_hdl_plan.py`` also measures them on the elaborated hardware, and
``tests/test_report.py`` checks the memories against Yosys).

Offsets are clocks after a slot's first clock (its admission, see :mod:`.core`); a value
*at* an offset is slot-aligned there (see :mod:`.common`).
"""

from dataclasses import dataclass

from ..params import ParameterError
from .common import tag_layout
from .trees import (DEFAULT_EVERY, PAIRED_ADDER_BITS, min_tree_latency, popcount_plan,
                    register_plan, sad_plan, tree_levels)

__all__ = ["MAX_WIDTH", "MAX_BLOCK", "MAX_DISPARITIES", "check_buildable", "output_width",
           "transform_plan", "cost_plan", "min_tree_clocks", "evaluation_latency", "CENTRE_FANOUT",
           "centre_copies", "STORE_SLICE_BITS", "store_slices", "INPUT_LATENCY", "cost_rows",
           "transformed_rows", "window_rows", "window_first_row", "window_pixels",
           "masks_after_compare", "census_registers_compared",
           "vertical_bits", "VERTICAL_READ", "BANK_CHOICE", "COST_BANK", "cost_banks",
           "bank_choice_levels", "vertical_read", "vertical_plan",
           "horizontal_plan",
           "row_sum_plan", "vertical_clocks", "aggregation_latency", "MAX_SKEW_ONE_ROUND", "unit_skews",
           "CalculationTiming", "calculation_timing",
           "LR_STAGE_A", "lr_stage_b", "LRTiming", "lr_timing", "CoreTiming", "core_timing", "latency",
           "cycles_per_frame", "Memory", "memories", "memory_bits", "SGM_LOOP_CLOCKS",
           "sgm_min_rounds", "SgmTiming", "sgm_timing", "sgm_memories"]

#: Widest frame the hardware is generated for. 8192 covers 8K video (7680); the line
#: buffers are W deep (the costs line buffer W * R), so a wider frame only grows memories
#: no FPGA of the paper's class holds next to the logic, while generation time grows with
#: the depth of every memory.
MAX_WIDTH = 8192
#: Largest transform window. The paper sweeps 7 .. 19; at 31 x 31 an extended census word
#: is 7,680 bits and the stores of the right transforms hold D of them; generation time
#: grows with B^2 per cost unit.
MAX_BLOCK = 31
#: Largest disparity range: 256 is the most an 8-bit disparity word holds.
MAX_DISPARITIES = 256


def check_buildable(params):
    """Raise :class:`ParameterError` unless the hardware can be generated for ``params``.

    The golden model runs any size; the hardware needs the frame size and stays within
    :data:`MAX_WIDTH`, :data:`MAX_BLOCK` and :data:`MAX_DISPARITIES`, checked before
    anything is built so that an oversized request fails at once instead of elaborating
    for minutes. Semi-global aggregation also needs enough rounds for its left path's loop
    (:func:`sgm_min_rounds`).
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
    if params.is_sgm:
        _check_sgm_rounds(params)


def output_width(params):
    """Width of ``m_axis_tdata``: disparity bits plus the valid flag, in whole bytes."""
    return 8 * -(-(params.disparity_bits + 1) // 8)


# Register plans of the datapath units (lists of bool, see trees.register_plan) -----------

def _unit_plan(tree, params, every, depth):
    """Register plan of a unit over the k neighbours: ``tree`` "popcount" (of k bits),
    "sum" (of k values), "sad" (of k absolute differences, see trees.sad_leaves) or None
    (one value); ``depth`` levels of logic in front of it count against the register
    spacing, and the result is registered (``every`` > 0)."""
    registered = every > 0
    if tree == "popcount":
        return popcount_plan(params.neighbours, every, depth, registered)
    if tree == "sad":
        return sad_plan(params.neighbours, every, depth, registered,
                        params.lut_inputs)
    return register_plan(params.neighbours if tree == "sum" else 1, every, depth, registered)


def transform_plan(params, every=DEFAULT_EVERY, mask_after=False):
    """Register plan of ``params.transform``; ``sum()`` of it is the transform's latency.

    The comparisons or differences with the centre come first, and they are registered
    on their own: the centre pixel reaches all k of them, and that fanout plus a carry
    chain is a clock's worth of routing on ECP5 (8.2 ns for rank 7x7 with the popcount's
    full adders behind it). For rank the plan's first entry is that register, then the
    popcount's plan; ext. rank's subtractions and inversions are the leaves of its tree
    (one level, then a register); census and ext. census are one level and the output
    register. Census with ``mask_after`` (:func:`masks_after_compare`) registers the
    comparisons, then chooses the bits of the neighbours outside the frame, then the
    output register.
    """
    if census_registers_compared(params, every, mask_after):
        return [True, True]
    if params.transform == "rank":
        return [every > 0] + popcount_plan(params.neighbours, every, 0, every > 0)
    tree = {"ext-rank": "sad"}.get(params.transform)
    return _unit_plan(tree, params, every, 1)


def census_registers_compared(params, every, mask_after):
    """Whether census registers its comparisons (with the flags) before the choice of the
    masked bits, then the output: a LUT behind the comparison's carry chain in the same
    clock was census 7x7's critical path (6.67 ns, ECP5)."""
    return params.transform == "census" and mask_after and every > 0


#: Neighbours above which the census cost's popcount registers every second adder level,
#: not every level. Census is flip-flop-bound on the ECP5 from 17x17 on: at 17x17 the
#: thirty popcounts' registers were 22,680 of 70,503 flip-flops (84 % of the 85k, its LUTs
#: at 79 %), and those cores' clocks are limited by the input stage's wires (8.5 ns and
#: more), not by the 6.7 ns two adder levels take.
SPACED_POPCOUNT_ABOVE = 256


#: Neighbours above which ext. census's sum of absolute differences takes its first
#: register one adder level later (spacing 3; the latency is the same). Yosys then maps
#: the differences' inversions and two adder levels into Cyclone V's ALM compressors (a
#: 360-pair sum alone: 10,290 ALUTs against 11,295), which ECP5's LUT4s cannot hold (48
#: pairs: 1,704 LUT4 against 1,560, 4.6 LUT levels against 3.6). From 13x13 on ext. census
#: is too large for the ECP5-85k, the largest ECP5 (122 % of its LUTs at 13x13, 159 % at
#: 15x15), and at 19x19 it was 4.1 % over the paper's EP2S180 (138,648 ALUTs now, within).
#: Arranged for 6-input LUTs (``lut_inputs`` 6) the sum is smaller still with the usual
#: spacing, and the wider one does not pay: 8,877 ALUTs and 3.6 levels against 10,369 and
#: 9.3 (360 pairs, Cyclone V).
SPACED_SAD_ABOVE = 120


def cost_plan(params, every=DEFAULT_EVERY):
    """Register plan of the matching cost; ``sum()`` of it is the cost unit's latency.

    The census cost's XOR in front of the popcount is one LUT level, far shorter than an
    adder level, and is not counted against the spacing, and its adder levels are
    registered one by one; the ext. census sum of absolute
    differences counts its subtraction itself; rank and ext. rank costs are one absolute
    difference.
    """
    tree = {"census": "popcount", "ext-census": "sad"}.get(params.transform)
    if (tree == "sad" and every and params.neighbours > SPACED_SAD_ABOVE
            and params.lut_inputs < 6):
        every = max(every, 3)
    if tree == "popcount" and params.neighbours <= SPACED_POPCOUNT_ABOVE:
        # A register after every adder level: two of the popcount's short adders in one
        # clock were census 9x9's critical path once the control paths were cut (6.7 ns,
        # five LUT levels, ECP5).
        every = min(every, 1)
    if tree is None and every and params.transform_bits > PAIRED_ADDER_BITS:
        # Both differences registered, then the choice: a wide comparison, two
        # subtractions and the multiplexer in one clock were 7.7 ns (ext. rank 9x9, ECP5).
        return [True, True]
    return _unit_plan(tree, params, every, 1 if tree is None else 0)


def min_tree_clocks(params):
    """Clocks of the partition's WTA over D/R aggregated costs: two per level (the
    comparison, registered with both candidates, then the choice of the whole (cost,
    index) pair; see :func:`~.trees.build_min_tree`)."""
    return min_tree_latency(params.per_round)


def evaluation_latency(params):
    """Clocks from the evaluation stage's input (round 0's partition winner) to the
    position's winner, slot-aligned: the R winners of a slot are in a shift register
    after round R-1, a minimum tree over them (:func:`~.trees.build_min_tree`), then the
    winner's register."""
    return params.rounds + min_tree_latency(params.rounds)


#: Comparisons (rank, census) or differences (ext. rank, ext. census) with the window's
#: centre that one copy of it feeds. A difference is an 8-bit carry chain per neighbour,
#: a clock of its own with the copy's routing in front: at 8 per copy that routing was
#: ext. rank 9x9's critical path (6.7 ns, 149.5 MHz on ECP5).
CENTRE_FANOUT = {"rank": 8, "census": 8, "ext-rank": 4, "ext-census": 4}


def centre_copies(params):
    """Copies of each window's centre pixel, one per :data:`CENTRE_FANOUT` neighbours
    (of the transform).

    The centre reaches all k comparisons (or differences) of a transform; as one register
    that fan-out was 5 ns of routing on ECP5 (rank 7x7). Each copy is loaded by a clock
    enable from a slot counter of its own, which keeps synthesis from merging the copies;
    with R = 1 there is no slot to count, and one register it stays.
    """
    if params.rounds == 1:
        return 1
    return -(-params.neighbours // CENTRE_FANOUT[params.transform])


#: Widest slice of a right-transform store with address counters of its own: an address
#: register driving a whole store (census 9x9: 60 LUT RAM cells) was 7 ns of routing on
#: ECP5.
STORE_SLICE_BITS = 32


def store_slices(width):
    """Widths of the slices a store word of ``width`` bits is cut into: as equal as can
    be, none wider than :data:`STORE_SLICE_BITS`."""
    count = -(-width // STORE_SLICE_BITS)
    return [width // count + (k < width % count) for k in range(count)]


# Offsets of the stages ---------------------------------------------------------------------

#: Clocks from the admission of a pixel to the window: the line buffers' block RAM read,
#: its output register, the window's shift, the masked window's register, a second
#: register of the window and the centres' copies.
INPUT_LATENCY = 5


def cost_rows(params):
    """Rows whose costs each cost unit computes: A when the rows above are kept as
    transformed pixels or as pixels (``stored_rows`` "transforms" or "pixels"), else 1."""
    if params.agg_radius and params.stored_rows in ("transforms", "pixels"):
        return params.aggregation
    return 1


def transformed_rows(params):
    """Rows whose windows are transformed per position: A with ``stored_rows ==
    "pixels"`` (the rows above are transformed again from pixels), else 1."""
    return cost_rows(params) if params.stored_rows == "pixels" else 1


def window_rows(params):
    """Rows of the input stage's window: B, or B + A - 1 when the rows above are
    transformed again from pixels (the A windows of a column, one below the other)."""
    return params.block + transformed_rows(params) - 1


def window_first_row(params, k):
    """First row, in the input stage's window of :func:`window_rows` rows (top row 0),
    of the window k rows above the newest."""
    return transformed_rows(params) - 1 - k


def window_pixels(params):
    """Pixels of the window the input stage hands the calculation stage: the A windows'
    own masked pixels, or with :func:`masks_after_compare` the rows they share."""
    if masks_after_compare(params):
        return window_rows(params) * params.block
    return transformed_rows(params) * params.block * params.block


def masks_after_compare(params):
    """Whether the A windows of a column share one unmasked window of pixels, and the
    transforms mask their comparisons instead (``Transform(mask_after=True)``).

    Census and rank with ``stored_rows == "pixels"``: a neighbour outside the frame is 0,
    and its bit (0 < centre) is centre != 0, one LUT after the comparison (census: after
    the comparison's register, see :func:`transform_plan`). Masking the
    pixels instead keeps A masked copies of overlapping rows, twice (the window register
    and the one by the comparisons): census 11x11 held 11,616 flip-flops there, against
    4,576 for one shared window and 726 for its flags (ECP5 placement: docs/hardware.md).
    """
    return params.transform in ("census", "rank") and transformed_rows(params) > 1


def vertical_bits(params):
    """Width of a vertical (column) sum of A costs."""
    return (params.max_cost * params.aggregation).bit_length()


#: Clocks until the rows of a vertical sum from stored costs are there with the bank
#: chosen in one level (:func:`bank_choice_levels`): the address register, the block RAM
#: read, each bank's output register, the bank's choice, then the read register. Each
#: further level of the choice adds a clock (:func:`vertical_read`).
VERTICAL_READ = 5

#: Banks chosen among in one clock: a 4:1 multiplexer is a LUT4 pair and a PFUMX on ECP5.
#: A unit's ten banks chosen in one clock were ext. census 7x7's critical path (11.3 ns,
#: four LUT levels, 88.2 MHz); more banks are chosen in a registered tree of such choices.
BANK_CHOICE = 4

#: Words of one bank of a cost line buffer (one ECP5 DP16KD at 36 bits, two Cyclone V
#: M10K at 20): the W*R words of a unit are cut into banks of their own, each with its
#: output register, and the bank is chosen behind those registers. One memory W*R deep was
#: a cascade of block RAMs with the choice in front of the first register (ext. census 7x7
#: on ECP5: nine DP16KD per unit, 70 MHz).
COST_BANK = 512


def cost_banks(params):
    """Depths of the banks of one unit's cost line buffer (W*R words in all)."""
    words = params.width * params.rounds
    full, rest = divmod(words, COST_BANK)
    return [COST_BANK] * full + ([rest] if rest else [])


def bank_choice_levels(params):
    """Registered levels of the choice of a unit's cost line buffer bank: level l chooses
    by digit l of the bank's index in base :data:`BANK_CHOICE` (one level for up to
    ``BANK_CHOICE`` banks, or a single bank)."""
    levels, banks = 1, len(cost_banks(params))
    while banks > BANK_CHOICE:
        levels, banks = levels + 1, -(-banks // BANK_CHOICE)
    return levels


def vertical_read(params):
    """Clocks until the rows of a vertical sum from stored costs are there."""
    return VERTICAL_READ + bank_choice_levels(params) - 1


def vertical_plan(params, every=DEFAULT_EVERY):
    """Register plan of the vertical sum of A stored costs; their masks are a level of
    logic in front of the adders."""
    return register_plan(params.aggregation, every, 1, True, params.cost_bits)


def horizontal_plan(params, every=DEFAULT_EVERY):
    """Register plan of the horizontal sum of 2a + 1 vertical sums; their masks are a
    level of logic in front of the adders."""
    return register_plan(2 * params.agg_radius + 1, every, 1, True, vertical_bits(params))


def row_sum_plan(params, every=DEFAULT_EVERY):
    """Register plan of a cost unit's sum of its A row costs (rows above kept as
    transforms); the masks are a level of logic in front of the adders."""
    return register_plan(cost_rows(params), every, 1, True, params.cost_bits)


def vertical_clocks(params, every=DEFAULT_EVERY):
    """Clocks of the vertical sum from stored costs (``stored_rows == "costs"``), else 0."""
    if not params.agg_radius or params.stored_rows != "costs":
        return 0
    return vertical_read(params) + sum(vertical_plan(params, every))


def aggregation_latency(params, every=DEFAULT_EVERY):
    """Clocks from the aggregation's input to its A x A sums (0 for A = 1), or to the
    summed path costs of semi-global aggregation (:func:`sgm_timing`).

    The vertical sum from stored costs (``stored_rows == "costs"``), then the horizontal
    sum: the registered taps, then the tree of 2a + 1 terms. (The units' skew comes on
    top, see :func:`calculation_timing`.)
    """
    if params.is_sgm:
        return sgm_timing(params, every).latency
    if not params.agg_radius:
        return 0
    return vertical_clocks(params, every) + 1 + sum(horizontal_plan(params, every))


#: Largest skew between the first and the last cost unit with R = 1 (see :func:`unit_skews`).
MAX_SKEW_ONE_ROUND = 7


def unit_skews(params):
    """Clocks by which each cost unit runs behind unit 0: the units form a systolic chain.

    Unit i takes its left operand from unit i - 1's register and its right-image words
    from unit i - 1's operand register, so no operand is broadcast to all units and no
    store's read feeds another store's write. Neighbouring units differ by 0 or 1 clock:
    s_i = i S // (D/R - 1). With R >= 2 the last unit's words go round to unit 0 for its
    next round, which needs S <= R - 1; with R = 1 nothing goes round, and S is kept small
    (:data:`MAX_SKEW_ONE_ROUND`) because re-aligning the units' results costs
    S - s_i registers per unit. Units with equal skew share their left operand.
    """
    units = params.per_round
    if units == 1:
        return (0,)
    top = min(units - 1, params.rounds - 1 if params.rounds > 1 else MAX_SKEW_ONE_ROUND)
    return tuple(i * top // (units - 1) for i in range(units))


@dataclass(frozen=True)
class CalculationTiming:
    """Offsets inside the calculation stage, in clocks after its input (the windows)."""
    transformed: int    #: transforms (and the rows above) of a position, slot-aligned
    stored: int         #: round 0 of unit 0's right-transform store read
    costed: int         #: masked costs (row costs) of a round, unit 0
    skew: int           #: clocks the last unit runs behind unit 0 (see unit_skews)
    vertical: int       #: unit 0's costs or vertical sums at the aggregation's input
                        #: (SGM: all units', re-aligned)
    sums: int           #: aggregated sums of the aggregation centre
    min_tree: int       #: clocks of the partition's minimum tree
    latency: int        #: the partition winner (registered)


def calculation_timing(params, every=DEFAULT_EVERY):
    """The calculation stage's offsets (see :mod:`.calculation_stage`).

    The transform units' results; with the rows above kept as transforms, the block RAM
    of transformed rows is read in round 0 and its word passes the RAM's output register
    and a fabric register, so the current row waits for it (at least 3 clocks). The
    newest right word is written into
    unit 0's store in the one clock of a slot that the words coming round from the last
    unit leave free, and unit 0 reads it R - S clocks later (S: the last unit's skew), so
    with R >= 2 the stores are read R - S clocks after the transforms. Unit 0's read
    register precedes its cost unit; the cost masks take two registers (x - j*D/R, then one
    comparison per unit), so at least 3 clocks pass from the stores to the masked costs.
    With A rows the row costs are summed (registered); a single row's cost is registered
    once; then unit i's result waits S - s_i clocks for the last unit's: before SGM, or
    after the box sum (:class:`~.aggregation.Aggregation`).
    """
    transform_latency = sum(transform_plan(params, every, masks_after_compare(params)))
    rows = cost_rows(params)
    # At least a clock, so that unit 0's store write can be prepared a clock ahead.
    transformed = max(transform_latency, 3 if rows > 1 and params.stored_rows == "transforms"
                      else 1)
    skew = unit_skews(params)[-1]
    stored = transformed + (params.rounds - skew if params.rounds > 1 else 0)
    costed = max(stored + 1 + sum(cost_plan(params, every)), stored + 3)
    vertical = costed + (sum(row_sum_plan(params, every)) if rows > 1 else 1)
    # SGM takes the units' results re-aligned; the box sum takes them skewed and
    # re-aligns its own.
    vertical += skew if params.is_sgm else 0
    sums = vertical + aggregation_latency(params, every) + (0 if params.is_sgm else skew)
    min_tree = min_tree_clocks(params)
    return CalculationTiming(transformed, stored, costed, skew, vertical, sums, min_tree,
                             sums + min_tree + 1)


#: Offset (after the L/R stage's input) where its units read their stores: the candidates'
#: flags take two registers (x - j*D/R, then one comparison per unit).
LR_STAGE_A = 2


def lr_stage_b(params):
    """Offset where the L/R check's units choose and write the running winner: a clock
    after stage A, or two with R >= 3 (the word read is registered before it is
    compared; the next unit reads that word again R clocks after it first did)."""
    return LR_STAGE_A + (2 if params.rounds >= 3 else 1)


@dataclass(frozen=True)
class LRTiming:
    """Offsets inside the L/R check, in clocks after its input (the aggregated sums)."""
    left: int           #: where the left winners arrive (slot-aligned)
    exit: int           #: a final dR leaves the last unit (0 without the check)
    history: int        #: words of the left winners' store and of the dR history
    latency: int        #: the retire pulse and the output word


def lr_timing(params, left):
    """The L/R check's offsets, for left winners arriving ``left`` clocks after the sums.

    The last unit's stage B of round R-1 (:func:`lr_stage_b` + R - 1), then a register:
    the final dR. Its check then takes 9 clocks (left winners' RAM, its output register and
    a fabric register, the partner's address, the history RAM, its output register and a
    fabric register, the two comparisons with the consistency bounds, the result). The
    stores are indexed by position: the left side writes ``left`` clocks after the input,
    the check reads at ``exit``; in between the left side runs ahead by up to
    ceil((exit - left) / R) + 1 positions, and the history is read 4 clocks after
    ``exit`` while up to 4 more positions write it.
    """
    if not params.lr_check:
        return LRTiming(left, 0, 0, left + 1)
    rounds = params.rounds
    exit_ = lr_stage_b(params) + rounds
    ahead = max(-(-(exit_ - left) // rounds) + 1, 0)
    history = 1 << (params.disparities + ahead + 7 - 1).bit_length()
    return LRTiming(left, exit_, history, exit_ + 9)


@dataclass(frozen=True)
class CoreTiming:
    """Offsets of the stages' inputs, in clocks after a slot's admission."""
    calculation: int    #: the windows (calculation stage's input)
    sums: int           #: the aggregated sums (L/R check's input)
    evaluation: int     #: the partition winners (evaluation stage's input)
    left: int           #: the left winners (slot-aligned)
    output: int         #: a position's retire pulse and word, before the output queue
    queue_depth: int    #: words of the output queue


def core_timing(params, every=DEFAULT_EVERY):
    """The core's offsets, and the output queue's depth: every position in flight between
    admission and the queue must find room for its word (a credit is taken at admission),
    plus a few words so that a steady stream never waits for a credit."""
    calculation = INPUT_LATENCY
    timing = calculation_timing(params, every)
    sums = calculation + timing.sums
    evaluation = calculation + timing.latency
    left = evaluation + evaluation_latency(params)
    output = sums + lr_timing(params, left - sums).latency
    depth = 1 << (-(-output // params.rounds) + 4).bit_length()
    return CoreTiming(calculation, sums, evaluation, left, output, depth)


def latency(params):
    """Positions from a pixel's admission to the admission of the position that completes
    its output word: the window's centre trails the newest pixel by r rows and r columns,
    the aggregation centre the window's by a rows and a columns, and the L/R check waits
    D positions (positions are raster-continuous, so a row is W of them).

    After the last frame of a stream the core feeds this many dummy positions (the flush);
    a frame that follows at once needs none (its own pixels push the previous one out).
    """
    p = params
    lag = (p.radius + p.agg_radius) * (p.width + 1)
    return lag + (p.disparities if p.lr_check else 0)


def cycles_per_frame(params):
    """Clocks per frame without stalls, frames back to back: W x H x R.

    A frame that starts right after the previous one overlaps its flush (the input stage
    keeps the finishing frame's coordinates for its last centres), so each frame costs
    exactly its W x H slots. A frame after a pause (idle input) is flushed with
    :func:`latency` dummy positions, which the pause covers.
    """
    return params.width * params.height * params.rounds


# Memories ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Memory:
    """One kind of memory of the core: ``count`` memories of ``depth`` words of ``width``
    bits, and what holds them."""
    name: str
    count: int
    depth: int
    width: int

    @property
    def bits(self):
        return self.count * self.depth * self.width


def memories(params, every=DEFAULT_EVERY):
    """Every memory of the core for ``params`` (with width and height), as the components
    build them (docs/hardware.md, "Memories")."""
    p = params
    units, rounds, a = p.per_round, p.rounds, p.agg_radius
    result = [Memory("input lines", 2, p.width, 8 * (window_rows(p) - 1))]
    rows = cost_rows(p)
    if rows > 1 and p.stored_rows == "transforms":
        result.append(Memory("transform lines", 1, p.width, 2 * (rows - 1) * p.transform_bits))
    if a and p.stored_rows == "costs":
        banks = cost_banks(p)
        for depth in sorted(set(banks), reverse=True):
            result.append(Memory("cost lines", units * banks.count(depth), depth,
                                 (p.aggregation - 1) * p.cost_bits))
    if p.is_sgm:
        result += sgm_memories(p)
    if rounds > 1:
        widths = store_slices(rows * p.transform_bits)
        for width in sorted(set(widths)):
            result.append(Memory("right-transform stores", units * widths.count(width), rounds,
                                 width))
        if a:
            result.append(Memory("row taps", units, rounds, 2 * a * vertical_bits(p)))
    if p.lr_check:
        d_bits = max(1, (p.disparities - 1).bit_length())
        timing = core_timing(p, every)
        history = lr_timing(p, timing.left - timing.sums).history
        if rounds > 1:
            result.append(Memory("right winners", units, rounds,
                                 p.aggregated_cost_bits + d_bits + 1))
        result.append(Memory("left winners", 1, history, tag_layout(p).size + d_bits))
        result.append(Memory("dR history", 1, history, d_bits))
    depth = core_timing(p, every).queue_depth
    result.append(Memory("output queue", 1, depth - 1, output_width(p) + 2))
    return result


def memory_bits(params, every=DEFAULT_EVERY):
    """Bits the core's memories hold (what Yosys counts in its ``$mem_v2`` cells)."""
    return sum(memory.bits for memory in memories(params, every))


# Semi-global aggregation (hdl/sgm.py) ------------------------------------------------------

#: Clocks of the left path's loop besides its minimum tree: the store's read register,
#: C + a, the running minimum over the rounds, the minimum m, the materialised L, the next
#: a, and its write into the store before the next position reads it. The loop closes in
#: a slot of R clocks if R >= T + SGM_LOOP_CLOCKS (docs/hardware.md, "Semi-global
#: aggregation").
SGM_LOOP_CLOCKS = 6

#: Clocks from the SGM stage's input to each path's P2: the intensity steps, then P2.
SGM_GUIDE_CLOCKS = 2

#: Where the left path reads a(x, d) of round 0 from its store (the address is a local
#: round counter, a register).
SGM_LEFT_READ = 1

#: Clocks from the SGM stage's input to L of the paths from the row above (round 0): the
#: row address, its block RAM read address, the read, the RAM's output register, the
#: top-left store's read register, the newest word's register (the next round's first
#: value arrives), L + P1, the minimum of the three candidates, the normalisation, + C.
SGM_ROW_CLOCKS = 10


def _sgm_tree_clocks(units):
    """Registers of a minimum over ``units`` values: one per level (a comparison and the
    multiplexer it drives fill a 150 MHz clock on ECP5)."""
    return tree_levels(units)


def sgm_min_rounds(disparities):
    """Fewest rounds R dividing D for which the left path's loop fits a slot, or None.

    R >= T + :data:`SGM_LOOP_CLOCKS` with T = ceil(log2(D/R)); both sides move the same
    way with R, so every larger divisor fits too.
    """
    for rounds in range(1, disparities + 1):
        if disparities % rounds == 0 and \
                rounds >= _sgm_tree_clocks(disparities // rounds) + SGM_LOOP_CLOCKS:
            return rounds
    return None


def _check_sgm_rounds(params):
    """Refuse (one line) rounds too few for the left path's loop."""
    tree = _sgm_tree_clocks(params.per_round)
    if params.rounds >= tree + SGM_LOOP_CLOCKS:
        return
    need = sgm_min_rounds(params.disparities)
    if need is None:
        raise ParameterError(
            f"aggregation sgm needs rounds >= {SGM_LOOP_CLOCKS} (the left path's loop), so "
            f"disparities >= {SGM_LOOP_CLOCKS}, not {params.disparities}")
    raise ParameterError(
        f"aggregation sgm needs rounds >= {need} for {params.disparities} disparities "
        f"(the left path's loop takes {tree + SGM_LOOP_CLOCKS} clocks at "
        f"{params.per_round} per round), not {params.rounds}")


@dataclass(frozen=True)
class SgmTiming:
    """Offsets inside the SGM stage, in clocks after its input (the round's costs).

    Each is where round 0 of a position is; round j is j clocks later.
    """
    tree: int           #: T, registers of a minimum over the round's D/R values
    guide: int          #: P2 of every path (slot-aligned)
    left_read: int      #: the left path reads a(x, d) from its store
    materialise: int    #: the left path's L(x, d) is formed (m(x - 1) is there)
    left: int           #: L of the left path
    rows: int           #: L of the paths from the row above
    minima: int         #: their minima m(x) are written (the last round's running minimum)
    latency: int        #: the summed costs S


def sgm_timing(params, every=DEFAULT_EVERY):
    """The SGM stage's offsets (see :mod:`.sgm`).

    The left path reads a(x, d) at ``left_read``, registers C + a a clock later, and its
    minimum over the round (T registers) and the running minimum over the rounds (one)
    hold U(x) in the last round; m(x) follows a clock later, ``left_read + 3 + T + R``
    clocks after the input, which is R clocks into the next position: that position forms
    its L from m(x - 1) from ``left_read + 3 + T`` on (``materialise``). The paths from
    above take :data:`SGM_ROW_CLOCKS`; the four L are summed by a tree of four terms
    (registered as ``every`` says, and at its root).
    """
    tree = _sgm_tree_clocks(params.per_round)
    materialise = SGM_LEFT_READ + 3 + tree
    left = materialise + 1
    rows = SGM_ROW_CLOCKS
    summed = max(left, rows) + sum(register_plan(4, every, 0, True))
    return SgmTiming(tree, SGM_GUIDE_CLOCKS, SGM_LEFT_READ, materialise, left, rows,
                     rows + tree + params.rounds, summed)


def sgm_memories(params):
    """The SGM stage's memories (docs/hardware.md, "Memories").

    Block RAM: the previous row's path costs, one word per (column, round) of D/R values,
    top and top-left in one memory (both read the position's own column), top-right in
    another (it reads the next column); the three paths' minima, one word per column.
    LUT RAM: the left path's a(x, d) and the top-left words held for the next position,
    one word per round each.
    """
    p = params
    word = p.per_round * p.path_cost_bits
    return [Memory("path rows (top, top-left)", 1, p.width * p.rounds, 2 * word),
            Memory("path rows (top-right)", 1, p.width * p.rounds, word),
            Memory("path minima", 1, p.width, 3 * p.path_cost_bits),
            Memory("left path store", 1, p.rounds, word),
            Memory("top-left store", 1, p.rounds, word)]
