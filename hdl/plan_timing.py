"""When the hardware does what, as pure functions of the parameters.

The clock offsets of the stages, which the components take for their ``latency`` attributes
and their internal timing, and what follows from them for the whole core: its latency in
positions (the flush), its cycles per frame, its output queue's depth. Offsets are clocks
after a slot's first clock (its admission, see :mod:`.core`); a value *at* an offset is
slot-aligned there (see :mod:`.common`). ``tests/test_hdl_plan.py`` measures them on the
elaborated hardware.
"""

from dataclasses import dataclass

from ..params import SGM_ROW_PATHS, SGM_TRACK_AGE, SGM_TRACK_STEPS
from .plan_structure import (bank_choice_levels, choice_levels, cost_plan, cost_rows,
                             horizontal_plan, masks_after_compare, row_banks, row_sum_plan,
                             transform_plan, vertical_plan)
from .cost_term import term_clocks
from .median import MEDIAN_LATENCY
from .trees import DEFAULT_EVERY, min_tree_latency, register_plan, tree_levels

__all__ = ["INPUT_LATENCY", "MAX_SKEW_ONE_ROUND", "unit_skews", "VERTICAL_READ",
           "vertical_read", "vertical_clocks", "aggregation_latency", "min_tree_clocks",
           "CalculationTiming", "calculation_timing", "SGM_GUIDE_CLOCKS", "SGM_ROW_CLOCKS",
           "sgm_row_clocks", "SGM_ABOVE_EVERY", "SGM_LEFT_LEAD", "sgm_left_stages",
           "sgm_left_firsts_registered", "sgm_left_shift_store", "sgm_tree_clocks", "SgmTiming",
           "sgm_timing", "FifthTiming", "sgm_fifth_timing", "evaluation_latency",
           "LR_STAGE_A", "lr_stage_b", "LRTiming", "lr_timing", "CoreTiming", "core_timing", "latency",
           "cycles_per_frame"]


# The input stage --------------------------------------------------------------------------

#: Clocks from the admission of a pixel to the window: the line buffers' block RAM read,
#: its output register, the window's shift, the masked window's register, a second
#: register of the window and the centres' copies.
INPUT_LATENCY = 5
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


# Semi-global aggregation (hdl/sgm.py) -----------------------------------------------------

#: Clocks from the SGM stage's input to each path's P2: the intensity steps, then P2.
SGM_GUIDE_CLOCKS = 2


#: Clocks from the SGM stage's input to L of the paths from the row above (round 0): the
#: column's flags, the row address, its block RAM read address, the read, the RAM's output
#: register, the top-left store's read register, the newest word's register (the next
#: round's first value arrives), L + P1, the comparisons of the three candidates, their
#: minimum, the normalisation's comparison and difference, its choice, + C; with the rows
#: in one bank (:func:`sgm_row_clocks`).
SGM_ROW_CLOCKS = 13


def sgm_row_clocks(params):
    """Clocks to L of the paths from the row above: :data:`SGM_ROW_CLOCKS`, and with the
    path rows in several banks (W R words, :func:`~.plan_structure.row_banks`) a clock more
    for the register behind each bank's and a clock more per level of the bank's choice
    (:func:`~.banks.banked_memory`)."""
    banks = len(row_banks(params))
    return SGM_ROW_CLOCKS + (1 + choice_levels(banks) if banks > 1 else 0)


#: Register spacing of the sum of the three paths from above: every level (two additions
#: in one clock were census 7x7 SGM's path at R = 10, 6.96 ns; the sum waits for the left
#: path's L anyway).
SGM_ABOVE_EVERY = 1


#: Clocks from the left path's minimum tree over C(0, .) (``tree`` + R after the input) to
#: its loop (hdl/sgm_left.py): b(x) of the history or of G(0) registered (<= 1 clock after),
#: C(p, b) picked (two clocks), its file written, the picked costs read, their sum with P2,
#: then ref + P2 (the clock before the loop).
SGM_LEFT_LEAD = 6




