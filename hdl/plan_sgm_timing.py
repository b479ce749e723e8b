"""When the SGM stage does what (:mod:`.sgm`, :mod:`.sgm_left`, :mod:`.sgm_right`), as pure
functions of the parameters: the part of :mod:`.plan_timing` for semi-global aggregation
(which re-exports it for the rest of the core's timing).
"""

from dataclasses import dataclass

from ..params import SGM_ROW_PATHS, SGM_TRACK_AGE, SGM_TRACK_STEPS
from .plan_structure import banked_read_clocks, row_banks
from .trees import DEFAULT_EVERY, min_tree_latency, register_plan, tree_levels

__all__ = ["SGM_GUIDE_CLOCKS", "SGM_ROW_CLOCKS", "sgm_row_clocks", "SGM_ABOVE_EVERY",
           "SGM_LEFT_LEAD", "SGM_LEFT_LATE_CLOCKS", "SGM_HISTORY_PAIRS_CLOCKS",
           "sgm_left_pairs", "sgm_left_stages",
           "sgm_left_firsts_registered",
           "sgm_left_shift_store", "sgm_tree_clocks", "SgmTiming", "sgm_timing", "sgm_delays",
           "FifthTiming", "sgm_fifth_timing", "sgm_fifth_forwarded"]


#: Clocks from the SGM stage's input to each path's P2: the intensity differences, their
#: magnitudes (the steps), then P2.
SGM_GUIDE_CLOCKS = 3


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
    return SGM_ROW_CLOCKS - banked_read_clocks(1) + banked_read_clocks(len(row_banks(params)))


#: Register spacing of the sum of the three paths from above: every level (two additions
#: in one clock were census 7x7 SGM's path at R = 10, 6.96 ns; the sum waits for the left
#: path's L anyway).
SGM_ABOVE_EVERY = 1


#: Clocks from reading the picked costs to their sum where C(x - 1, b(x)) joins it last
#: (``SgmTiming.left_sum_late``): its own (read, registered, then the last addition), and
#: the others' (read, registered, three levels of additions over J - 1 terms and P2, each
#: registered, then the last addition).
SGM_LEFT_LATE_CLOCKS = (2, 5)


