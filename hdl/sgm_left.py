"""The left path of semi-global aggregation in hardware, at any number of rounds R.

Part of :class:`npstereo.hdl.sgm.SemiGlobalAggregation`; docs/semantics.md ("The left
path") is the contract, docs/hardware.md ("Semi-global aggregation") the structure. The
unnormalised path cost Lu is kept modulo 2^n (``params.left_loop_bits``): every pair of
values compared differs by less than 2^(n-1), so the sign bit of an n-bit difference
orders them.

**The loop.** Per lane, Lu(x, d) = C(x, d) + min(Lu(x-1, d), Lu(x-1, d +- 1) + P1,
ref(x) + P2(x)), the P1 candidates only into the columns of ``SGM_LEFT_P1_PARITY`` (a flag
per group of lanes clears the comparisons they win and sets those they lose); Lu(x-1, .) of round j is word j of a store of R words (shifting
registers at R <= 2, LUT RAM above), the neighbour d - 1 across the round's lower edge
is the last lane of the word the previous round read (registered), the neighbour d + 1
across the upper edge the first lane of word j + 1 (a store of its own). Round j + 1 of
x - 1 is written R - 1 clocks (back to back) before round j of x reads it: one clock of
logic at R <= 2, two at R = 3 (the comparisons, then the choice and the addition), three
from R = 4 on (the comparisons, the choice, the addition;
``plan_timing.sgm_left_stages``). ref(x) + P2(x) is one register per group of lanes,
constant through the slot: nothing inside the loop spans all D disparities.

**The reference.** ref(x) = Lu(s, b) + C(s+1, b) + ... + C(x-1, b), s = max(x - J, 0),
b = b(x) the argmin over d of Lu(max(x - K, 0), .):

- a registered argmin tree over the lanes of Lu, then a running argmin over the rounds,
  gives m(x) and G(x) = argmin Lu(x, .) (as round and lane), written into a file of K
  entries indexed by x mod K; b(x) is entry (x - K) mod K, or G(0) for x <= K, which an
  argmin over C(0, .) = Lu(0, .) gives early (handed from position to position);
- at position p, for k = 1 .. J - 1, C(p, b(p + k)) is picked (a two-clock multiplexer
  per round, kept when b's round passes) into a file of J entries indexed by p mod J;
  Lu(p, b(p + J)) likewise from the loop's output;
- position x adds what positions x - J .. x - 1 left for it and P2(x) (m(0) instead of
  Lu(0, b) for x <= J, no C of columns < 1).

Files indexed by the column, not shift registers, so that what a position reads does not
depend on the gaps between positions; every step is at a fixed offset after its position's
slot (``plan_timing.sgm_timing`` derives them and checks the margins), files and stores
are written only in slots with a position.

**The output.** L(x, d) = Lu(x, d) - m(x - 1) (Lu(0, d) at x = 0): Lu delayed until
m(x - 1), the exact minimum over D of the previous position, is there.
"""

from amaranth.hdl import Cat, Const, Mux, Signal, unsigned

from ..params import SGM_TRACK_AGE, SGM_TRACK_STEPS
from .common import (LaneStores, ShiftStore, Store, bits_for, delay_line, register, replica,
                     split_lanes)
from .plan_timing import sgm_delays, sgm_left_firsts_registered, sgm_left_shift_store
from .sgm_left_choice import copies, less, minimum, pick, small_step, winners
from .sgm_left_pairs import pair_update
from .sgm_left_reference import pick_references as _picks, reference_sum
from .trees import build_min_tree

__all__ = ["PathOwner", "left_path"]