def sgm_left_pairs(rounds):
    """Whether the left path's loop spans two positions (R = 1): with the small step only
    into odd columns (``params.SGM_LEFT_P1_PARITY``) Lu(x) of an even column is one minimum
    over Lu(x - 2, .) and the two references, compared in one clock and chosen and added
    in the next, while an odd column's Lu comes from the same comparisons outside the loop.
    One position per clock leaves a one-position loop one clock (its comparison, choice and
    addition in series: 81.8 MHz on ECP5, docs/sgm/lane_loop_probe.py); the two-position
    loop two (149.7 MHz, its ``pairs`` style)."""
    return rounds == 1


def sgm_left_stages(rounds):
    """Clocks of the left path's lane update: round j + 1 of x - 1 is written R - 1 clocks
    before round j of x reads it, so the update may take up to R - 1 clocks. One clock
    (comparisons, choice and addition) at R = 2; the comparisons registered at R = 3; from
    R = 4 the choice registered as well, so that each clock holds one carry chain or one
    multiplexer (the choice and the 11-bit addition were 9.6 ns in one clock,
    docs/sgm/lane_loop_probe.py). At R = 1 (:func:`sgm_left_pairs`) Lu is there three
    clocks after the loop's read: an odd column compares a clock after its slot (Lu of
    the even column before it is written then), then chooses and adds."""
    if sgm_left_pairs(rounds):
        return 3
    return min(max(rounds - 1, 1), 3)


def sgm_left_firsts_registered(rounds):
    """Whether the store of the rounds' first lanes, read a clock early into a register,
    always has the word (from R = 5). Round j of x reads the first lane of round j + 1 of
    x - 1, written in clock T - R + j + stages (one later than round j), so the early read
    needs stages + 1 <= R - 1. At R = 3, 4 (stages + 1 = R) the word is written in the
    clock before the read whenever the slot before held a position: the stage then takes
    it from the write's register instead."""
    return not sgm_left_shift_store(rounds) and sgm_left_stages(rounds) + 1 <= rounds - 1


def sgm_left_shift_store(rounds):
    """The left path's store in shifting registers (:class:`~.common.ShiftStore`) where its
    update takes one clock (R <= 2): Lu(x, round j) is then written in the clock that reads
    Lu(x - 1, round j), always the R-th write before, so the read is one register. In LUT
    RAM at R = 2 the read address, the RAM's read, + P1, the comparisons, the choice and
    the addition in one clock were census 5x5 SGM's critical path at 640 x 480, D = 64
    (19.1 ns, 14 levels, 52.4 MHz). From R = 3 the update's clocks would move the word read
    with the gaps between positions, and R words of LUT RAM cost less than R words of
    flip-flops; there Lu(x - 1, round j), written in clock T - R + j + stages - 1 for the
    read of round j of x in clock T + j, is there two clocks early (stages + 1 <= R), and
    the LUT RAM is read a clock early into a register. At R = 1 the loop's state is Lu of
    the last even column, one register per lane (:func:`sgm_left_pairs`)."""
    return rounds == 2


def sgm_tree_clocks(units):
    """Registers of a minimum over ``units`` values: one per level (a comparison and the
    multiplexer it drives fill a 150 MHz clock on ECP5)."""
    return tree_levels(units)


@dataclass(frozen=True)
class SgmTiming:
    """Offsets inside the SGM stage, in clocks after its input (the round's costs).

    Each is where round 0 of a position is; round j is j clocks later.
    """
    tree: int           #: T, registers of a minimum over the round's D/R values
    guide: int          #: P2 of every path (slot-aligned)
    loop: int           #: the left path's loop reads Lu(x - 1, .) (ref + P2 is there)
    left_stages: int    #: clocks of the loop's lane update (:func:`sgm_left_stages`)
    left_pairs: bool    #: the loop spans two positions (:func:`sgm_left_pairs`)
    left_reference: int  #: ref(x) + P2(x) is loaded (there a clock later)
    left_lu: int        #: Lu(x, .) in its register
    left_argmin: int    #: m(x) and argmin Lu(x, .) complete
    left_argmin_split: bool  #: the argmin tree's comparisons and choices in clocks of their own
    left_early: int     #: m(0) and argmin C(0, .) complete (from the costs)
    left_hand: int      #: m(0) stored for the row's first J positions
    left_history: int   #: clocks of the multiplexer that reads b(p + k) from the history
    left_sum_clocks: int  #: clocks from reading the picked costs C(x - k, b(x)) to their sum
    left_start_early: bool  #: ref's start, Lu(x - J, b(x)) or m(0), chosen a clock early
    left_picks: tuple   #: per k = 1 .. J, where position p registers b(p + k)
    left: int           #: L of the left path
    rows: int           #: L of the paths from the row above
    minima: int         #: their minima m(x) are written (the last round's running minimum)
    latency: int        #: the summed costs S


