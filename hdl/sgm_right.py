"""The fifth SGM path's recursion in hardware: the left path's lane update over a row fed
right to left.

docs/semantics.md ("The fifth path") defines the fifth path as the left path of the
mirrored row, so its hardware is :func:`.sgm_left.left_path` unchanged, fed the row's
positions in mirrored order: the caller gives, slot after slot, the costs of column
x = W - 1 - x' on the tag's column x', and P2 from |I(x) - I(x + 1)|. The left path keys
everything it keeps (its files, its fresh start) on the tag's column and writes only in
slots that carry a position, so the order of the columns is the only thing that changes.

Inside the SGM stage (:func:`fifth_path`, docs/hardware.md "The fifth path"): while row
y + 1 streams in, slot x of it reads column W - 1 - x of row y from row buffers whose
address direction alternates every row (a word is read, then rewritten with row y + 1's
word a clock later), runs the recursion on it and adds L_right to row y's S4. The sums S5
of row y leave in mirrored order, slot x carrying column W - 1 - x: ``centre`` names them
(x' = x, the row before), and the back end works on the mirrored row (the L/R check's
mirrored mode, :mod:`.mirror`), whose output words alone are turned round.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import P2_ADAPT_OFF, sgm_summed_cost_bits
from .banks import banked_memory
from .common import SlotClock, bits_for, delay_line, pipe, register, split_lanes, \
    tag_layout, taps
from .mirror import turning_rows
from .plan_structure import banked_read_clocks, row_banks
from .plan_timing import sgm_fifth_forwarded, sgm_fifth_timing, sgm_timing
from .sgm_left import PathOwner, left_path

__all__ = ["RightPathRecursion", "fifth_path"]


class RightPathRecursion(PathOwner, wiring.Component):
    """L of the fifth path per lane for a row streamed in mirrored column order.

    Parameters
    ----------
    params : StereoParams
        With ``aggregation="sgm"``, width and height (any R that divides D).

    Attributes
    ----------
    costs : In(ArrayLayout(unsigned(cost_bits), D/R))
        C(W - 1 - x', j*D/R + i) on lane i in round j, for the tag's mirrored column x'.
    p2 : In(unsigned(bitlen(P2)))
        P2 of the fifth path at that column (slot-aligned with ``costs``).
    tag : In(tag_layout)
        The position in mirrored coordinates (x' = W - 1 - x), slot-aligned at the input.
    first, round : In
        Slot timing at the input.
    lanes : Out(ArrayLayout(unsigned(left_cost_bits), D/R))
        L_right(W - 1 - x', j*D/R + i) on lane i, ``latency`` clocks after the input.
    centre : Out(tag_layout)
        The tag of ``lanes``.
    """

    def __init__(self, params):
        self.params = params
        self.timing = sgm_timing(params)
        self.latency = self.timing.left
        super().__init__({
            "costs": In(data.ArrayLayout(unsigned(params.cost_bits), params.per_round)),
            "p2": In(bits_for(params.p2)),
            "tag": In(tag_layout(params)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "lanes": Out(data.ArrayLayout(unsigned(params.left_cost_bits),
                                          params.per_round)),
            "centre": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p, t = self.params, self.timing
        m = Module()
        self._slots = slots = SlotClock(m, self.first, self.round, p.rounds, "sgm_right")
        self._valid = {}
        units = p.per_round
        costs = self.costs.as_value()
        # As deep as the SGM stage's taps need for the left path alone.
        self._costs = [split_lanes(word, units, p.cost_bits) for word in
                       taps(m, costs, max(t.loop + t.left_stages - 1, t.left_picks[-2] + 1),
                            "sgm_right_cost")]
        # Fresh start at the mirrored row's first column, and P2, slot-aligned at
        # ``timing.guide`` as the SGM stage gives them to the left path.
        flag = register(m, self.tag.x == 0, 1, "sgm_right_fresh")
        fresh = taps(m, flag, t.guide - 1, "sgm_right_fresh")[-1]
        p2 = self._aligned(self.p2, 0, t.guide, "sgm_right_p2")
        lanes = left_path(self, m, fresh, p2)
        for i, value in enumerate(lanes):
            m.d.comb += self.lanes[i].eq(value)
        m.d.comb += self.centre.eq(slots.delay(self.tag, 0, self.latency, "sgm_right_centre"))
        return m


def _turnaround(owner, m, name, width, offset, column, data):
    """A row of words (W R of ``width`` bits) whose word at ``column`` (slot-aligned at 1)
    and the round at ``offset`` comes out at ``offset`` + 1, when ``data`` is written in its
    place. ``column`` alternates its direction every row, so the word read is the previous
    row's at the mirrored column.

    The row is cut into :func:`~.plan_structure.row_banks` banks (:func:`.banks.banked_memory`,
    block RAMs full at any depth: one memory W R deep was a cascade 62.5 % full at 1280 x
    720), so the read is issued :func:`~.plan_structure.banked_read_clocks` clocks ahead
    and the words written meanwhile are forwarded (:func:`_forwarded`)."""
    p, slots = owner.params, owner._slots
    banks = row_banks(p)
    ahead = banked_read_clocks(len(banks))
    issued = offset + 1 - ahead
    at = owner._aligned(column, 1, issued, f"{name}_column")
    early = at * p.rounds + slots.round(issued) if p.rounds > 1 else at
    address = Signal(range(p.width * p.rounds), name=f"{name}_read_early")
    m.d.comb += address.eq(early)
    written = pipe(m, address, ahead - 1, f"{name}_write_early")
    word = banked_memory(m, name, unsigned(width), banks, address, written, data,
                         owner._valid_at(offset))
    return _forwarded(m, name, address, ahead, owner._valid_at(offset + 1), data, word,
                      sgm_fifth_forwarded(p))


def _forwarded(m, name, address, ahead, enable, data, read_data, distances):
    """``read_data``, the word read at ``address`` ``ahead`` clocks ago, or the word
    written to that address since: ``data`` with its write ``enable``, k clocks ago for k
    in ``distances`` (:func:`~.plan_timing.sgm_fifth_forwarded`). A row's first positions
    read the column its last ones wrote: the word is forwarded from the previous row (the
    block RAM's ports do not order a read and a write of one address in one clock)."""
    value = read_data
    for k in sorted(distances, reverse=True):
        # Compared a clock ahead, between registers.
        hit = register(m, (pipe(m, address, ahead - 1, f"{name}_reader") ==
                           pipe(m, address, ahead - 1 + k, f"{name}_writer{k}")) &
                       pipe(m, enable, k - 1, f"{name}_writing{k}", reset=True), 1,
                       f"{name}_hit{k}")
        held = delay_line(m, data, k, f"{name}_held{k}")
        value = Mux(hit, held, value)
    return value


def fifth_path(owner, m, four, p2_left):
    """S5 per lane and its tag at ``sgm_fifth_timing(...).latency`` (module docstring).

    ``owner`` is the SGM stage being elaborated; ``four`` the lanes' S4 at its
    ``timing.latency``, ``p2_left`` the left path's P2, slot-aligned at ``timing.guide``:
    the fifth path's P2 at column x is the left path's at x + 1, |I(x + 1) - I(x)|, i.e.
    the previous position's of the mirrored row.
    """
    p, t, slots, tag = owner.params, owner.timing, owner._slots, owner.tag
    f = sgm_fifth_timing(p, owner.every)
    units, width = p.per_round, p.width
    cost_bits, four_bits = p.cost_bits, sgm_summed_cost_bits(p.max_cost, p.p2)
    # Row starts, slot-aligned at 1 (a register: the column's comparison with 0 into the
    # rows' and the direction's multiplexers was census 5x5 SGM's critical path at 640 x 48,
    # R = 4, 8.82 ns, 4 levels): the address direction flips, and the rows' y are kept a row
    # back. In a row's first slot the registers change after its first clock, so the values
    # of the slot are formed from their old contents there (R clocks alike).
    # The flag's slot pulse from a round counter of its own: the stage's shared pulse tap (the
    # core's) into it was the recommended configuration's critical path at 1280 x 720
    # (9.85 ns, 2 levels, 101.5 MHz). Any round of the slot would do (the tests pass at
    # every phase): what the flag moves is read in the slot's last clock.
    starts = register(m, slots.private_first(0, 0, "sgm_fifth_round") & tag.valid &
                      (tag.x == 0), 1, "sgm_fifth_starts")
    direction, before = turning_rows(m, p, "sgm_fifth", starts,
                                     owner._aligned(tag.y, 0, 1, "sgm_fifth_tag_y"))
    # The column, slot-aligned at 1: x and its mirror image registered, chosen by the
    # direction. The comparison, the direction and the choice in one clock behind the tag
    # were census 5x5 SGM's critical path at 1280 x 720, R = 4 (8.96 ns, 4 levels).
    column = Mux(direction,
                 owner._aligned(width - 1 - tag.x, 0, 1, "sgm_fifth_flipped"),
                 owner._aligned(tag.x, 0, 1, "sgm_fifth_column_x"))

    adaptive = p.p2_adapt != P2_ADAPT_OFF
    p2_bits = bits_for(p.p2) if adaptive else 0
    costs_word = Cat(*owner._costs[f.costs + 1],
                     owner._aligned(p2_left, t.guide, f.costs + 1, "sgm_fifth_p2")
                     if adaptive else Const(0, 0))
    stored = register(m, _turnaround(owner, m, "sgm_fifth_costs", units * cost_bits + p2_bits,
                                     f.costs, column, costs_word),
                      units * cost_bits + p2_bits, "sgm_fifth_costs_read")
    m.submodules.sgm_right = right = RightPathRecursion(p)
    at = f.recursion
    m.d.comb += [right.first.eq(slots.first(at)), right.round.eq(slots.round(at)),
                 right.tag.x.eq(owner._aligned(tag.x, 0, at, "sgm_fifth_x")),
                 right.tag.y.eq(owner._aligned(before, 1, at, "sgm_fifth_y")),
                 right.tag.valid.eq(owner._valid_at(at)), right.tag.live.eq(1)]
    m.d.comb += [right.costs[i].eq(c) for i, c in enumerate(split_lanes(stored, units, cost_bits))]
    if adaptive:
        # The previous position's P2, held through the slot (loaded in its last clock).
        previous = Signal(p2_bits, name="sgm_fifth_p2_previous", reset_less=True)
        with m.If(slots.first(at + p.rounds - 1) & owner._valid_at(at)):
            m.d.sync += previous.eq(stored[units * cost_bits:])
        m.d.comb += right.p2.eq(previous)
    else:
        m.d.comb += right.p2.eq(p.p2)

    # S4 of the row before, at the mirrored column, waits for L_right.
    sums = _turnaround(owner, m, "sgm_fifth_four", units * four_bits, f.four - 1, column,
                       Cat(*(v[:four_bits] for v in four)))
    sums = split_lanes(taps(m, sums, f.right - f.four, "sgm_fifth_four_aligned")[-1], units,
                       four_bits)
    total = [register(m, s + right.lanes[i], p.aggregated_cost_bits, f"sgm_fifth_s{i}")
             for i, s in enumerate(sums)]
    # S5 of row y leaves in mirrored order while row y + 1 streams in: the back end works
    # on it so (docs/hardware.md "The fifth path"), and the output words are turned round.
    centre = slots.delay(tag, 0, f.latency, "sgm_fifth_centre")
    y = owner._aligned(before, 1, f.latency, "sgm_fifth_centre_y")
    return total, (centre.x, y, centre.valid, centre.live)
