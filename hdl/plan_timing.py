"""When the hardware does what, as pure functions of the parameters.

The clock offsets of the stages, which the components take for their ``latency`` attributes
and their internal timing, and what follows from them for the whole core: its latency in
positions (the flush), its cycles per frame, its output queue's depth. Offsets are clocks
after a slot's first clock (its admission, see :mod:`.core`); a value *at* an offset is
slot-aligned there (see :mod:`.common`). ``tests/test_hdl_plan.py`` measures them on the
elaborated hardware.
"""

from dataclasses import dataclass

from .plan_structure import (bank_choice_levels, cost_plan, cost_rows,
                             horizontal_plan, masks_after_compare, row_sum_plan,
                             transform_plan, vertical_plan)
from .cost_term import term_clocks
from .median import MEDIAN_LATENCY
from .plan_sgm_timing import (SGM_ABOVE_EVERY, SGM_GUIDE_CLOCKS,  # noqa: F401
                              SGM_HISTORY_PAIRS_CLOCKS, SGM_LEFT_LATE_CLOCKS,
                              SGM_LEFT_LEAD, SGM_ROW_CLOCKS,
                              FifthTiming, SgmTiming, sgm_delays,
                              sgm_fifth_forwarded, sgm_fifth_timing,
                              sgm_left_firsts_registered,
                              sgm_left_pairs, sgm_left_shift_store, sgm_left_stages,
                              sgm_row_clocks, sgm_timing, sgm_tree_clocks)
from .trees import DEFAULT_EVERY, min_tree_latency

__all__ = ["INPUT_LATENCY", "decision_clocks", "MAX_SKEW_ONE_ROUND", "unit_skews", "VERTICAL_READ",
           "vertical_read", "vertical_clocks", "aggregation_latency", "min_tree_clocks",
           "CalculationTiming", "calculation_timing", "SGM_GUIDE_CLOCKS", "SGM_ROW_CLOCKS",
           "sgm_row_clocks", "SGM_ABOVE_EVERY", "SGM_LEFT_LEAD", "SGM_LEFT_LATE_CLOCKS",
           "SGM_HISTORY_PAIRS_CLOCKS",
           "sgm_left_stages",
           "sgm_left_firsts_registered", "sgm_left_shift_store", "sgm_tree_clocks", "SgmTiming",
           "sgm_timing", "sgm_left_pairs", "sgm_delays", "FifthTiming", "sgm_fifth_timing",
           "sgm_fifth_forwarded", "reversed_sums_clocks", "reversed_sums_depth",
           "ROW_TURN_LATENCY",
           "evaluation_latency",
           "LR_STAGE_A", "lr_stage_b", "LRTiming", "lr_timing", "CoreTiming", "core_timing", "latency",
           "cycles_per_frame"]


# The input stage --------------------------------------------------------------------------

#: Clocks from the admission of a pixel to the window: the line buffers' block RAM read,
#: its output register, the window's shift, the masked window's register, a second
#: register of the window and the centres' copies.
INPUT_LATENCY = 5


def decision_clocks(rounds):
    """Clocks from the admission's decision to the input stage: at R = 1 the decision is
    registered by the admission (hdl/core.py), and the input stage takes it a clock
    later."""
    return 1 if rounds == 1 else 0
#: Registers every output word passes after ``CoreTiming.output`` besides the output queue
#: and the port's register slice: its register into the queue and the slice by the queue
#: (hdl/core.py).
OUTPUT_REGISTERS = 2


# The calculation stage and the box aggregation --------------------------------------------

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


#: Clocks until the rows of a vertical sum from stored costs are there with the bank
#: chosen in one level (:func:`bank_choice_levels`): the address register, the block RAM
#: read, each bank's output register, the bank's choice, then the read register. Each
#: further level of the choice adds a clock (:func:`vertical_read`).
VERTICAL_READ = 5