def sgm_timing(params, every=DEFAULT_EVERY):
    """The SGM stage's offsets (see :mod:`.sgm` and :mod:`.sgm_left`).

    The left path: the argmin over C(0, .) is complete at T + R (``left_early``); the loop
    reads at ``loop`` = T + :data:`SGM_LEFT_LEAD` + 1 and has Lu(x, .) in a register
    ``left_stages`` later; its argmin at T (2T with the tree split) + R after that.
    Position p registers b(p + k) as early as both G(p + k - K) (``left_argmin`` of a
    position (K - k) slots back) and G(0) allow; the asserts below are the margins of docs/hardware.md ("Semi-global
    aggregation"), which hold for every D <= 256 and R dividing D. L = Lu - m(x - 1)
    leaves 2 clocks after m(x - 1). The paths from above take :data:`SGM_ROW_CLOCKS`; the
    three paths' L are summed by a tree (registered as ``every`` says, and at its root),
    and that sum and the left path's L by another.
    """
    rounds, steps, age = params.rounds, SGM_TRACK_STEPS, SGM_TRACK_AGE
    tree = sgm_tree_clocks(params.per_round)
    stages, pairs = sgm_left_stages(rounds), sgm_left_pairs(rounds)
    early = tree + rounds
    # ref + P2 in the clock before the loop, two before a loop over two positions (which
    # compares it with the costs' sum a clock earlier).
    reference = tree + SGM_LEFT_LEAD
    loop = reference + 1 + pairs
    lu = loop + stages
    hand = max(early + 1, reference)
    # b(p + k) registered once G(p + k - K) and G(0) are there; it holds for R clocks, as
    # long as the first level of its multiplexer needs it: C(p, .) is delayed to it, and
    # for k = J it is registered just before Lu(p, .).
    # The history's multiplexer takes two clocks (read a clock before b is registered, from
    # the column two clocks before), and the picked costs are read from their files a clock
    # before they are summed, where the margins below allow it: everywhere but at R = 1
    # with T = 8 (D > 128), where each takes one clock.
    def picks_with(argmin, history):
        return tuple(max(tree + 1, history, argmin + history - (age - k) * rounds)
                     for k in range(1, steps)) + (lu - 1,)

    def margins(picks, sum_clocks):
        return all(at + rounds + 2 <= k * rounds + reference - sum_clocks
                   for k, at in enumerate(picks[:-1], 1))
    # The argmin tree over Lu(x, .) takes two clocks a level (the comparison, then the
    # choice) where the margins still allow both two-clock multiplexers below: a level's
    # 11-bit comparison and its choice of value and lane in one clock were census 7x7 SGM's
    # recurring path at R = 10 (7.1-8.1 ns, 10-12 cells, in four placements of seven).
    units = params.per_round
    split = margins(picks_with(lu + min_tree_latency(units, True) + rounds, 2), 2)
    argmin = lu + min_tree_latency(units, split) + rounds
    # Three clocks for the sum (the picked costs registered, the first level of additions
    # registered, then the last) where the margins allow them with the history's two: the
    # two levels of additions in one clock recurred in census 7x7 SGM's placements at
    # R = 10 (6.69-7.17 ns, 10-11 cells).
    history, sum_clocks = next((h, s) for h, s in ((2, 3), (2, 2), (2, 1), (1, 2), (1, 1))
                               if margins(picks_with(argmin, h), s))
    picks = picks_with(argmin, history)
    # C(x - k, b(x)) in its file before position x reads it at reference - sum_clocks.
    assert margins(picks, sum_clocks), picks
    for k, at in enumerate(picks, 1):
        # G(p + k - K) in the history before position p reads it.
        assert at - history + (age - k) * rounds >= argmin, (k, at)
    # Lu(x - J, b) in its file before position x reads it at ``reference``.
    assert lu + rounds + 1 <= steps * rounds + reference
    # ... and a clock earlier, with m(0) (stored at ``hand`` of the row's first position),
    # where the reference's start is chosen in a clock of its own: its file's multiplexer
    # and the addition in one clock were census 7x7 SGM's path at R = 10 (7.57 ns).
    start_early = (lu + rounds + 1 <= steps * rounds + reference - 1
                   and hand + 1 <= rounds + reference - 1)
    # m(x - 1) is there R clocks before argmin, and L = Lu - m(x - 1) leaves 2 clocks after.
    left = argmin - rounds + 2
    rows = sgm_row_clocks(params)
    # The three paths from above are summed first (then wait for the left path as one
    # sum, not three L), then the left path's L is added.
    above = rows + sum(register_plan(len(SGM_ROW_PATHS), SGM_ABOVE_EVERY, 0, True))
    summed = max(left, above) + sum(register_plan(2, every, 0, True))
    return SgmTiming(tree, SGM_GUIDE_CLOCKS, loop, stages, pairs, reference, lu, argmin, split, early, hand,
                     history, sum_clocks, start_early, picks, left, rows,
                     rows + tree + rounds, summed)