#: Clocks of the chain's history reader where its margins allow them: the entry's index
#: copied, then a registered level of 4:1 multiplexers per two of its five bits (K = 32)
#: (``sgm_left_reference._pick_by_pairs``). An 8:1 first level (three clocks) was census 7x7
#: SGM's critical path at D = 100, R = 10, 450 x 375 (the index copy into it, 6.78 ns,
#: 3 LUT levels, 5.55 ns of wire).
SGM_HISTORY_PAIRS_CLOCKS = 1 + -(-(SGM_TRACK_AGE.bit_length() - 1) // 2)


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
    left_sum_late: bool  #: C(x - 1, b(x)) joins the sum last (:data:`SGM_LEFT_LATE_CLOCKS`)
    left_read_split: bool  #: ... and the picked costs' files are read in two clocks, a clock earlier
    left_start_early: bool  #: ref's start, Lu(x - J, b(x)) or m(0), chosen a clock early
    left_start_read: bool  #: ... and Lu(x - J, b(x)) read from its file a clock before that
    left_picks: tuple   #: per k = 1 .. J, where position p registers b(p + k)
    left_chain: int     #: the first k whose b(p + k) comes down the chain (the rest read)
    left_chain_at: int  #: where position p shifts the chain (b(p + J) read from the history)
    left_chain_history: int  #: clocks of the multiplexer that reads b(p + J) for the chain
    left: int           #: L of the left path
    rows: int           #: L of the paths from the row above
    above: int          #: the sum of those three L
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

    def margins(picks, sum_clocks, first_clocks=None):
        # (``first_clocks``: C(x - 1, b(x))'s own where it is read apart from the others.)
        return all(at + rounds + 2 <= k * rounds + reference - (
                       first_clocks if k == 1 and first_clocks is not None else sum_clocks)
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
    # The sum with a clock per level of additions where the margins allow it: C(x - 1,
    # b(x)), picked last, joins the sum of the others in the last clock. Two levels of
    # additions in one clock were census 7x7 SGM's critical path at 640 x 480, D = 64,
    # R = 4 (7.81 ns, 8 levels, 128.1 MHz).
    # (P2 joins the others' terms, so it must be there: not with one lane, T = 0.)
    late, rest = SGM_LEFT_LATE_CLOCKS
    sum_late = reference - rest + 1 >= SGM_GUIDE_CLOCKS and margins(picks, rest, late)
    # ... and each file's multiplexer in two clocks (the entry's low bits within groups,
    # registered, then the group) where the files are written a clock earlier still: the
    # entry through the eight-way multiplexer into the term's register was the floor of
    # the recommended configuration at 1280 x 720 (6.74 ns, 4 levels, 148.3 MHz).
    read_split = sum_late and margins(picks, rest + 1, late + 1)
    for k, at in enumerate(picks, 1):
        # G(p + k - K) in the history before position p reads it.
        assert at - history + (age - k) * rounds >= argmin, (k, at)
    # The chain: position p reads b(p + J) from the history once G(p + J - K) is there and
    # shifts b(p + k + 1) of the position before into b(p + k), for every k whose pick is
    # no earlier (then delayed to it). Everywhere but at R = 1, where G(p + J - K) comes
    # too late for the first picks, the history then has one reader instead of J: J
    # two-clock multiplexers over its K entries were census 7x7 SGM's critical path at
    # R = 10 (11.30 ns, 8.9 of it routing, 88.5 MHz).
    ready = argmin + history - (age - steps) * rounds
    chain = next(k for k, at in enumerate(picks, 1) if at >= ready)
    chain_at = picks[chain - 1]
    # The chain's one reader in three clocks (the group's choice registered too) where
    # G(p + J - K) is there for it: the entry's index through the first level into its
    # register was census 5x5 SGM's critical path at 1280 x 720, D = 64, R = 4 (6.75 ns,
    # 4 levels, 148.2 MHz).
    # With more margin, in SGM_HISTORY_PAIRS_CLOCKS (4) clocks.
    chain_history = next((clocks for clocks in (SGM_HISTORY_PAIRS_CLOCKS, 3)
                          if chain_at >= clocks and
                          chain_at - clocks + (age - steps) * rounds >= argmin), history)
    assert list(picks) == sorted(picks), picks
    # Lu(x - J, b) in its file before position x reads it at ``reference``.
    assert lu + rounds + 1 <= steps * rounds + reference
    # ... and a clock earlier, with m(0) (stored at ``hand`` of the row's first position),
    # where the reference's start is chosen in a clock of its own: its file's multiplexer
    # and the addition in one clock were census 7x7 SGM's path at R = 10 (7.57 ns).
    start_early = (lu + rounds + 1 <= steps * rounds + reference - 1
                   and hand + 1 <= rounds + reference - 1)
    # ... and its file read into a register a clock before that choice (m(0) is still
    # chosen where it was): the file's multiplexer and the choice in one clock were census
    # 7x7 SGM's critical path at 640 x 480, D = 64, R = 4 (8.93 ns, 4 levels, 112.0 MHz).
    start_read = start_early and lu + rounds + 1 <= steps * rounds + reference - 2
    # m(x - 1) is there R clocks before argmin, and L = Lu - m(x - 1) leaves 2 clocks after.
    left = argmin - rounds + 2
    rows = sgm_row_clocks(params)
    # The three paths from above are summed first (then wait for the left path as one
    # sum, not three L), then the left path's L is added.
    above = rows + sum(register_plan(len(SGM_ROW_PATHS), SGM_ABOVE_EVERY, 0, True))
    summed = max(left, above) + sum(register_plan(2, every, 0, True))
    return SgmTiming(tree, SGM_GUIDE_CLOCKS, loop, stages, pairs, reference, lu, argmin, split, early, hand,
                     history, sum_clocks, sum_late, read_split, start_early, start_read, picks, chain,
                     chain_at, chain_history, left, rows,
                     above, rows + tree + rounds, summed)


def sgm_delays(params, every=DEFAULT_EVERY):
    """The SGM stage's free-running delays in clocks (:func:`.common.delay_line`): the sum
    of the three paths from above (``above``) and the left path's L (``left``) to where
    they are added, and the left path's Lu to its normalisation by m(x - 1) (``lu``)."""
    t = sgm_timing(params, every)
    aligned = max(t.left, t.above)
    return {"above": aligned - t.above, "left": aligned - t.left, "lu": t.left - 1 - t.left_lu}


@dataclass(frozen=True)
class FifthTiming:
    """Offsets of the fifth path (:mod:`.sgm_right`) after the SGM stage's input; each
    row buffer is read at its offset and written a clock later."""
    costs: int          #: the costs row (C and the left path's P2) is read
    recursion: int      #: the word read, forwarded and registered, enters the recursion
    four: int           #: the four paths' sum S4 (its row is read a clock before)
    right: int          #: L_right of the previous row, mirrored (the recursion's output)
    latency: int        #: S5 of the previous row, mirrored (registered after the addition)


def sgm_fifth_forwarded(params):
    """Clocks k between a word's write and a read of its address that the fifth path's
    rows (``sgm_right._turnaround``) forward, their read being issued ``ahead`` clocks
    before its word is there (:func:`~.plan_structure.banked_read_clocks`): 0 < k <
    ``ahead``. A word's address is its round's too, and slots are R clocks, so only
    multiples of R occur (a row's first positions reading the column its last ones wrote).
    """
    ahead = banked_read_clocks(len(row_banks(params)))
    return list(range(params.rounds, ahead, params.rounds))


def sgm_fifth_timing(params, every=DEFAULT_EVERY):
    """The fifth path's offsets: the costs row read as late as lets the recursion (the left
    path's ``left`` clocks) end where S4 is there, or later (and no earlier than its banks'
    read takes from two clocks after the input), S5 registered after both."""
    t = sgm_timing(params, every)
    # The costs row's read is issued that many clocks before its word is there
    # (``sgm_right._turnaround``), from the column (slot-aligned at 1) in a register: the
    # column's choice from the row's direction, straight from the input's tag into the
    # read address, was census 5x5 SGM's critical path at 1280 x 720, R = 4 (9.38 ns, 5
    # levels).
    ahead = banked_read_clocks(len(row_banks(params)))
    # The word read (``costs`` + 1) is registered behind its forwarding multiplexers: they
    # fed the recursion's first minimum tree straight from the banks' last register (4 LUTs
    # and a carry chain, the deepest path of census 5x5 SGM with the fifth path).
    costs = max(t.guide, t.latency - t.left - 2, ahead + 1)
    recursion = costs + 2
    right = recursion + t.left
    return FifthTiming(costs, recursion, t.latency, right, right + 1)