def vertical_read(params):
    """Clocks until the rows of a vertical sum from stored costs are there."""
    return VERTICAL_READ + bank_choice_levels(params) - 1


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
        timing = sgm_fifth_timing if params.fifth_path else sgm_timing
        return timing(params, every).latency
    if not params.agg_radius:
        return 0
    return vertical_clocks(params, every) + 1 + sum(horizontal_plan(params, every))


def min_tree_clocks(params):
    """Clocks of the partition's WTA over D/R aggregated costs: two per level (the
    comparison, registered with both candidates, then the choice of the whole (cost,
    index) pair; see :func:`~.trees.build_min_tree`)."""
    return min_tree_latency(params.per_round)


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
    comparison per unit), so at least 3 clocks pass from the stores to the masked costs, and
    with a cost term at least its clocks (:mod:`.cost_term`).
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
    costed = max(stored + 1 + sum(cost_plan(params, every)), stored + 3,
                 stored + 1 + term_clocks(params))
    vertical = costed + (sum(row_sum_plan(params, every)) if rows > 1 else 1)
    # SGM takes the units' results re-aligned; the box sum takes them skewed and
    # re-aligns its own.
    vertical += skew if params.is_sgm else 0
    sums = vertical + aggregation_latency(params, every) + (0 if params.is_sgm else skew)
    min_tree = min_tree_clocks(params)
    return CalculationTiming(transformed, stored, costed, skew, vertical, sums, min_tree,
                             sums + neighbour_clocks(params) + min_tree + 1)


def neighbour_clocks(params):
    """Clocks by which the partition's WTA takes the sums late to carry the winner's
    neighbours (hdl/subpixel.py): one with F > 0 and R > 1, where the next round's
    unit 0 is the last unit's d + 1."""
    return 1 if params.subpixel_bits and params.rounds > 1 else 0


def subpixel_clocks(params):
    """Clocks of the sub-pixel fit (:class:`~.subpixel.SubpixelFit`), 0 without it: the
    differences, their sum, the numerator, the F + 1 stages of the divider, the value."""
    return params.subpixel_bits + 5 if params.subpixel_bits else 0


# Evaluation, L/R check, the whole core ----------------------------------------------------

def evaluation_latency(params):
    """Clocks from the evaluation stage's input (round 0's partition winner) to the
    position's winner, slot-aligned: the R winners of a slot are in a shift register
    after round R-1, a minimum tree over them (:func:`~.trees.build_min_tree`), then the
    winner's register."""
    return params.rounds + min_tree_latency(params.rounds)


#: Offset (after the L/R stage's input) where its units read their stores: the candidates'
#: flags take two registers (x - j*D/R, then one comparison per unit).
LR_STAGE_A = 2


def lr_stage_b(params):
    """Offset where the L/R check's units choose and write the running winner: a clock
    after stage A, or two with R >= 3 (the word read is registered before it is
    compared; the next unit reads that word again R clocks after it first did)."""
    return LR_STAGE_A + (2 if params.rounds >= 3 else 1)


#: Registers of the final dR and its pulse between the last unit and the check's counters
#: and history: the pulse straight from the last unit into the counters was census 5x5
#: box's critical path at 1280 x 720, D = 64, R = 1 (7.57 ns, one LUT).
LR_EXIT_REGISTERS = 1


