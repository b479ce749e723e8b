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

from amaranth.hdl import Cat, Const, Module, Mux, Shape, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import SlotClock, Store, better, bits_for, control_copies, each_unit, pipe, \
    register, replica, round_base, row_inside_ahead, tag_layout
from .plan_timing import LR_STAGE_A, lr_stage_b, lr_timing

#: Units served by one copy of the candidates' column and frame flag.
LR_UNITS_PER_COPY = 8

__all__ = ["LRCheck"]


def _write_enables(slots, valid, stage_b, units):
    """The right winners' write enable at ``stage_b`` for each unit: ``valid``
    (slot-aligned at 1) in :func:`~.common.control_copies` kept copies, from a register
    shared up to a clock before (one copy when the units are few: the Verilog is then as
    it was)."""
    copies = control_copies(units)
    if copies == 1:
        return [slots.delay(valid, 1, stage_b - 1, "lr_writing")] * units
    early = slots.delay(valid, 1, stage_b - 2, "lr_writing_early")
    registers = [slots.delay(early, stage_b - 1, 1, f"lr_writing{k}", keep=True)
                 for k in range(copies)]
    return each_unit(registers, units)


def _primed(seen, depth):
    """The left winners' store holds a written word for the position checked now: D
    positions have left the chain since reset (before, it holds whatever it held)."""
    return seen == depth


def _consistent(partner, low, high):
    """The consistency test |dL - dR| <= T, as dR in [dL - T, dL + T] (the bounds are
    registers formed while dR is read: two comparisons behind the read, no subtraction)."""
    return (partner >= low) & (partner <= high)


def _low_comparisons(m, x, base, difference, units, copies_of_difference, copies, slots):
    """``at_least(k, i)``: copy k of ``difference`` = x - ``base`` (a register of it,
    ``base`` the round's first disparity) is >= unit i, as a comparison of the low bits
    only.

    The high part's two cases (above the units, or zero) are flags formed a clock ahead
    beside each copy, so the comparison left in the clock is as wide as the unit index:
    the whole column's carry chain and the frame flag in one clock were census 5x5 box's
    critical path at 1920 x 1080, R = 1 (6.68 ns, 13 levels), and the carry chain alone
    into a register census 7x7 SGM's at 640 x 480, D = 64, R = 4 (7.37 ns, 13 levels).
    With R > 1 the flags compare x with the base and with the base + 2^bits (a counter of
    its own), side by side: the subtraction and a comparison after it in one clock were
    census 7x7 SGM's critical path there (8.17 ns, 11 levels).
    """
    low_bits = bits_for(units - 1)
    if slots.rounds == 1:       # the base is 0: x itself against 2^bits
        above_early = difference >= (1 << low_bits)
        within_early = (difference >= 0) & (difference < (1 << low_bits))
    else:
        above_early = x >= round_base(m, slots, 1, units, start=1 << low_bits)
        within_early = (x >= base) & ~above_early
    above = [replica(m, above_early, f"lr_x_above_units{k}", reset_less=True)
             for k in copies]
    within = [replica(m, within_early, f"lr_x_within_units{k}", reset_less=True)
              for k in copies]

    def at_least(k, i):
        if i == 0:    # the low bits are >= 0 always (a constant comparison fails lint)
            return above[k] | within[k]
        if i >= 1 << low_bits:     # and never as large (the mirrored row's last unit)
            return above[k]
        return above[k] | (within[k] & (copies_of_difference[k][:low_bits] >= i))
    return at_least


def _lookahead(m, i, early_cost, previous_cost, previous_held, held, previous_wins,
               writing, beats):
    """Whether unit ``i``'s candidate beats the word it holds (R = 1), from comparisons
    made a clock ahead.

    The word unit ``i`` holds next clock is one of three, known now: the previous unit's
    candidate (if that unit writes and its candidate wins), the previous unit's held word
    (if it writes and its candidate loses), or this unit's own word (no write: a gap).
    Its next candidate, ``early_cost``, is compared with all three now; next clock a
    choice by the previous unit's registered win and write flags is all that is left of
    the comparison. Compared in the same clock, the chain of units was census 5x5 box's
    critical path at 1280 x 720, D = 64, R = 1 (a carry chain and the choice per unit,
    7.15 ns on ECP5).
    """
    against = {"candidate": previous_cost, "passed": previous_held.cost, "kept": held.cost}
    if i == 1:
        # Unit 0's word is never written at R = 1 (its candidate is always fresh): it
        # stays 0, which no cost is less than (and a comparison with it fails lint).
        del against["passed"]
    ahead = {name: register(m, beats(early_cost, value), 1, f"lr_ahead_{name}{i}")
             for name, value in against.items()}
    won = register(m, previous_wins, 1, f"lr_won{i - 1}")
    wrote = register(m, writing, 1, f"lr_wrote{i}")
    return Mux(wrote, Mux(won, ahead["candidate"], ahead.get("passed", Const(0))),
               ahead["kept"])