class PathOwner:
    """What :func:`left_path` asks its owner for besides ``params``, ``timing``, ``tag``,
    ``_slots`` (its slot clock) and ``_costs`` (the costs' taps): the tag's valid flag and
    slot-aligned delays. The SGM stage and the fifth path's recursion (:mod:`.sgm_right`)
    are owners; each sets ``_valid = {}`` when it elaborates."""

    def _valid_at(self, offset):
        """The tag's ``valid`` slot-aligned at ``offset``: the write enable of every state."""
        if offset not in self._valid:
            self._valid[offset] = self._slots.delay(self.tag.valid, 0, offset,
                                                    f"{self._slots.name}_valid{offset}")
        return self._valid[offset]

    def _aligned(self, value, start, offset, name):
        """A slot-aligned ``value`` moved from ``start`` to ``offset`` (constants stay)."""
        if isinstance(value, Const):
            return value
        return self._slots.delay(value, start, offset - start, name)

    def _lane_copies(self, m, value, start, offset, name):
        """:meth:`_aligned` to ``offset`` > ``start``, its last register copied per group of
        lanes (:func:`.sgm_left_choice.copies`): the list of each lane's copy."""
        if isinstance(value, Const):
            return [value] * self.params.per_round
        early = self._aligned(value, start, offset - 1, name)
        return copies(m, early, value.shape(), self.params.per_round, f"{name}_s{offset}",
                       self._slots.first(offset - 1))


#: Lanes per copy of m(x - 1) and of the fresh start in the output's subtraction.
_OUTPUT_LANES_PER_COPY = 4


def _file(m, count, shape, name):
    """``count`` registers read by a column index (its low bits)."""
    return [Signal(shape, name=f"{name}{k}", reset_less=True) for k in range(count)]


def _argmin(m, values, less, name, split=False):
    """(value, lane) of the smallest of ``values``, ties to the lowest lane: a tree with a
    register after every level, two with ``split`` (:func:`~.trees.build_min_tree`)."""
    lane_bits = bits_for(len(values) - 1)
    leaves = [(v, Const(i, lane_bits)) for i, v in enumerate(values)]
    return build_min_tree(m, 1, leaves, split, name, compare=less)


def _running_argmin(owner, m, item, offset, less, name):
    """Over a slot's rounds, the smallest ``item`` (value, lane) of each round (round j's at
    ``offset`` + j), ties to the earliest round: (value, round, lane) registers holding the
    result in the clock ``offset`` + R.

    The comparison is made twice, against the value and against a copy of it kept for the
    lane and the round: one comparison into all three was census 7x7 SGM's critical path at
    R = 10 (the tree's value through it into the round, 7.01 ns, 12 cells)."""
    slots, rounds = owner._slots, owner.params.rounds
    value, lane = item
    best = Signal(value.shape(), name=f"{name}_value", reset_less=True)
    best_copy = Signal(value.shape(), name=f"{name}_value_copy", reset_less=True,
                       attrs={"keep": 1})
    best_lane = Signal(lane.shape(), name=f"{name}_lane", reset_less=True)
    best_round = Signal(bits_for(rounds - 1), name=f"{name}_round", reset_less=True)
    first = slots.first(offset)
    restart, restart_copy = first | less(value, best), first | less(value, best_copy)
    m.d.sync += [best.eq(Mux(restart, value, best)),
                 best_copy.eq(Mux(restart_copy, value, best_copy)),
                 best_lane.eq(Mux(restart_copy, lane, best_lane)),
                 best_round.eq(Mux(restart_copy, slots.round(offset), best_round))]
    return best, best_round, best_lane