def lr_exit_delay(params, left):
    """Clocks by which the final dR waits before the check: :data:`LR_EXIT_REGISTERS`, or
    more where the left winner of position n would not be in its store (written at
    ``left``) before position n + D leaves the chain, at least D R clocks later: only the
    sub-pixel fit (:func:`subpixel_clocks`) brings the left winners that late, at small
    D R."""
    return max(LR_EXIT_REGISTERS, left + 1 - (lr_stage_b(params) + params.rounds)
               - params.disparities * params.rounds)


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
    exit_ = lr_stage_b(params) + rounds + lr_exit_delay(params, left)
    ahead = max(-(-(exit_ - left) // rounds) + 1, 0)
    history = 1 << (params.disparities + ahead + 7 - 1).bit_length()
    return LRTiming(left, exit_, history, exit_ + 9)


def reversed_sums_clocks(params):
    """Clocks by which the L/R check's sums are late on mirrored rows (the fifth path, with
    the check), candidates in reversed order (:func:`~.mirror.reversed_sums`): R + 1 with R > 1 (a
    slot's rounds turned round), 0 at R = 1 (its lanes only)."""
    mirrored = params.fifth_path and params.lr_check
    return params.rounds + 1 if mirrored and params.rounds > 1 else 0


def reversed_sums_depth(rounds):
    """Words of :func:`~.mirror.reversed_sums`'s ring at R = ``rounds`` > 1: a power of two
    holding the 2R clocks that the last round of a slot waits."""
    return 1 << (2 * rounds - 1).bit_length()


#: Clocks from a tick into :class:`~.mirror.RowTurn` to its word: the tick's register
#: (with both addresses), the read, the block RAM's output register, the forwarded word's
#: choice into the output registers.
ROW_TURN_LATENCY = 4


@dataclass(frozen=True)
class CoreTiming:
    """Offsets of the stages' inputs, in clocks after a slot's admission."""
    calculation: int    #: the windows (calculation stage's input)
    sums: int           #: the aggregated sums
    check: int          #: the L/R check's input (the sums, reversed on mirrored rows)
    evaluation: int     #: the partition winners (evaluation stage's input)
    left: int           #: the left winners (slot-aligned)
    output: int         #: a position's retire pulse and word, before the output queue
    queue_depth: int    #: words of the output queue


#: Clocks a credit is away after ``CoreTiming.output``: the word's register into the output
#: queue, the queue's two (SyncFIFOBuffered), then the returned credit's two registers, the
#: counter and its room flag (hdl/core.py). Left out of the queue's depth, a steady stream
#: at R = 1 waited for credits (3 clocks in 67, census 3x3 SGM with the fifth path).
CREDIT_RETURN = 7


def core_timing(params, every=DEFAULT_EVERY):
    """The core's offsets, and the output queue's depth: every position in flight between
    admission and the queue must find room for its word (a credit is taken at admission),
    plus a few words so that a steady stream never waits for a credit."""
    calculation = decision_clocks(params.rounds) + INPUT_LATENCY
    timing = calculation_timing(params, every)
    sums = calculation + timing.sums
    evaluation = calculation + timing.latency
    left = evaluation + evaluation_latency(params) + subpixel_clocks(params)
    check = sums + reversed_sums_clocks(params)
    output = check + lr_timing(params, left - check).latency
    if params.fifth_path:
        output += ROW_TURN_LATENCY
    if params.median:
        output += MEDIAN_LATENCY
    depth = 1 << (-(-(output + CREDIT_RETURN) // params.rounds) + 4).bit_length()
    return CoreTiming(calculation, sums, check, evaluation, left, output, depth)


def latency(params):
    """Positions from a pixel's admission to the admission of the position that completes
    its output word: the window's centre trails the newest pixel by r rows and r columns,
    the aggregation centre the window's by a rows and a columns, the L/R check waits
    D positions and the 3x3 median W + 1 (positions are raster-continuous, so a row is W
    of them).

    After the last frame of a stream the core feeds this many dummy positions (the flush);
    a frame that follows at once needs none (its own pixels push the previous one out).
    """
    p = params
    lag = (p.radius + p.agg_radius) * (p.width + 1)
    # The fifth path gives a row's sums while the row after the next streams in.
    lag += 2 * p.width if p.fifth_path else 0
    return lag + (p.disparities if p.lr_check else 0) + (p.width + 1 if p.median else 0)


def cycles_per_frame(params):
    """Clocks per frame without stalls, frames back to back: W x H x R.

    A frame that starts right after the previous one overlaps its flush (the input stage
    keeps the finishing frame's coordinates for its last centres), so each frame costs
    exactly its W x H slots. A frame after a pause (idle input) is flushed with
    :func:`latency` dummy positions, which the pause covers.
    """
    return params.width * params.height * params.rounds
