"""Calculation stage: transforms, matching costs, aggregation and WTA per partition.

Hardware counterpart of :mod:`npstereo.golden.transform`, :mod:`~npstereo.golden.matching_cost`,
:mod:`~npstereo.golden.aggregation` and :func:`npstereo.golden.wta.wta_partition`, in that
order. A position takes a slot of R clocks (rounds); D/R cost units work in every round.

**Round j evaluates disparities j*D/R .. (j+1)*D/R - 1; cost unit i takes j*D/R + i** (the
paper's partitions). Unit i therefore needs, in round j, the right-image transform of
column x - j*D/R - i, and at the next position the same columns shifted by one: the word
unit i reads in round j is the word unit i + 1 needs in round j of the next position. Each
unit keeps its R words in a store of R words of LUT RAM (one read and one write per clock,
the write to the word just read), and hands every word it reads to the next unit; the last
unit's words go round to unit 0 one round later, and the newest column enters unit 0 in
round R-1. Only one word per unit moves per clock, between neighbours (and round the ring):
this replaces a ring of D registers rotating through wide multiplexers, whose wiring kept
census 9x9 from routing and whose flip-flops made the extended census too big.

For the vertical aggregation the stage either computes the costs of the A rows of the window
(``params.stored_rows == "transforms"``: the transforms of the A-1 rows above come from a
block RAM of transformed pixels, one word per column, and travel through the stores with
the current row's) or hands single-row costs to :class:`~.aggregation.Aggregation`, which
keeps the costs of the rows above (``"costs"``).

The datapath never stalls (no clock enable): each value carries the tag of its slot, and
only the stores are written, only in slots that carry a position.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .aggregation import Aggregation
from .banks import line_memory
from .common import SlotClock, Store, bits_for, pipe, replica, round_base, \
    row_inside_ahead, tag_layout
from .cost_term import COLUMN_BITS, COST_TERM_CLOCKS, Ad3Term, right_column
from .matching_cost import MatchingCost
from .pair_flags import pair_flags
from .plan_structure import (centre_copies, cost_rows, masks_after_compare, row_sum_plan,
                             store_slices, transformed_rows, vertical_bits, window_first_row,
                             window_pixels)
from .plan_timing import calculation_timing, neighbour_clocks, unit_skews
from .sgm import SemiGlobalAggregation, guide_pixels
from .subpixel import partition_leaves
from .transform import Transform
from .trees import DEFAULT_EVERY, build_min_tree, build_sum

__all__ = ["CalculationStage"]


def _missing_cost(params):
    """The cost of a pair that does not exist (x - d < 0): 0 in a box sum, Cmax for SGM
    (docs/sgm.md), so that no path is drawn towards disparities without a partner."""
    return params.max_cost if params.is_sgm else 0


class CalculationStage(wiring.Component):
    """Aggregated costs and the partition winner of one (position, round) per clock.

    Parameters
    ----------
    params : StereoParams
    every : int
        Register spacing of the transform, cost and adder/minimum trees (see :mod:`.trees`).
    slot_base : int
        Clocks from the core's slot clock to ``first`` (see :class:`~.common.SlotClock`).

    Attributes
    ----------
    window_left, window_right : In(ArrayLayout(unsigned(8), B * B))
        From the input stage, slot-aligned at this stage's input (its layout:
        :class:`~.input_stage.InputStage`).
    keep : In(A * B * B)
        With :func:`~.plan_structure.masks_after_compare`: the windows' flags of pixels inside the
        frame.
    centres_left, centres_right : In(ArrayLayout(unsigned(8), copies))
        Copies of the windows' centre (:func:`~.plan_structure.centre_copies`), each its
        own register.
    tag : In(tag_layout)
        Centre of those windows.
    first, round : In
        Slot timing at the input.
    sums : Out(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(centre, i*R + round) of unit i, at offset ``sums_latency``.
    centre : Out(tag_layout)
        The aggregation centre of ``sums``, slot-aligned at ``sums_latency``.
    best_cost, best_disparity : Out
        The partition winner of the round, at offset ``latency``.
    best_before, best_after : Out
        With F > 0 (:mod:`.subpixel`): S(d-1) and S(d+1) of the partition winner d, with it.
    sums_latency, latency : int
        Clocks from the input to ``sums`` and to the partition winner.
    """

    def __init__(self, params, every=DEFAULT_EVERY, slot_base=0):
        self.params, self.every, self.slot_base = params, every, slot_base
        copies, after = centre_copies(params), masks_after_compare(params)
        self.transform_left = Transform(params, every, copies, after)
        self.transform_right = Transform(params, every, copies, after)
        #: With ``stored_rows == "pixels"``: the transforms of the windows 1 .. A-1 rows
        #: above, (left, right) per row.
        self.transforms_above = [(Transform(params, every, copies, after),
                                  Transform(params, every, copies, after))
                                 for _ in range(transformed_rows(params) - 1)]
        #: Rows whose costs the cost units compute: A with stored transforms, else 1.
        self.rows = cost_rows(params)
        self.cost_units = [[MatchingCost(params, every) for _ in range(self.rows)]
                           for _ in range(params.per_round)]
        timing = calculation_timing(params, every)
        self.aggregation = (SemiGlobalAggregation(params, every, slot_base + timing.vertical)
                            if params.is_sgm else
                            Aggregation(params, every, slot_base + timing.vertical))
        timing = calculation_timing(params, every)
        # Offsets (clocks after the input) of the datapath's steps; see elaborate().
        self.transformed, self.stored = timing.transformed, timing.stored
        self.costed, self.vertical = timing.costed, timing.vertical
        #: Clocks by which unit i runs behind unit 0 (:func:`~.plan_timing.unit_skews`).
        self.skews = unit_skews(params)
        self.sums_latency, self.min_latency = timing.sums, timing.min_tree
        self.latency = timing.latency
        units = params.per_round
        window = data.ArrayLayout(unsigned(8), window_pixels(params))
        centres = data.ArrayLayout(unsigned(8), copies * transformed_rows(params))
        keep = ({"keep": In(transformed_rows(params) * params.block * params.block)}
                if after else {})
        if params.subpixel_bits:
            keep.update(best_before=Out(params.aggregated_cost_bits),
                        best_after=Out(params.aggregated_cost_bits))
        super().__init__({**keep,
            "window_left": In(window), "window_right": In(window),
            "centres_left": In(centres), "centres_right": In(centres),
            "tag": In(tag_layout(params)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "sums": Out(data.ArrayLayout(unsigned(params.aggregated_cost_bits), units)),
            "centre": Out(tag_layout(params)),
            "best_cost": Out(params.aggregated_cost_bits),
            "best_disparity": Out(bits_for(params.disparities - 1)),
        })

    def elaborate(self, platform):
        p = self.params
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "calculation", self.slot_base)

        m.submodules.transform_left = tl = self.transform_left
        m.submodules.transform_right = tr = self.transform_right
        if not self.transforms_above:
            m.d.comb += [tl.window.eq(self.window_left), tr.window.eq(self.window_right)]
        m.d.comb += [tl.en.eq(1), tr.en.eq(1)]
        if tl.impl.copies > 1 and not self.transforms_above:
            m.d.comb += [tl.centres.eq(self.centres_left), tr.centres.eq(self.centres_right)]
        if self.transforms_above:
            self._windows_above(m, tl, tr)
        left, right = self._transformed_rows(m, slots, tl.value, tr.value)
        if p.cost_term:
            # The cost term's pixel columns travel with the transforms (.cost_term).
            left.append(pipe(m, right_column(self.window_left, p.block), self.transformed,
                             "term_left_column"))
            right.append(pipe(m, right_column(self.window_right, p.block), self.transformed,
                              "term_right_column"))
        tag = slots.delay(self.tag, 0, self.transformed, "transformed_tag")
        before = slots.delay(self.tag, 0, self.transformed - 1, "transformed_tag_ahead")
        right_words = self._right_stores(m, slots, Cat(*right), tag, before)
        left_words = self._left_chain(m, slots, Cat(*left))
        early = slots.delay(tag, self.transformed, self.stored - self.transformed,
                            "stored_tag")
        tag = slots.delay(early, self.stored, 1, "cost_tag")
        costs = self._costs(m, slots, left_words, right_words, tag, early)

        m.submodules.aggregation = aggregation = self.aggregation
        newest = slots.delay(tag, self.stored + 1, self.vertical - self.stored - 1,
                             "aggregation_tag")
        m.d.comb += [aggregation.tag.eq(newest), aggregation.first.eq(slots.first(self.vertical)),
                     aggregation.round.eq(slots.round(self.vertical))]
        if not p.is_sgm and aggregation.masks_ahead:
            m.d.comb += aggregation.tag_ahead.eq(slots.delay(
                early, self.stored, self.vertical - self.stored - 1, "aggregation_tag_ahead"))
        m.d.comb += [aggregation.costs[i].eq(c) for i, c in enumerate(costs)]
        if p.is_sgm:
            m.d.comb += aggregation.guide.eq(slots.delay(
                guide_pixels(self.window_left, p.block), 0, self.vertical, "sgm_guide"))
        m.d.comb += [self.sums.eq(aggregation.sums), self.centre.eq(aggregation.centre)]

        # WTA of the partition: unit i's leaf carries i, to which the round's first disparity
        # j*D/R is added at the root (ties keep the lowest unit, i.e. the lowest disparity).
        # With F > 0 the leaves carry the neighbours S(d-1), S(d+1) (.subpixel).
        index_shape = unsigned(bits_for(p.per_round - 1))
        if p.subpixel_bits:
            leaves = partition_leaves(m, aggregation.sums, index_shape, p)
        else:
            leaves = [(aggregation.sums[i], Const(i, index_shape))
                      for i in range(p.per_round)]
        best = build_min_tree(m, 1, leaves, name="partition")
        first_disparity = round_base(
            m, slots, self.sums_latency + neighbour_clocks(p) + self.min_latency, p.per_round)
        m.d.sync += [self.best_cost.eq(best[0]),
                     self.best_disparity.eq(first_disparity + best[1])]
        if p.subpixel_bits:
            m.d.sync += [self.best_before.eq(best[2]), self.best_after.eq(best[3])]
        return m

    def _windows_above(self, m, tl, tr):
        """``stored_rows == "pixels"``: the input stage gives the A windows of the column
        (each masked in its own centre's frame), the newest first; each transform unit
        takes its window and its window's centre copies."""
        p = self.params
        block, copies = p.block, tl.impl.copies
        pixels = block * block
        units = [(tl, tr), *self.transforms_above]
        for k, (left, right) in enumerate(units):
            if k:
                m.submodules[f"transform_left_above{k}"] = left
                m.submodules[f"transform_right_above{k}"] = right
                m.d.comb += [left.en.eq(1), right.en.eq(1)]
            # Window k's pixels: its own masked window, or its rows of the shared one.
            first = window_first_row(p, k) * block if tl.impl.mask_after else k * pixels
            for unit, window, centres in ((left, self.window_left, self.centres_left),
                                          (right, self.window_right, self.centres_right)):
                m.d.comb += [unit.window[i].eq(window[first + i]) for i in range(pixels)]
                if tl.impl.mask_after:
                    m.d.comb += unit.keep.eq(self.keep[k * pixels:(k + 1) * pixels])
                if copies > 1:
                    m.d.comb += [unit.centres[j].eq(centres[k * copies + j])
                                 for j in range(copies)]

    def _transformed_rows(self, m, slots, left, right):
        """The transforms of the rows of the aggregation window, slot-aligned at
        ``self.transformed``: the current row (from the transform units), then the rows
        above (from a block RAM of transformed pixels, or from transform units of their
        own when they are transformed again from pixels)."""
        p = self.params
        delay = self.transformed - self.transform_left.latency
        left, right = (pipe(m, left, delay, "left_current"),
                       pipe(m, right, delay, "right_current"))
        if self.transforms_above:
            lefts, rights = [left], [right]
            for k, (above_left, above_right) in enumerate(self.transforms_above):
                lefts.append(pipe(m, above_left.value, delay, f"left_above{k + 1}"))
                rights.append(pipe(m, above_right.value, delay, f"right_above{k + 1}"))
            return lefts, rights
        if self.rows == 1:
            return [left], [right]
        above, bits = self.rows - 1, p.transform_bits
        lines = line_memory(m, "transform_lines", 2 * above * bits, p.width)
        # Read the position's column in round 0 of slots with a position (the word then
        # stays on the read port); two clocks later the word has left the block RAM and the plain
        # register behind it (the RAM's own output register on ECP5), and at least one
        # fabric register follows (the block RAM's output straight into a store's write was
        # 7.2 ns, census 9x9 on ECP5). The write-back of a
        # column comes `transformed` clocks after its read, and the column is read again a
        # row later: no collision logic (no_rw_check).
        m.d.comb += [lines.read_addr.eq(self.tag.x),
                     lines.read_en.eq(slots.first(0) & self.tag.valid)]
        word = pipe(m, lines.read_data, 1, "transform_lines_read")
        word = pipe(m, word, self.transformed - 2, "transform_lines_word")
        left_above = [word[k * bits:(k + 1) * bits] for k in range(above)]
        right_above = [word[(above + k) * bits:(above + k + 1) * bits] for k in range(above)]
        tag = slots.delay(self.tag, 0, self.transformed, "transform_lines_tag")
        m.d.comb += [lines.write_addr.eq(tag.x),
                     lines.write_en.eq(slots.first(self.transformed) & tag.valid),
                     lines.write_data.eq(Cat(left, *left_above[:above - 1],
                                             right, *right_above[:above - 1]))]
        return [left, *left_above], [right, *right_above]

    def _right_stores(self, m, slots, newest, tag, before):
        """Each unit's R right-image words; returns the units' operand registers.

        Unit i reads its word of round j (column x - j*D/R - i) at ``stored + s_i + j`` and
        registers it as its operand; from that register the word is written into unit
        i + 1, at the place unit i + 1 reads in round j, for the next position. With
        s_(i+1) = s_i + 1 the write falls in the clock of that read (the LUT RAM's read is
        asynchronous and sees the old word, the write lands at the clock edge); with equal
        skews a clock later, at an address counter of its own a clock behind. Unit 0 takes
        the last unit's word of round j as its word j + 1 (written S + 1 clocks after its
        own read of that word and before the next position's), and the newest column as its
        word 0, in the one clock of each slot that those R - 1 writes leave free: the
        newest word's first clock, ``stored - (R - S)`` (see
        :func:`~.plan_timing.calculation_timing`).
        So every write comes from a register, and every wire runs between neighbours but
        the one that closes the ring.

        A store is cut into slices (:func:`~.plan_structure.store_slices`), each with its
        own address counters, write enable and (unit 0) select, so that no register drives
        more than a slice's RAM cells; a slice's enable includes its counter's ``!= R``, which never
        fails but keeps synthesis from merging the slices' enables.

        ``tag`` is slot-aligned at ``self.transformed``, ``before`` a clock earlier; with
        R = 1 the stores are registers, nothing goes round and unit 0 takes the newest
        word directly.
        """
        p = self.params
        rounds, units, skews = p.rounds, p.per_round, self.skews
        start = self.transformed
        valid = _Aligned(m, slots, tag.valid, start, "store_valid")
        valid.values[start - 1] = before.valid      # for the replicas of R = 1's enables
        bounds, low = [], 0
        for width in store_slices(len(newest)):
            bounds.append((low, low + width))
            low += width
        counters = {}

        def address(i, offset, g):
            """Slice g of unit i: its place for round j, ``offset + j`` clocks after the
            slot's start. Unit i keeps its word j at (j + i) mod R, which is as good as j
            for a store read and written at the same round."""
            if (i, offset, g) not in counters:
                counters[i, offset, g] = slots.phased_round(offset, i,
                                                            f"store{i}_{g}_address{offset}")
            return counters[i, offset, g]

        operands, reads = [], []
        for i in range(units):
            at = self.stored + skews[i]
            if i == 0 and rounds == 1:         # unit 0 reads the newest word itself
                word = newest
                stores = None
            else:
                stores = [Store(m, f"right_store{i}_{g}", unsigned(high - low), rounds)
                          for g, (low, high) in enumerate(bounds)]
                word = Cat(store.read(address(i, at, g)) for g, store in enumerate(stores))
            reads.append((word, stores))
            operands.append(pipe(m, word, 1, f"right_operand{i}"))
        for i in range(1, units):
            stores = reads[i][1]
            follows = skews[i] == skews[i - 1] + 1
            for g, (low, high) in enumerate(bounds):
                if rounds == 1:
                    # Registers: with equal skews unit i - 1's word of this position is its
                    # register itself, a clock later only in its operand register. Each
                    # slice's enable is a replica: one valid bit for all the units of a
                    # skew was census 5x5's critical path at 1280 x 720, D = 64 (11.8 ns
                    # of routing, ECP5).
                    source = operands[i - 1] if follows else reads[i - 1][0]
                    enable = replica(m, valid.at(self.stored + skews[i] - 1),
                                     f"store{i}_{g}_write")
                    stores[g].write(0, source[low:high], enable)
                    continue
                at = self.stored + skews[i - 1] + 1
                place = address(i, at, g)
                enable = Signal(name=f"store{i}_{g}_write")
                m.d.sync += enable.eq(valid.at(at - 1) & (place != rounds))
                stores[g].write(place, operands[i - 1][low:high], enable)
        if rounds > 1:
            # Unit 0: the newest word in the slot's first clock at the transforms, the last
            # unit's words of rounds 0 .. R-2 in the R - 1 clocks after it, one slot later.
            previous = slots.delay(valid.at(start), start, rounds, "store0_previous_valid")
            for g, (low, high) in enumerate(bounds):
                place = address(0, start, g)
                # place == R - 1 a clock before the slot's first clock at the transforms
                # (where it is 0): registered, the select and enable of that clock.
                coming = place == rounds - 1
                newest_now = Signal(name=f"store0_{g}_newest")
                enable = Signal(name=f"store0_{g}_write")
                m.d.sync += [newest_now.eq(coming),
                             enable.eq(Mux(coming, before.valid, previous))]
                reads[0][1][g].write(place, Mux(newest_now, newest[low:high],
                                                operands[-1][low:high]), enable)
        return operands

    def _left_chain(self, m, slots, newest):
        """The left word of each unit, slot-aligned at its operand: a register per step of
        the skew, handed from unit to unit; units with the same skew share one."""
        delay = self.stored + 1 - self.transformed
        if delay <= 2:
            word = pipe(m, newest, delay, "left_word")
        else:
            word = slots.delay(newest, self.transformed, delay, "left_word", reset_less=True)
        words = [word]
        for i in range(1, self.params.per_round):
            if self.skews[i] != self.skews[i - 1]:
                word = pipe(m, word, 1, f"left_word{i}")
            words.append(word)
        return words

    def _costs(self, m, slots, left_words, right_words, tag, early):
        """Masked costs (or vertical sums of A rows) per unit, at offset ``self.vertical``
        (unit i s_i clocks later, except for SGM).

        ``tag`` is slot-aligned at ``self.stored + 1``, where unit 0's operands are,
        ``early`` a clock before; unit i works s_i clocks later, and its masks are delayed
        with it. The box aggregation takes the units' costs skewed; for SGM unit i's
        result waits S - s_i clocks, so that all units' results leave together. A cost is
        0 (Cmax for SGM) where x - d < 0, where its row lies outside the frame, and in
        slots without a position; elsewhere the cost term, if any, is added (:meth:`_term`).
        """
        p = self.params
        start = self.stored + 1
        bits = p.transform_bits
        outside = _missing_cost(p)
        units, skews = p.per_round, self.skews
        last = skews[-1]
        at_least = pair_flags(m, slots, early.x, start - 1, p, p.cost_term)
        rows_ok = []
        for k in range(self.rows):
            ok = Signal(name=f"cost_row_ok{k}")
            if self.aggregation.from_costs:
                # The row's cost is stored for the rows below it, which may already belong
                # to the next frame (frames overlap): it is stored unmasked by the frame,
                # and the aggregation masks the rows of each sum.
                m.d.sync += ok.eq(tag.valid & tag.live)
            else:
                # The row's comparisons a clock ahead, from ``early``.
                inside = row_inside_ahead(m, early.y, k, p.height, "cost_row", str(k))
                m.d.sync += ok.eq(tag.valid & tag.live & inside)
            ok = pipe(m, ok, self.costed - start - 1, f"cost_row_ok{k}")
            # One tap per skew: the chain of unit 0's flags, a register per step.
            taps = [ok]
            for step in range(last):
                taps.append(pipe(m, taps[-1], 1, f"cost_row_ok{k}_skew{step + 1}"))
            rows_ok.append(taps)
        masked = []
        for i, units_of_row in enumerate(self.cost_units):
            skew = skews[i]
            in_row = pipe(m, at_least(i, 0), self.costed - start - 2 + skew, f"in_row{i}")
            term = self._term(m, slots, i, left_words[i], right_words[i], tag, at_least)
            row_costs = []
            for k, unit in enumerate(units_of_row):
                m.submodules[f"cost{i}_row{k}"] = unit
                m.d.comb += [unit.left.eq(left_words[i][k * bits:(k + 1) * bits]),
                             unit.right.eq(right_words[i][k * bits:(k + 1) * bits]),
                             unit.en.eq(1)]
                cost = pipe(m, unit.cost, self.costed - start - unit.latency, f"cost{i}_{k}")
                if term is not None:
                    cost = (cost + term)[:p.cost_bits]
                row_costs.append(Mux(in_row & rows_ok[k][skew], cost, outside))
            if self.rows > 1:
                # The masks are a level of logic in front of the adders (rank 7x7 on ECP5:
                # a mask and two carry chains were 7.9 ns).
                total = build_sum(m, 1, row_costs, row_sum_plan(p, self.every))
                total = total[:vertical_bits(p)]
            else:
                total = pipe(m, row_costs[0], 1, f"masked_cost{i}")
            if p.is_sgm:
                # SGM's lanes meet their neighbours: its input is re-aligned here. The box
                # sum runs skewed and re-aligns its own sums.
                total = pipe(m, total, last - skew, f"aligned_cost{i}")
            masked.append(total)
        return masked

    def _term(self, m, slots, i, left_word, right_word, tag, at_least):
        """Unit i's cost term (:class:`~.cost_term.Ad3Term`) at ``self.costed + s_i``, or
        None without one. ``tag`` is slot-aligned at unit 0's operands, ``at_least`` makes
        the flags x - d >= n a clock after them (as the pairs' mask)."""
        p = self.params
        if not p.cost_term:
            return None
        start, skew, bits = self.stored + 1, self.skews[i], p.transform_bits
        at = start + skew
        # The flags and the history's write enable at ``at + 3``: the flags are made at
        # start + 2, the enable is a replica of its own a clock after the slot's valid bit,
        # as the stores' enables are (one valid bit for all units was census 5x5's
        # critical path at 720p there).
        older = pipe(m, at_least(i, 1), 1 + skew, f"term{i}_older")
        oldest = pipe(m, at_least(i, 2), 1 + skew, f"term{i}_oldest")
        write = replica(m, slots.delay(tag.valid, start, skew + 2, f"term{i}_valid"),
                        f"term{i}_write")
        term = Ad3Term(m, slots, p, i, left_word[bits:bits + COLUMN_BITS],
                       right_word[bits:bits + COLUMN_BITS], at, older, oldest, write)
        return pipe(m, term.value, self.costed - start - COST_TERM_CLOCKS, f"term{i}")


class _Aligned:
    """A slot-aligned value at any later offset, from one chain of latches
    (:meth:`~.common.SlotClock.delay`) shared by all offsets asked for."""

    def __init__(self, m, slots, value, start, name):
        self.slots, self.name = slots, name
        self.values = {start: value}

    def at(self, offset):
        """The value slot-aligned ``offset`` clocks after the slot's start."""
        if offset not in self.values:
            base = max(o for o in self.values if o < offset)
            self.values[offset] = self.slots.delay(self.values[base], base, offset - base,
                                                   self.name)
        return self.values[offset]
