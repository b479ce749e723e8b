"""Left/right consistency check and the invalid border (output word of each position).

Hardware counterpart of :class:`npstereo.golden.wta.RightWTA`,
:func:`npstereo.golden.lr_check.lr_check` and :func:`~npstereo.golden.lr_check.invalidate_border`.

**Right-referenced WTA.** dR(xr) is the argmin over d of S(xr + d, d): its candidates come
from the positions xr .. xr + D - 1, candidate d from cost unit d // R in round d % R. So the
running winner of right pixel xr lives where its candidates are made: with unit i while
that unit handles it (R positions, rounds j = 0 .. R-1 handle xr = x - i*R - j), in a store
of R words per unit (LUT RAM, read-modify-write once per round), then it moves to unit
i + 1. Each unit has one comparator, not one per disparity. Units run one clock apart
(unit i's costs are delayed i clocks) so that the word a unit finishes in round R-1 is
registered and ready for the next unit's round 0. The winner leaving the last unit is final:
dR of the position D - 1 back, which goes into a history of dR indexed by position.

**Check.** Left winners dL wait in a store indexed by position until all their partners are
final (D positions), then meet dR(x - dL) from the history; the partner lookup is a memory
read, not a D:1 multiplexer. Every slot with a position produces one *retire* pulse at the
output (the credit for the output queue, see :mod:`.core`), and, if its left pixel lies in
the frame, one output word.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import SlotClock, Store, bits_for, pipe, tag_layout

__all__ = ["LRCheck", "keeps"]


def keeps(disparity, partner, threshold):
    """The consistency test: |dL - dR| <= T (both unsigned)."""
    difference = Mux(disparity > partner, disparity - partner, partner - disparity)
    return difference <= threshold


def _winning(candidate, held):
    """A right pixel's candidate replaces its running winner only if strictly smaller:
    candidates come in increasing d, so ties keep the lowest disparity."""
    return candidate < held


class LRCheck(wiring.Component):
    """Valid flag and disparity of one output word per position.

    Parameters
    ----------
    params : StereoParams
    left_offset : int
        Where ``disparity``/``left_tag`` are slot-aligned, in clocks after this stage's
        input (``sums``/``tag``).

    Attributes
    ----------
    sums : In(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(x, i*R + round) of unit i for the position ``tag``.
    tag : In(tag_layout)
        The position of ``sums`` (slot-aligned).
    first, round : In
        Slot timing at the input.
    disparity, left_tag : In
        dL of the position ``left_tag`` (from the evaluation stage), at ``left_offset``.
    retire : Out(1)
        One pulse per slot with a position, at offset ``latency``.
    produce : Out(1)
        With ``retire``: an output word, for an in-frame position.
    valid, disparity_out, x, y : Out
        The word and its position (with ``produce``).
    latency : int
        Clocks from the input to ``retire``.
    """

    def __init__(self, params, left_offset):
        self.params, self.left_offset = params, left_offset
        depth, rounds, units = params.disparities, params.rounds, params.per_round
        if params.lr_check:
            #: Offset of the final dR leaving the last unit (see elaborate()).
            self.exit = units + rounds + 1
            # The left winners' store is written `left_offset` after the input and read
            # at `exit`; in between the left side runs ahead by up to this many positions.
            ahead = -(-(self.exit - left_offset) // rounds) + 1
            self.history_depth = 1 << (depth + max(ahead, 0) + 4 - 1).bit_length()
            self.latency = self.exit + 4
        else:
            self.latency = left_offset + 1
        d_bits = bits_for(depth - 1)
        layout = tag_layout(params)
        super().__init__({
            "sums": In(data.ArrayLayout(unsigned(params.aggregated_cost_bits), units)),
            "tag": In(layout),
            "first": In(1), "round": In(bits_for(rounds - 1)),
            "disparity": In(d_bits),
            "left_tag": In(layout),
            "retire": Out(1), "produce": Out(1),
            "valid": Out(1), "disparity_out": Out(d_bits),
            "x": Out(layout["x"].shape), "y": Out(layout["y"].shape),
        })

    def _in_frame(self, tag):
        return tag.live & (tag.y >= 0) & (tag.y < self.params.height)

    def elaborate(self, platform):
        p = self.params
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "lr")
        if not p.lr_check:
            tag = self.left_tag
            with m.If(slots.first(self.left_offset)):
                m.d.sync += [self.retire.eq(tag.valid),
                             self.produce.eq(tag.valid & self._in_frame(tag))]
            with m.Else():
                m.d.sync += [self.retire.eq(0), self.produce.eq(0)]
            m.d.sync += [self.valid.eq(tag.x >= p.first_valid_column),
                         self.disparity_out.eq(self.disparity),
                         self.x.eq(tag.x), self.y.eq(tag.y)]
            return m
        final, leaving = self._right_winners(m, slots)
        self._check(m, slots, final, leaving)
        return m

    def _right_winners(self, m, slots):
        """The chain of units; returns dR leaving the last unit and its pulse (at
        ``self.exit``)."""
        p = self.params
        rounds, units = p.rounds, p.per_round
        cost_bits, d_bits = p.aggregated_cost_bits, bits_for(p.disparities - 1)
        entry = data.StructLayout({"cost": unsigned(cost_bits), "d": unsigned(d_bits),
                                   "empty": unsigned(1)})
        # Candidates at offset 1: unit i's disparity i*R + j takes part iff xr = x - d is in
        # the row (x - j >= i*R) and the position lies in the frame.
        tag = self.tag
        x_minus_round = Signal(range(-rounds, p.width), name="lr_x_minus_round")
        in_frame = Signal(name="lr_in_frame")
        m.d.sync += [x_minus_round.eq(tag.x - slots.round(0)),
                     in_frame.eq(tag.valid & self._in_frame(tag))]
        # The store address of the right pixel in round j: (n - j) mod R for the n-th
        # position, the same in every unit (unit i's pixels are i*R positions older).
        address = Const(0)
        if rounds > 1:
            count = Signal(range(rounds), name="lr_count")
            address = Signal(range(rounds), name="lr_address")
            with m.If(slots.first(0)):
                m.d.sync += address.eq(count)
                with m.If(tag.valid):
                    m.d.sync += count.eq(Mux(count == rounds - 1, 0, count + 1))
            with m.Else():
                m.d.sync += address.eq(Mux(address == 0, rounds - 1, address - 1))
        valid = slots.delay(tag.valid, 0, 1, "lr_valid")

        forward = None
        for i in range(units):
            # Unit i runs i clocks after unit 0: stage A reads at offset 1 + i, stage B
            # compares and writes back at 2 + i.
            ok = pipe(m, in_frame & (x_minus_round >= i * rounds), i, f"candidate_ok{i}")
            cost = pipe(m, pipe(m, self.sums[i], 1, f"candidate_cost{i}"), i,
                        f"candidate_cost{i}")
            d = pipe(m, Const(i * rounds, d_bits) + slots.round(1), i, f"candidate_d{i}")
            store = Store(m, f"right_winners{i}", entry, rounds)
            unit_address = pipe(m, address, i, f"lr_address{i}")
            stored = store.read(unit_address)
            starting = slots.first(1 + i) if rounds > 1 else Const(1)
            held = Signal(entry, name=f"held{i}", reset_less=True)
            if i == 0:
                m.d.sync += [held.eq(stored), held.empty.eq(starting | stored.empty)]
            else:
                m.d.sync += held.eq(Mux(starting, forward, stored))
            candidate_ok = pipe(m, ok, 1, f"candidate_ok{i}_b")
            candidate_cost = pipe(m, cost, 1, f"candidate_cost{i}_b")
            candidate_d = pipe(m, d, 1, f"candidate_d{i}_b")
            better = candidate_ok & (held.empty | _winning(candidate_cost, held.cost))
            updated = Signal(entry, name=f"updated{i}")
            m.d.comb += updated.eq(Mux(better, Cat(candidate_cost, candidate_d, Const(0, 1)),
                                       held))
            stage_b_valid = slots.delay(valid, 1, 1 + i, f"lr_valid{i}")
            store.write(pipe(m, unit_address, 1, f"lr_write_address{i}"), updated,
                        stage_b_valid)
            handing = stage_b_valid & (slots.first(2 + i + rounds - 1) if rounds > 1
                                       else Const(1))
            forward = Signal(entry, name=f"forward{i + 1}", reset_less=True)
            with m.If(handing):
                m.d.sync += forward.eq(updated)
        leaving = Signal(name="right_final_valid")
        m.d.sync += leaving.eq(handing)
        return forward.d, leaving

    def _check(self, m, slots, final, leaving):
        """History of dR, the left winners' store and the check itself."""
        p = self.params
        depth, size = p.disparities, self.history_depth
        d_bits = bits_for(depth - 1)
        layout = tag_layout(p)
        index_shape = unsigned(bits_for(size - 1))

        # The left winners, stored by position index.
        waiting_layout = data.StructLayout({"tag": layout, "d": unsigned(d_bits)})
        m.submodules.left_winners = waiting = Memory(shape=waiting_layout, depth=size,
                                                     init=[])
        left_read, left_write = waiting.read_port(domain="comb"), waiting.write_port()
        left_count = Signal(index_shape, name="left_count")
        arriving = slots.first(self.left_offset) & self.left_tag.valid
        with m.If(arriving):
            m.d.sync += left_count.eq(left_count + 1)
        m.d.comb += [left_write.addr.eq(left_count), left_write.en.eq(arriving),
                     left_write.data.eq(Cat(self.left_tag, self.disparity))]

        # dR leaving the chain belongs to position n - D + 1 when position n leaves it;
        # then the left winner of position n - D has all its partners.
        m.submodules.right_history = history = Memory(shape=unsigned(d_bits), depth=size,
                                                      init=[])
        history_read, history_write = history.read_port(domain="comb"), history.write_port()
        exit_count = Signal(index_shape, name="exit_count")
        primed = Signal(name="primed")          # D positions have left since reset
        seen = Signal(range(depth + 1), name="exits_seen")
        with m.If(leaving):
            m.d.sync += exit_count.eq(exit_count + 1)
            with m.If(seen != depth):
                m.d.sync += seen.eq(seen + 1)
        m.d.comb += primed.eq(seen == depth)
        m.d.comb += [history_write.addr.eq(exit_count - depth + 1),
                     history_write.en.eq(leaving), history_write.data.eq(final),
                     left_read.addr.eq(exit_count - depth)]
        entry = Signal(waiting_layout, name="checked_left", reset_less=True)
        checked_index = Signal(index_shape, name="checked_index", reset_less=True)
        m.d.sync += [entry.eq(left_read.data), checked_index.eq(exit_count - depth)]
        stage = pipe(m, Cat(leaving, primed), 1, "check_pulse", reset=True)
        partner_address = Signal(index_shape, name="partner_address", reset_less=True)
        m.d.sync += partner_address.eq(checked_index - entry.d)
        entry2 = pipe(m, entry, 1, "checked_left2")
        m.d.comb += history_read.addr.eq(partner_address)
        partner = pipe(m, history_read.data, 1, "partner")
        entry3 = pipe(m, entry2, 1, "checked_left3")
        stage = pipe(m, stage, 2, "check_pulse2", reset=True)
        kept = entry3.tag.x >= entry3.d
        if p.lr_threshold is not None:
            kept = kept & keeps(entry3.d, partner, p.lr_threshold)
        m.d.sync += [
            self.retire.eq(stage[0]),
            self.produce.eq(stage[0] & stage[1] & self._in_frame(entry3.tag)),
            self.valid.eq(kept & (entry3.tag.x >= p.first_valid_column)),
            self.disparity_out.eq(entry3.d),
            self.x.eq(entry3.tag.x), self.y.eq(entry3.tag.y),
        ]