def left_path(owner, m, fresh, p2):
    """L of the left path per lane at ``timing.left`` (see the module docstring).

    ``owner`` is the :class:`~.sgm.SemiGlobalAggregation` being elaborated (its slot
    clock, costs taps, alignment helpers); ``fresh`` and ``p2`` are slot-aligned at
    ``timing.guide``.
    """
    p, t, slots = owner.params, owner.timing, owner._slots
    units, rounds, tree = p.per_round, p.rounds, t.tree
    bits, cost_bits = p.left_loop_bits, p.cost_bits
    steps, age = SGM_TRACK_STEPS, SGM_TRACK_AGE
    assert steps & (steps - 1) == 0 and age & (age - 1) == 0, \
        "the files are indexed by the column's low bits"
    costs = owner._costs
    lu_at, argmin_at = t.left_lu, t.left_argmin
    lane_bits, round_bits = bits_for(units - 1), bits_for(rounds - 1)

    def modular_less(a, b):
        return less(a, b, bits)

    def column(offset):
        return owner._aligned(owner.tag.x, 0, offset, "sgm_left_x")

    def valid(offset):
        return slots.first(offset) & owner._valid_at(offset)

    def fresh_at(offset):
        return owner._aligned(fresh, t.guide, offset, "sgm_left_fresh")

    # G(0) = argmin C(0, .) and m(0) early, from the costs: the row's first b and m.
    early, hand = t.left_early, t.left_hand
    item = _argmin(m, costs[0], lambda a, b: a < b, "sgm_left_c0")
    first_m, first_round, first_lane = _running_argmin(owner, m, item, tree,
                                                       lambda a, b: a < b, "sgm_left_c0")
    start = valid(early) & fresh_at(early)
    b0 = register(m, Cat(first_lane, first_round), lane_bits + round_bits, "sgm_left_b0",
                   start)
    m0_held = register(m, first_m, cost_bits, "sgm_left_m0_held", start)
    # Written at a fresh start only, but at ``hand`` >= where x <= J read it, so that the
    # next row's first position cannot overwrite it before the last reader of this row.
    m0 = register(m, m0_held, cost_bits, "sgm_left_m0", valid(hand) & fresh_at(hand))

    # What positions x - J .. x - 1 leave for x: Lu(x - J, b(x)), C(x - k, b(x)).
    history = _file(m, age, lane_bits + round_bits, "sgm_left_g")
    chosen = _file(m, steps, bits, "sgm_left_v")
    sums = [_file(m, steps, cost_bits, f"sgm_left_c{k}") for k in range(1, steps)]

    # ref(x) + P2(x), loaded at ``left_reference`` and held through the slot.
    reference = copies(m, reference_sum(owner, m, column, m0, p2, chosen, sums), bits, units,
                        "sgm_left_ref", slots.first(t.left_reference))
    update = pair_update if t.left_pairs else _lane_update
    lu = update(owner, m, reference, fresh_at, column)

    # m(x) and G(x) = argmin Lu(x, .), complete at ``argmin_at``.
    item = _argmin(m, lu, modular_less, "sgm_left_lu_min", t.left_argmin_split)
    lowest, best_round, best_lane = _running_argmin(owner, m, item, argmin_at - rounds,
                                                    modular_less, "sgm_left_lu_min")
    done = valid(argmin_at)
    # m(x) (and below the fresh start) in a copy per group of four lanes: one register of
    # it into every lane's subtraction was census 7x7 SGM's path at R = 10 (7.19 ns, 5.54
    # of it routing), one per eight lanes still 6.64 ns (4.49).
    previous_m = copies(m, lowest, bits, units, "sgm_left_m", done, _OUTPUT_LANES_PER_COPY)
    # Each entry's write enable decoded a clock ahead into a register of its own: the slot
    # pulse through the decoder into all K entries' enables was census 7x7 SGM's path at
    # R = 10 (6.74 ns, 5.51 of it routing).
    x = column(argmin_at - 1)
    for k, entry in enumerate(history):
        write = replica(m, valid(argmin_at - 1) & (x[:age.bit_length() - 1] == k),
                        f"sgm_left_g_write{k}")     # a control bit, so it resets
        with m.If(write):
            m.d.sync += entry.eq(Cat(best_lane, best_round))
    _picks(owner, m, column, fresh_at, history, b0, lu, chosen, sums)

    # L(x, d) = Lu(x, d) - m(x - 1): Lu waits for m(x - 1).
    out = t.left - 1
    fresh_out = copies(m, fresh_at(out - 1), 1, units, "sgm_left_fresh_out",
                        per=_OUTPUT_LANES_PER_COPY)
    assert out - lu_at == sgm_delays(p)["lu"]
    delayed = split_lanes(delay_line(m, Cat(*lu), out - lu_at, "sgm_left_lu_delay"), units, bits)
    return [register(m, (v - Mux(f, 0, mc))[:p.left_cost_bits], p.left_cost_bits,
                     f"sgm_left_l{i}")
            for i, (v, f, mc) in enumerate(zip(delayed, fresh_out, previous_m))]