def sgm_delays(params, every=DEFAULT_EVERY):
    """The SGM stage's free-running delays in clocks (:func:`.common.delay_line`): the sum
    of the three paths from above (``above``) and the left path's L (``left``) to where
    they are added, and the left path's Lu to its normalisation by m(x - 1) (``lu``)."""
    t = sgm_timing(params, every)
    above = t.rows + sum(register_plan(len(SGM_ROW_PATHS), SGM_ABOVE_EVERY, 0, True))
    aligned = max(t.left, above)
    return {"above": aligned - above, "left": aligned - t.left, "lu": t.left - 1 - t.left_lu}


@dataclass(frozen=True)
class FifthTiming:
    """Offsets of the fifth path (:mod:`.sgm_right`) after the SGM stage's input; each
    row buffer is read at its offset and written a clock later."""
    costs: int          #: the costs row (C and the left path's P2) is read
    four: int           #: the four paths' sum S4 (its row is read a clock before)
    right: int          #: L_right of the previous row, mirrored (the recursion's output)
    latency: int        #: S5 of the row before that, in raster order (its row's read data)


def sgm_fifth_timing(params, every=DEFAULT_EVERY):
    """The fifth path's offsets: the costs row read as late as lets the recursion (the left
    path's ``left`` clocks) end where S4 is there, or later, S5 registered after both."""
    t = sgm_timing(params, every)
    costs = max(t.guide, t.latency - t.left - 1)
    right = costs + 1 + t.left
    return FifthTiming(costs, t.latency, right, right + 1)


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


def lr_exit_delay(params, left):
    """Clocks by which the final dR waits before the check: the left winner of position n
    must be in its store (written at ``left``) before position n + D leaves the chain, at
    least D R clocks later. Only the sub-pixel fit (:func:`subpixel_clocks`) brings the
    left winners late enough for that, at small D R; otherwise 0."""
    return max(0, left + 1 - (lr_stage_b(params) + params.rounds) - params.disparities
               * params.rounds)


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
    left = evaluation + evaluation_latency(params) + subpixel_clocks(params)
    output = sums + lr_timing(params, left - sums).latency
    if params.median:
        output += MEDIAN_LATENCY
    depth = 1 << (-(-output // params.rounds) + 4).bit_length()
    return CoreTiming(calculation, sums, evaluation, left, output, depth)


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
