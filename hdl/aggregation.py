"""Aggregation in hardware: the A x A box sum of the matching costs (the paper's 3 x 3).

Hardware counterpart of :func:`npstereo.golden.aggregation.aggregate`. Each of the D/R cost
units delivers, in round j of a slot, the cost of its disparity i*R + j at the newest
position. The sum over the A rows is done before this stage when the rows above are kept as
transformed pixels (``params.stored_rows == "transforms"``: the cost units compute A costs);
when they are kept as costs, a block RAM per unit holds the A-1 rows above (vertical sum
here). The sum over the A columns takes, for each round, the vertical sums of the 2a
previous positions from a store of R words per unit (LUT RAM, one word per round), so the
stage never stalls and bubbles simply do not write. Rows and columns outside the frame are
masked from the tag, never from memory contents.

The result is the aggregated cost S of the *centre* position, a rows and a columns behind
the newest one.

The units run skewed (:func:`~.plan_timing.unit_skews`): unit i's costs arrive s_i clocks after
unit 0's, and each unit's control (addresses, masks, write enables) is unit 0's handed on
by a register per step of the skew, so no control signal fans out to every unit. At the
end unit i's sums wait S - s_i clocks, and all units' sums leave together.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .banks import choose_bank
from .common import SlotClock, Store, bits_for, pipe, register, replica, row_bounds, tag_layout
from .plan_structure import (bank_choice_levels, cost_banks, horizontal_plan,
                             vertical_bits, vertical_plan)
from .plan_timing import aggregation_latency, unit_skews, vertical_clocks
from .trees import DEFAULT_EVERY, build_sum

__all__ = ["Aggregation"]


def _below(value, bound):
    """``value < bound`` for a small constant ``bound``: equalities, no carry chain (the
    comparisons of the tap flags were 6.5 ns through a carry chain, rank 7x7 on ECP5)."""
    return Cat(*(value == v for v in range(bound))).any()


def _tap_inside(newest_x, k, a):
    """Tap k (column ``newest_x - k``) lies in the row of the centre, a columns behind
    the newest: in the same row it is column newest_x - k >= 0; when the centre is still
    in the row above (newest_x < a) it is that row's column W + newest_x - k < W. Formed
    from the newest column directly, not from the centre's (a subtraction and a
    multiplexer more in front of the comparisons)."""
    if k == 0:    # newest_x >= 0 always holds (a constant comparison fails Verilator's lint)
        return ~_below(newest_x, a)
    return Mux(_below(newest_x, a), _below(newest_x, k), ~_below(newest_x, k))


class Aggregation(wiring.Component):
    """Box sums of the round's D/R disparities, for the centre of the aggregation window.

    Parameters
    ----------
    params : StereoParams
    every : int
        Register spacing of the adder trees (see :mod:`.trees`).
    slot_base : int
        Clocks from the core's slot clock to ``first`` (see :class:`~.common.SlotClock`).

    Attributes
    ----------
    costs : In(ArrayLayout(unsigned(bits), D/R))
        Per unit, s_i clocks after ``tag`` (:func:`~.plan_timing.unit_skews`), the newest
        position's cost (``stored_rows == "costs"``: one row, masked where x - d < 0 or
        outside the frame) or vertical sum (``"transforms"``).
    tag : In(tag_layout)
        The newest position, slot-aligned at this stage's input.
    tag_ahead : In(tag_layout)
        With R = 1 and a box wider than one column: ``tag`` a clock earlier.
    first, round : In
        Slot timing at the input.
    sums : Out(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(centre, d) for unit i's disparity d = i*R + round.
    centre : Out(tag_layout)
        The aggregation window's centre, slot-aligned at the output.
    latency : int
        Clocks from input (``tag``, unit 0's costs) to output.
    """

    def __init__(self, params, every=DEFAULT_EVERY, slot_base=0):
        self.params, self.every, self.slot_base = params, every, slot_base
        a = params.agg_radius
        self.from_costs = a > 0 and params.stored_rows == "costs"
        in_bits = params.cost_bits if a == 0 or self.from_costs else vertical_bits(params)
        self.vertical_latency = vertical_clocks(params, every)
        self.skews = unit_skews(params)
        arithmetic = aggregation_latency(params, every)
        self.horizontal_latency = arithmetic - self.vertical_latency
        self.latency = arithmetic + self.skews[-1]
        units = params.per_round
        #: The row taps' masks are formed from the tag a clock ahead (see _horizontal).
        self.masks_ahead = a > 0 and params.rounds == 1
        ahead = {"tag_ahead": In(tag_layout(params))} if self.masks_ahead else {}
        super().__init__({**ahead,
            "costs": In(data.ArrayLayout(unsigned(in_bits), units)),
            "tag": In(tag_layout(params)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "sums": Out(data.ArrayLayout(unsigned(params.aggregated_cost_bits), units)),
            "centre": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p = self.params
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "aggregation", self.slot_base)
        values = [self.costs[i] for i in range(p.per_round)]
        tag = self.tag
        ahead = self.tag_ahead if self.masks_ahead else None
        if self.from_costs:
            values = self._vertical(m, slots, values)
            tag = slots.delay(tag, 0, self.vertical_latency, "vertical_tag")
            if ahead is not None:
                ahead = slots.delay(ahead, 0, self.vertical_latency, "vertical_tag_ahead")
        if p.agg_radius:
            values, tag = self._horizontal(m, slots, values, tag, self.vertical_latency,
                                           ahead)
        last = self.skews[-1]
        values = [pipe(m, v, last - skew, f"aligned_sum{i}")
                  for i, (v, skew) in enumerate(zip(values, self.skews))]
        tag = slots.delay(tag, self.latency - last, last, "aligned_centre")
        m.d.comb += [self.sums[i].eq(v) for i, v in enumerate(values)]
        m.d.comb += self.centre.eq(tag)
        return m

    def _vertical(self, m, slots, costs):
        """Column sums over rows y - 2a .. y from a block RAM of the A-1 rows above.

        Word (x, j) of unit i's memory (address x*R + j, in banks of plan_structure.cost_banks)
        holds the costs of disparity i*R + j at column x for the A-1 rows above; every
        round reads it and writes it back shifted by one row. A column's word is
        read again only a row later, long after the write-back (three clocks after the
        read), and never in the clock it is written: no collision logic (no_rw_check).
        """
        p = self.params
        rows, bits, rounds = p.aggregation - 1, p.cost_bits, p.rounds
        tag = self.tag
        # x * R without a multiplier: consecutive positions are raster-continuous (x + 1,
        # or 0 at a line start), so the row base advances by R per position.
        base = Signal(range(p.width * rounds), name="cost_lines_base")
        with m.If(slots.first(0) & tag.valid):
            m.d.sync += base.eq(Mux(tag.x == 0, 0, base + rounds))
        address = Signal(range(p.width * rounds), name="cost_lines_address")
        m.d.sync += address.eq(base + slots.round(1))
        # Every row of the sum is masked here, the newest too: the costs are stored as
        # computed, for the rows below may belong to the next frame (see the calculation
        # stage).
        inside = [Signal(name=f"row_ok{k}") for k in range(rows + 1)]
        m.d.sync += [ok.eq(low & high) for ok, (low, high) in
                     zip(inside, (row_bounds(tag.y, k, p.height) for k in range(rows + 1)))]
        # Each level of the bank's choice beyond the first is a clock more to the word.
        later = bank_choice_levels(p) - 1
        # A clock short: each unit's own copy is the last register (_Chain.own).
        inside = [slots.delay(ok, 1, 3 + later, f"row_ok{k}", reset_less=True)
                  for k, ok in enumerate(inside)]
        masks = _Chain(m, self.skews, "row_masks")
        reading = slots.delay(tag.valid, 0, 2, "cost_lines_reading")
        written = slots.delay(reading, 2, 3 + later, "cost_lines_written")
        control = _Chain(m, self.skews, "cost_lines")
        banks = cost_banks(p)
        # The address bits within a bank (all of them with one bank).
        low = (banks[0] - 1).bit_length() if len(banks) > 1 else len(address)
        sums = []
        for i, cost in enumerate(costs):
            unit_address, unit_reading, unit_written = control.unit(
                i, address, reading, written)
            unit_inside = masks.own(i, *inside)
            # Bank b holds words b*COST_BANK ..: every bank reads at the ``low`` bits, its
            # output register (the block RAM's own) holds the word, and the bank is
            # chosen behind those registers.
            write_address = pipe(m, unit_address, 3 + later, f"cost_lines{i}_write_address")
            newest = pipe(m, cost, 5 + later, f"vertical_in{i}")
            stored_word = Signal(rows * bits, name=f"cost_lines{i}_read")
            stored = [stored_word[k * bits:(k + 1) * bits] for k in range(rows)]
            words = []
            for b, depth in enumerate(banks):
                m.submodules[f"cost_lines{i}_{b}"] = lines = Memory(
                    shape=unsigned(rows * bits), depth=depth, init=[],
                    attrs={"no_rw_check": 1})
                read, write = lines.read_port(domain="sync"), lines.write_port()
                mine = unit_written if len(banks) == 1 else \
                    unit_written & (write_address[low:] == b)
                m.d.comb += [read.addr.eq(unit_address[:low]), read.en.eq(unit_reading),
                             write.addr.eq(write_address[:low]), write.en.eq(mine),
                             write.data.eq(Cat(newest, *stored[:rows - 1]))]
                words.append(pipe(m, read.data, 1, f"cost_lines{i}_{b}_out"))
            if len(banks) == 1:
                m.d.sync += stored_word.eq(words[0])
            else:
                m.d.sync += stored_word.eq(choose_bank(m, words, unit_address[low:],
                                                       f"cost_lines{i}_bank"))
            terms = [Mux(ok, row, 0) for ok, row in zip(unit_inside, [newest, *stored])]
            # The masks are a level of logic in front of the adders.
            total = build_sum(m, 1, terms, vertical_plan(p, self.every))
            sums.append(total[:vertical_bits(p)])
        return sums

    def _horizontal(self, m, slots, values, tag, offset, ahead=None):
        """Row sums over the positions x - 2a .. x, reported for the centre x - a
        (``ahead``: the tag a clock earlier, or None)."""
        p = self.params
        a, width, rounds = p.agg_radius, p.width, p.rounds
        bits = len(values[0])
        # The centre trails the newest position by a columns (a row earlier near a line
        # start); it is the output tag, a rows up as well.
        # In two clocks: the comparison and both candidates, then the choice (all three
        # in one clock were 7.1 ns, census 9x9 on ECP5).
        newest_x = tag.x
        layout = tag_layout(p)
        wraps = Signal(name="aggregation_wraps")
        wrapped, plain = Signal(layout, name="centre_wrapped"), Signal(layout, name="centre_plain")
        m.d.sync += [wraps.eq(_below(newest_x, a)), wrapped.eq(tag), plain.eq(tag),
                     wrapped.x.eq(newest_x + width - a), wrapped.y.eq(tag.y - a - 1),
                     plain.x.eq(newest_x - a), plain.y.eq(tag.y - a)]
        centre = Signal(layout, name="aggregation_centre")
        m.d.sync += centre.eq(Mux(wraps, wrapped, plain))
        # Tap k holds column x_newest - k, i.e. the centre's column + (a - k).
        # Formed a clock ahead of the taps: each unit's own copy is the register in front of
        # its masks (_Chain.own).
        # At R = 1 the units of one skew are many (9 at D = 64), and the first skew's own
        # copies were loaded from the comparisons on the tag: the tag into them was census
        # 5x5 box's critical path at 1920 x 1080 (7.56 ns, 3 levels). So there the
        # comparisons are made a clock ahead, into one register the copies load from.
        keep = [_tap_inside(newest_x if ahead is None else ahead.x, k, a)
                for k in range(2 * a + 1)]
        if ahead is not None:
            keep = [register(m, ok, 1, f"column_ok_ahead{k}") for k, ok in enumerate(keep)]
        control = _Chain(m, self.skews, "row_taps")
        masks = _Chain(m, self.skews, "column_ok")
        sums = []
        for i, value in enumerate(values):
            valid, = control.unit(i, tag.valid)
            unit_keep = masks.own(i, *keep)
            taps = Store(m, f"row_taps{i}", unsigned(2 * a * bits), rounds)
            round_ = slots.phased_round(offset + self.skews[i], i, f"row_taps{i}_address")
            word = taps.read(round_)
            older = [word[k * bits:(k + 1) * bits] for k in range(2 * a)]
            taps.write(round_, Cat(value, *older[:2 * a - 1]), valid)
            registered = pipe(m, Cat(value, *older), 1, f"row_taps{i}")
            terms = [Mux(unit_keep[k], registered[k * bits:(k + 1) * bits], 0)
                     for k in range(2 * a + 1)]
            total = build_sum(m, 1, terms, horizontal_plan(p, self.every))
            sums.append(total[:p.aggregated_cost_bits])
        out_tag = slots.delay(centre, offset + 2, self.horizontal_latency - 2, "centre_tag")
        return sums, out_tag


class _Chain:
    """Unit 0's control signals, handed from unit to unit by a register per step of the
    skew (units with the same skew share them)."""

    def __init__(self, m, skews, name):
        self.m, self.skews, self.name = m, skews, name
        self.handed = {}

    def unit(self, i, *signals):
        """``signals`` (unit 0's) as unit i sees them, s_i clocks later."""
        if i == 0 or self.skews[i] == self.skews[i - 1]:
            values = self.handed.get(i - 1, list(signals)) if i else list(signals)
        else:
            values = [pipe(self.m, v, 1, f"{self.name}_unit{i}_{k}", reset=True)
                      for k, v in enumerate(self.handed[i - 1])]
        self.handed[i] = values
        return values

    def own(self, i, *signals):
        """``signals`` (unit 0's) as unit i sees them, s_i + 1 clocks later, in registers
        of unit i's own: the masks in front of a unit's adders. A register shared by the
        units of one skew reached 9 units' adders, census 5x5 box at 1280 x 720, D = 64
        on ECP5 (a row tap's mask into the first adder, 7.8 ns twice)."""
        return [replica(self.m, v, f"{self.name}_own{i}_{k}", reset_less=True)
                for k, v in enumerate(self.unit(i, *signals))]