def _lane_update(owner, m, reference, fresh_at, column):
    """Lu(x, .) per lane in a register at ``timing.left_lu`` from a loop over one position
    (R >= 2; module docstring): round j of x reads Lu(x - 1, round j) at ``loop`` + j."""
    p, t, slots = owner.params, owner.timing, owner._slots
    units, rounds, bits, costs, loop = p.per_round, p.rounds, p.left_loop_bits, owner._costs, \
        t.loop
    small = owner._lane_copies(m, small_step(owner.tag.x), 0, loop, "sgm_left_small")
    # The loop: Lu(x - 1, .) of round j from the store at ``loop`` + j.
    # A word holds Lu and Lu + P1 of every lane (the + P1 added beside Lu, outside the
    # loop's path: the word's read, + P1 and the comparisons were census 7x7 SGM's
    # critical path at R = 10, 6.70 ns, nine levels).
    shifting = sgm_left_shift_store(rounds)
    if shifting:
        store = ShiftStore(m, "sgm_left_store", unsigned(2 * units * bits), rounds)
        word = store.oldest
    else:
        # LUT RAM read a clock early into a register: Lu(x - 1, round j) was written in
        # clock T - R + j + stages - 1 <= T + j - 2 (R >= 3). The round counter, the LUT
        # RAM's read and + P1 in front of the comparisons were census 7x7 SGM's critical
        # path at R = 10 (9.44 ns, 106 MHz), the read, + P1 and the comparisons census 5x5
        # SGM's at 1280 x 720, D = 64, R = 4 (10.76 ns, 92.9 MHz).
        # One LUT RAM per few lanes, each read at a round counter of its own (round loop - 1
        # is round loop - 2 a clock later): one counter into every lane's read address
        # recurred in census 7x7 SGM's placements at R = 10 (13-14 endpoints, wire only).
        store = LaneStores(m, "sgm_left_store", units, bits, rounds, sections=2)
        word = register(m, store.read(lambda k: replica(m, slots.round(loop - 2),
                                                        f"sgm_left_read_round{k}",
                                                        reset_less=True)),
                        2 * units * bits, "sgm_left_word")
    centre, plus = split_lanes(word, units, bits), split_lanes(word[units * bits:], units, bits)
    # The neighbours across the round's edges, + P1: the last lane of the word read a clock
    # ago (round j - 1 of x - 1), the first lane of word j + 1 (a store of its own, which
    # keeps it + P1). Outside 0 .. D-1 the lane itself stands in: Lu(d) + P1 never beats
    # Lu(d). The edge flags come from the round counters of a clock earlier, registered:
    # the counter, the store's read and the comparisons in one clock were census 7x7 SGM's
    # critical path at R = 10 (10.6 ns).
    before = register(m, plus[units - 1], bits, "sgm_left_before")
    firsts = None
    if rounds > 1:
        first_round = register(m, slots.round(loop - 1) == 0, 1, "sgm_left_first_round")
        last_round = register(m, slots.round(loop - 1) == rounds - 1, 1,
                              "sgm_left_last_round")
        # Round j reads the first lane of round j + 1 of x - 1, written R - 1 writes before.
        firsts = ShiftStore(m, "sgm_left_firsts", unsigned(bits), rounds - 1) if shifting \
            else Store(m, "sgm_left_firsts", unsigned(bits), rounds)
        # The round counter two clocks earlier reads j + 1 (mod R) a clock before round j.
        just_written = None
        if shifting:
            following = firsts.oldest
        else:
            following = register(m, firsts.read(slots.round(loop - 2)), bits,
                                 "sgm_left_following")
        if not shifting and not sgm_left_firsts_registered(rounds):
            # R = 3, 4: the word is written in the clock before its read when the slot
            # before held a position, and a clock too late for the early read; it is then
            # taken from the write's own register. Read through the LUT RAM at the round
            # counter, it was census 5x5 SGM's critical path at 1280 x 720, D = 64, R = 4
            # (9.83 ns, 101.8 MHz).
            just_written = Signal(bits, name="sgm_left_just_written", reset_less=True)
            just_valid = Signal(name="sgm_left_just_valid")
            above_written = Mux(last_round, plus[units - 1], just_written)
        below = Mux(first_round, plus[0], before)
        above = Mux(last_round, plus[units - 1], following)
    else:
        below, above = plus[0], plus[units - 1]
    neighbours = [below, *plus, above]
    last = loop + t.left_stages - 1           # the clock that writes Lu(x, round j)
    # With the choice registered, a fresh start zeroes that register (its flip-flops'
    # synchronous reset) instead of a multiplexer behind it: the fresh flag's copy through
    # the multiplexer and the additions into the store's write was census 7x7 SGM's
    # critical path at R = 10 in two placements of three (6.73 and 7.47 ns).
    fresh_chosen = (copies(m, fresh_at(last - 2), 1, units, "sgm_left_fresh_lane")
                    if t.left_stages == 3 else None)
    lanes = []
    for i in range(units):
        candidates = [centre[i], neighbours[i], neighbours[i + 2], reference[i]]
        beats, choose = minimum(candidates, bits, small[i])
        if t.left_stages >= 2:
            # Compare, then choose (and add): the loop has R - 1 >= 2 clocks to spare.
            # Where the comparisons' clock has nothing in front of them (R >= 5) the
            # winner's one-hot flags are registered, each a LUT behind three carry chains:
            # the comparisons registered and the flags formed in the choice's clock were
            # census 7x7 SGM's critical path at R = 10 (6.78 ns, 3 levels). At R = 3, 4 the
            # just-written word's multiplexer comes first, and the flags there were census
            # 5x5 SGM's critical path at 1280 x 720, R = 4 (7.67 ns, 12 cells; 130.3 MHz
            # against 150.1 with the comparisons registered).
            def registered(values):
                return [register(m, c, bits, f"sgm_left_cand{i}_{k}")
                        for k, c in enumerate(values)]
            # (Each branch makes its registers in the order of the netlists measured.)
            if just_written is None:
                wins = [register(m, w, 1, f"sgm_left_wins{i}_{k}")
                        for k, w in enumerate(winners(beats))]
                candidates = registered(candidates)
            else:
                if i == units - 1:
                    # The neighbour above compared both ways, as read and as just written,
                    # and chosen behind the comparisons: the choice in front of them was
                    # census 7x7 SGM's critical path at 640 x 480, D = 64, R = 4 (6.70 ns,
                    # 4 levels, 149.1 MHz).
                    written = candidates[:2] + [above_written, candidates[3]]
                    beats_written, _ = minimum(written, bits, small[i])
                    beats = {key: Mux(just_valid, beats_written[key], b) if 2 in key else b
                             for key, b in beats.items()}
                    candidates[2] = Mux(just_valid, above_written, above)
                candidates = registered(candidates)
                if 0 < i < units - 1:
                    # Nothing in front of a middle lane's comparisons: its flags are
                    # registered, a LUT behind them (with the small step's flag), so that
                    # the choice is the one-hot multiplexer alone. The flags formed from
                    # registered comparisons in front of it were census 5x5 SGM + fifth
                    # path's critical path at 640 x 48, R = 4 (6.86 ns, 3 levels).
                    wins = [register(m, w, 1, f"sgm_left_wins{i}_{k}")
                            for k, w in enumerate(winners(beats))]
                else:
                    wins = winners({key: register(m, b, 1,
                                                  f"sgm_left_beats{i}_{key[0]}{key[1]}")
                                    for key, b in beats.items()})
            best = pick(candidates, wins, bits)
        else:
            best = choose(beats)
        if fresh_chosen is not None:
            # Then add: R - 1 >= 3 clocks to spare.
            best = register(m, Mux(fresh_chosen[i], 0, best), bits, f"sgm_left_best{i}")
        lanes.append(best)
    if fresh_chosen is None:
        fresh_copies = copies(m, fresh_at(last - 1), 1, units, "sgm_left_fresh_lane")
        lanes = [Mux(f, 0, best) for f, best in zip(fresh_copies, lanes)]
    new = [(c + best)[:bits] for c, best in zip(costs[last], lanes)]
    # Lu + P1 from C + P1 (registered a clock before): one addition to the store, as Lu's.
    costs_plus = [register(m, c + p.p1, bits + 1, f"sgm_left_cost_plus{i}")
                  for i, c in enumerate(costs[last - 1])]
    new_plus = [(c + best)[:bits] for c, best in zip(costs_plus, lanes)]
    store.write(slots.round(last), Cat(*new, *new_plus), owner._valid_at(last))
    if firsts is not None:
        first = new_plus[0]
        firsts.write(slots.round(last), first, owner._valid_at(last))
        if just_written is not None:
            m.d.sync += [just_written.eq(first), just_valid.eq(owner._valid_at(last))]
    return [register(m, v, bits, f"sgm_left_lu{i}") for i, v in enumerate(new)]