class LRCheck(wiring.Component):
    """Valid flag and disparity of one output word per position.

    Parameters
    ----------
    params : StereoParams
    left_offset : int
        Where ``disparity``/``left_tag`` are slot-aligned, in clocks after this stage's
        input (``sums``/``tag``).
    slot_base : int
        Clocks from the core's slot clock to ``first`` (see :class:`~.common.SlotClock`).

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
    value : In(output_disparity_bits)
        With F > 0: the output disparity of dL (:mod:`.subpixel`), with it; the check
        compares the whole levels ``disparity``, the word carries ``value``.
    retire : Out(1)
        One pulse per slot with a position, at offset ``latency``.
    produce : Out(1)
        With ``retire``: an output word, for an in-frame position.
    valid, disparity_out, x, y : Out
        The word and its position (with ``produce``).
    frame_start, line_end, frame_end : Out(1)
        The position is (0, 0), the last of its row, the last of its frame.
    latency : int
        Clocks from the input to ``retire``.
    """

    def __init__(self, params, left_offset, slot_base=0):
        self.params, self.left_offset, self.slot_base = params, left_offset, slot_base
        #: The positions arrive in mirrored order, x' = W - 1 - x (the fifth path's rows,
        #: :mod:`.sgm_right`), and their sums in reversed order (:func:`.mirror.reversed_sums`).
        self.mirrored = params.fifth_path
        depth, rounds, units = params.disparities, params.rounds, params.per_round
        timing = lr_timing(params, left_offset)
        #: Offset of the final dR leaving the last unit (see elaborate()).
        self.exit = timing.exit
        self.history_depth = timing.history
        self.latency = timing.latency
        d_bits = bits_for(depth - 1)
        layout = tag_layout(params)
        out_bits = params.output_disparity_bits
        fraction = {"value": In(out_bits)} if params.subpixel_bits else {}
        super().__init__({**fraction,
            "sums": In(data.ArrayLayout(unsigned(params.aggregated_cost_bits), units)),
            "tag": In(layout),
            "first": In(1), "round": In(bits_for(rounds - 1)),
            "disparity": In(d_bits),
            "left_tag": In(layout),
            "retire": Out(1), "produce": Out(1),
            "valid": Out(1), "disparity_out": Out(out_bits),
            "x": Out(layout["x"].shape), "y": Out(layout["y"].shape),
            "frame_start": Out(1), "line_end": Out(1), "frame_end": Out(1),
        })

    def _in_frame(self, tag):
        return tag.live & (tag.y >= 0) & (tag.y < self.params.height)

    def _placed(self, x, d=None):
        """x lies outside the invalid border and (given ``d``) its right pixel x - d in the
        row. Mirrored (x the raster column W - 1 - x'), the border alone: x >= D > d."""
        p = self.params
        if self.mirrored:
            return x <= p.width - 1 - p.first_valid_column
        border = x >= p.first_valid_column
        return border if d is None else (x >= d) & border

    def elaborate(self, platform):
        p = self.params
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "lr", self.slot_base)
        if not p.lr_check:
            tag = self.left_tag
            with m.If(slots.first(self.left_offset)):
                m.d.sync += [self.retire.eq(tag.valid),
                             self.produce.eq(tag.valid & self._in_frame(tag))]
            with m.Else():
                m.d.sync += [self.retire.eq(0), self.produce.eq(0)]
            m.d.sync += [self.valid.eq(self._placed(tag.x)),
                         self.disparity_out.eq(self.value if p.subpixel_bits
                                                else self.disparity),
                         self.x.eq(tag.x), self.y.eq(tag.y),
                         self.frame_start.eq((tag.x == 0) & (tag.y == 0)),
                         self.line_end.eq(tag.x == p.width - 1),
                         self.frame_end.eq((tag.x == p.width - 1) & (tag.y == p.height - 1))]
            return m
        final, leaving = self._right_winners(m, slots)
        # The final dR and its pulse registered on their way to the check, and waiting for
        # late left winners (lr_exit_delay).
        wait = self.exit - (lr_stage_b(p) + p.rounds)
        final, leaving = pipe(m, final, wait, "right_final_wait"), pipe(
            m, leaving, wait, "right_final_valid_wait", reset=True)
        self._check(m, slots, final, leaving)
        return m

    def _right_winners(self, m, slots):
        """The units' stores of running winners; returns dR leaving the last unit and its
        pulse (at ``self.exit``).

        In round j unit i reads (stage A) the winner of xr = x - j*D/R - i, compares it
        with its candidate d = j*D/R + i (stage B, a clock later) and writes the
        result where the next unit reads it in round j of the next position (the last unit
        writes unit 0's word j + 1). The next unit has read its own word j a clock before
        the write lands, and reads it again R clocks later: no skew, no bypass. Unit 0's
        word 0 is a fresh winner (d = 0 is every right pixel's first candidate). With
        R = 1 each store is a register that the next unit reads in stage B directly, and
        each comparison is made a clock ahead (:func:`_lookahead`).
        """
        p = self.params
        rounds, units = p.rounds, p.per_round
        cost_bits, d_bits = p.aggregated_cost_bits, bits_for(p.disparities - 1)
        entry = data.StructLayout({"cost": unsigned(cost_bits), "d": unsigned(d_bits),
                                   "empty": unsigned(1)})
        # Candidates at stage B: unit i's disparity j*D/R + i takes part iff xr = x - d is
        # in the row (x - j*D/R >= i) and the position lies in the frame; each unit's flag
        # is a register of its own (a comparison in stage B would lengthen its path).
        tag = slots.delay(self.tag, 0, 1, "lr_tag")
        # One copy of x - j*D/R and of the frame flag per LR_UNITS_PER_COPY units (replicas):
        # one register for all 64 units' comparisons was census 5x5's critical path at
        # 1280 x 720, D = 64, R = 1 (6.2 ns of routing to the farthest unit, ECP5).
        base = round_base(m, slots, 1, units)
        # Mirrored, unit i's candidate d' = j*D/R + i is d = D - 1 - d' of right pixel
        # x' + d, inside the row iff d' >= x' + D - W: not (x' + D - W) - j*D/R >= i + 1.
        x = slots.delay(self.tag.x + (p.disparities - p.width), 0, 1, "lr_reach") \
            if self.mirrored else tag.x
        difference = x - base
        # The row's comparisons with the frame a clock ahead, from the input tag.
        framed = tag.valid & tag.live & row_inside_ahead(m, self.tag.y, 0, p.height, "lr_row")
        copies = range(-(-units // LR_UNITS_PER_COPY))
        span = range(-p.width - p.disparities, p.disparities) if self.mirrored else \
            range(-p.disparities, p.width)
        x_minus_base = [replica(m, difference, f"lr_x_minus_base{k}", Shape.cast(span),
                                reset_less=True) for k in copies]
        in_frame = [replica(m, framed, f"lr_in_frame{k}") for k in copies]
        stage_a, stage_b = LR_STAGE_A, lr_stage_b(p)
        at_least = _low_comparisons(m, x, base, difference, units, x_minus_base, copies,
                                    slots)
        if self.mirrored:
            beyond = at_least

            def at_least(k, i):
                return ~beyond(k, i + 1)
        # With R >= 3 the word read in stage A is registered before it is compared (a LUT
        # RAM read and a carry chain in one clock were 7.3 ns, census 7x7 on ECP5): the
        # write then lands two clocks after the next unit's read of that word, which
        # reads it again R clocks after the first.
        split = stage_b - stage_a == 2
        # Each unit's candidate disparity (j*D/R + i) is a register of its own, added a
        # clock ahead: one shared j*D/R and an adder per unit in front of the stores' write
        # data were 6.7 ns (census 9x9 on ECP5).
        first_disparity = pipe(m, round_base(m, slots, 1, units), stage_b - 2,
                               "lr_first_disparity")
        writing = _write_enables(slots, tag.valid, stage_b, units)
        last = slots.first(stage_b + rounds - 1) if rounds > 1 else Const(1)
        stores = [Store(m, f"right_winners{i}", entry, rounds) for i in range(units)]
        # Mirrored, a right pixel's candidates come from the highest d down: the later of
        # equal costs is the lower d, which keeps a tie.
        beats = (lambda candidate, best: candidate <= best) if self.mirrored else better
        updated_words, framed_late = [], {}
        wins = previous_cost = None          # unit i - 1's, for unit i's lookahead
        for i, store in enumerate(stores):
            ok = Signal(name=f"candidate_ok{i}")
            k = i // LR_UNITS_PER_COPY
            if stage_b > 3:
                # The comparison registered, then with the frame flag (both in one clock
                # were census 7x7 SGM's deepest logic at R = 10: 5.3 LUT levels).
                if k not in framed_late:
                    framed_late[k] = pipe(m, in_frame[k], 1, f"lr_in_frame{k}_late", True)
                m.d.sync += ok.eq(framed_late[k] &
                                  register(m, at_least(k, i), 1, f"candidate_ge{i}"))
            else:
                m.d.sync += ok.eq(in_frame[k] & at_least(k, i))
            ok = pipe(m, ok, stage_b - 3 - (stage_b > 3), f"candidate_ok{i}", reset=True)
            early_cost = pipe(m, self.sums[i], stage_b - 1, f"candidate_cost{i}")
            cost = pipe(m, early_cost, 1, f"candidate_cost{i}_b")
            if rounds > 1:
                # The comparison is registered with the word it was made on: in stage B
                # only the choice remains in front of the store's write (a comparison
                # there was the critical path of rank 7x7). The word's last write landed
                # at least a clock before this read.
                held = Signal(entry, name=f"held{i}", reset_less=True)
                lower = Signal(name=f"candidate_lower{i}")
                read_address = slots.phased_round(stage_a, i, f"right_winners{i}_read")
                word = store.read(read_address)
                if split:
                    word = pipe(m, word, 1, f"right_winner{i}_read")
                m.d.sync += [held.eq(word), lower.eq(beats(early_cost, word.cost))]
                fresh = slots.first(stage_b)
            else:
                # With R = 1 the word is written in every clock: it is compared a clock
                # ahead (_lookahead), and only the previous unit's choice is left in front
                # of this unit's own.
                held = store.read(0)
                if i:
                    lower = _lookahead(m, i, early_cost, previous_cost,
                                       stores[i - 1].read(0), held, wins, writing[i], beats)
            previous_cost = cost
            if i == 0 and rounds == 1:
                wins = ok            # every right pixel's first candidate: always fresh
            else:
                empty = held.empty | fresh if i == 0 else held.empty
                wins = ok & (empty | lower)
            candidate = Signal(d_bits, name=f"candidate_d{i}", reset_less=True)
            m.d.sync += candidate.eq(p.disparities - 1 - i - first_disparity
                                     if self.mirrored else first_disparity + i)
            if self.mirrored and i == 0:
                # A right pixel's first candidates lie before its row when mirrored
                # (x' + d > W - 1): its word starts empty, not from the stale one.
                held = Mux(fresh, entry.const({"empty": 1}), held) if rounds > 1 else \
                    entry.const({"empty": 1})
            updated = Signal(entry, name=f"updated{i}")
            m.d.comb += updated.eq(Mux(wins, Cat(cost, candidate, Const(0, 1)), held))
            updated_words.append(updated)
        # Store i keeps word j at (j + i) mod R, each with address counters of its own
        # (see SlotClock.phased_round).
        for i, store in enumerate(stores):
            if i:
                store.write(slots.phased_round(stage_b, i, f"right_winners{i}_write"),
                            updated_words[i - 1], writing[i])
            elif rounds > 1:
                # The last unit's word j becomes unit 0's word j + 1 (none after R-1).
                store.write(slots.phased_round(stage_b, 1, "right_winners0_write"),
                            updated_words[-1], writing[0] & ~last)
        leaving = Signal(name="right_final_valid")
        final = Signal(d_bits, name="right_final", reset_less=True)
        m.d.sync += leaving.eq(writing[-1] & last)
        m.d.sync += final.eq(updated_words[-1].d)
        return final, leaving

    def _check(self, m, slots, final, leaving):
        """History of dR, the left winners' store and the check itself.

        Both stores may become block RAM (D words and more): they are read synchronously
        and their data pass a plain register (the RAM's own output register on ECP5)
        before any logic, and no word is read in the clock it is written (no_rw_check).
        """
        p = self.params
        depth, size = p.disparities, self.history_depth
        d_bits = bits_for(depth - 1)
        layout = tag_layout(p)
        index_shape = unsigned(bits_for(size - 1))

        # The left winners, stored by position index.
        fraction = {"value": unsigned(p.output_disparity_bits)} if p.subpixel_bits else {}
        waiting_layout = data.StructLayout({"tag": layout, "d": unsigned(d_bits), **fraction})
        # Both are block RAM (ram_style): as LUT RAM, the read address passed a LUT RAM
        # and its multiplexers before the output register (census 7x7 on ECP5: 8.3 ns).
        ram = {"no_rw_check": 1, "ram_style": "block"}
        m.submodules.left_winners = waiting = Memory(shape=waiting_layout, depth=size,
                                                     init=[], attrs=ram)
        left_read, left_write = waiting.read_port(domain="sync"), waiting.write_port()
        left_count = Signal(index_shape, name="left_count")
        arriving = slots.first(self.left_offset) & self.left_tag.valid
        with m.If(arriving):
            m.d.sync += left_count.eq(left_count + 1)
        m.d.comb += [left_write.addr.eq(left_count), left_write.en.eq(arriving),
                     left_write.data.eq(Cat(self.left_tag, self.disparity,
                                            *([self.value] if p.subpixel_bits else [])))]

        # dR leaving the chain belongs to position n - D + 1 when position n leaves it;
        # then the left winner of position n - D has all its partners.
        m.submodules.right_history = history = Memory(shape=unsigned(d_bits), depth=size,
                                                      init=[], attrs=ram)
        history_read, history_write = history.read_port(domain="sync"), history.write_port()
        # Position n leaves: dR of n - D + 1 is written, the left winner of n - D is read.
        # Both addresses are counters of their own (the stores' depth is a power of two,
        # so they wrap with the index): no subtraction in front of the RAMs.
        written = Signal(index_shape, name="history_written", init=(1 - depth) % size)
        checked_address = Signal(index_shape, name="checked_address", init=(-depth) % size)
        primed = Signal(name="primed")          # D positions have left since reset
        seen = Signal(range(depth + 1), name="exits_seen")
        with m.If(leaving):
            m.d.sync += [written.eq(written + 1), checked_address.eq(checked_address + 1)]
            with m.If(seen != depth):
                m.d.sync += seen.eq(seen + 1)
        m.d.comb += primed.eq(_primed(seen, depth))
        m.d.comb += [history_write.addr.eq(written),
                     history_write.en.eq(leaving), history_write.data.eq(final),
                     left_read.addr.eq(checked_address)]
        # Clock 1: the RAM; 2: its output register; 3: a fabric register; 4: the partner's
        # address; 5: the RAM; 6: its output register; 7: a fabric register; 8: the
        # comparisons with the bounds; 9: the result. Nothing but a register follows a
        # block RAM's output register: a subtraction or comparisons' carry chains right
        # behind it were 6.8-7.3 ns (census and rank 7x7 on ECP5).
        entry = pipe(m, left_read.data, 1, "checked_left")
        early = pipe(m, entry, 1, "checked_left_early")
        # Mirrored, the partner of x' is x' + dL, position n - (D - 1 - dL).
        checked_index = pipe(m, checked_address + (1 - depth) if self.mirrored else
                             checked_address, 3, "checked_index")
        partner_address = Signal(index_shape, name="partner_address", reset_less=True)
        m.d.sync += partner_address.eq(checked_index + early.d if self.mirrored else
                                       checked_index - early.d)
        m.d.comb += history_read.addr.eq(partner_address)
        partner = pipe(m, history_read.data, 2, "partner")
        checked = pipe(m, entry, 6, "checked_left_late")
        stage = pipe(m, Cat(leaving, primed), 8, "check_pulse", reset=True)
        # What does not depend on dR is decided while dR is read.
        placed = Signal(name="checked_placed")
        in_frame = Signal(name="checked_in_frame")
        m.d.sync += [placed.eq(self._placed(early.tag.x, early.d)),
                     in_frame.eq(self._in_frame(early.tag))]
        kept = pipe(m, placed, 4, "checked_placed")
        in_frame = pipe(m, in_frame, 4, "checked_in_frame")
        if p.lr_threshold is not None:
            low = Signal(range(-p.lr_threshold, depth), name="consistent_low")
            high = Signal(range(depth + p.lr_threshold), name="consistent_high")
            m.d.sync += [low.eq(early.d - p.lr_threshold), high.eq(early.d + p.lr_threshold)]
            low, high = pipe(m, low, 3, "consistent_low"), pipe(m, high, 3, "consistent_high")
            consistent = Signal(name="consistent")
            m.d.sync += consistent.eq(_consistent(partner, low, high))
            kept = kept & consistent
        # The word's framing flags, formed from registers here rather than from the output
        # registers by the core (they feed the output queue and the flush's count).
        tag = checked.tag
        m.d.sync += [
            self.retire.eq(stage[0]),
            self.produce.eq(stage[0] & stage[1] & in_frame),
            self.valid.eq(kept),
            self.disparity_out.eq(checked.value if p.subpixel_bits else checked.d),
            self.x.eq(tag.x), self.y.eq(tag.y),
            self.frame_start.eq((tag.x == 0) & (tag.y == 0)),
            self.line_end.eq(tag.x == p.width - 1),
            self.frame_end.eq((tag.x == p.width - 1) & (tag.y == p.height - 1)),
        ]
