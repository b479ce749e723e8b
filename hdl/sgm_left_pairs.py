"""The left path's loop over two positions (R <= 2): part of :func:`.sgm_left.left_path`
(docs/hardware.md, "The left path at R = 1 and R = 2").

With the small step only into odd columns (``params.SGM_LEFT_P1_PARITY``), an even column x
has

    Lu(x) = min(S + Lu(x-2, d), S + Lu(x-2, d +- 1) + P1, S + Q(x-1), C(x) + Q(x)),

S = C(x-1, d) + C(x, d) and Q = ref + P2: the five candidates are compared as Lu(x-2, d),
Lu(x-2, d +- 1) + P1, Q(x-1) and Q(x) - C(x-1, d), then chosen and added to S. The loop's
state is Lu of the last even column; an odd column x' takes the first four's comparisons
over Lu(x' - 1) and chooses and adds C(x') outside the loop. Every state below is written
only in slots with a position (gaps hold it).
"""

from amaranth.hdl import Array, Cat, Mux, Signal, unsigned

from ..params import SGM_LEFT_P1_PARITY
from .common import ShiftStore, bits_for, register, split_lanes
from .sgm_left_choice import copies, less, minimum

__all__ = ["pair_update"]


class _Columns:
    """The column's parity and per-lane registers of an owner's loop over two positions."""

    def __init__(self, owner, m):
        self.owner, self.m = owner, m
        self.units, self.bits = owner.params.per_round, owner.params.left_loop_bits

    def odd_at(self, offset):
        """Whether the slot at ``offset`` is a column with the small step (slot-aligned)."""
        x = self.owner.tag.x[0]
        return self.owner._aligned(x if SGM_LEFT_P1_PARITY else ~x, 0, offset, "sgm_left_odd")

    def even_at(self, offset):
        """A position without the small step in the slot at ``offset``."""
        return self.owner._valid_at(offset) & ~self.odd_at(offset)

    def lanes_at(self, flag, offset, name):
        """A slot-aligned flag (a function of the offset) at ``offset``, a copy per group of
        lanes."""
        return self.owner._lane_copies(self.m, flag(offset - 1), offset - 1, offset, name)

    def in_round(self, flag, offset, j, name):
        """``flag`` at ``offset`` in round ``j`` only, a copy per group of lanes (registered
        from the clock before, where the flag and the round counter are a clock younger)."""
        slots = self.owner._slots
        return copies(self.m, flag(offset - 1) & (slots.round(offset - 1) == j), 1, self.units,
                      name)

    def lane_registers(self, name, shape=None):
        return [Signal(shape or self.bits, name=f"{name}{i}", reset_less=True)
                for i in range(self.units)]


def pair_update(owner, m, reference, fresh_at, column):
    """Lu(x, .) per lane in a register at ``timing.left_lu``.

    The state, Lu and Lu + P1 of the last even column, is a register per lane at R = 1 and
    a word of them per round at R = 2, read into registers by the round (with the
    neighbours across the round's edges) in every clock: ``reading`` = R - 1 clocks. In
    every clock, too, the six comparisons among the state's three candidates and Q of the
    last odd column (``odd_q``) are registered; they are what both columns need:

    - an even column x (round j) compares Q(x) - C(x-1, d) against those four at ``loop`` +
      j (a fresh start makes it win: S = C(0, d) and Q - C = 0), then chooses among five and
      adds S at ``loop`` + 1 + j, into word j: positions are R clocks apart, so the next
      even column reads word j + 1's first lane (the neighbour across the upper edge) in
      the clock ``loop`` - 1 + j it is there (R = 2), or the state two clocks after it is
      written (R = 1);
    - an odd column x' takes the comparisons made ``reading`` + 1 clocks after its slot
      (Lu(x' - 1) is written and read then) and chooses among four and adds C(x') in the
      next, outside the loop.
    """
    p, t, slots, cols = owner.params, owner.timing, owner._slots, _Columns(owner, m)
    units, rounds, bits, costs, loop = p.per_round, p.rounds, p.left_loop_bits, \
        owner._costs, t.loop
    reading = rounds - 1
    assert rounds <= 2 and t.left_reference == loop - 2 and t.left_lu == loop + 3 + reading
    state = [cols.lane_registers(f"sgm_left_even{j}_") for j in range(rounds)]
    state_plus = [cols.lane_registers(f"sgm_left_even_plus{j}_") for j in range(rounds)]

    def again(values, name):
        return [register(m, v, len(v), f"{name}{i}") for i, v in enumerate(values)]

    # In the clock before the comparisons (``loop`` - 1), ref + P2 holds Q(x); C(x - 1, round
    # j) is the oldest word of a store shifted in every clock of a slot with a position
    # (kept across gaps).
    before = loop - 1
    last = ShiftStore(m, "sgm_left_last_costs", unsigned(units * p.cost_bits), rounds)
    last.write(slots.round(before), Cat(*costs[before]), owner._valid_at(before))
    previous = split_lanes(last.oldest, units, p.cost_bits)
    fresh = cols.lanes_at(fresh_at, before, "sgm_left_pair_fresh")
    # S, S + P1 and Q(x) - C(x - 1): a fresh start has S = C(x) and Q(x) - C(x - 1) = 0.
    held = [register(m, Mux(f, 0, c), p.cost_bits, f"sgm_left_held{i}")
            for i, (f, c) in enumerate(zip(fresh, previous))]
    late_q = [register(m, Mux(f, 0, q - c), bits, f"sgm_left_late_q{i}")
              for i, (f, q, c) in enumerate(zip(fresh, reference, previous))]
    costs_plus = [register(m, c + p.p1, p.cost_bits + 1, f"sgm_left_cost_plus{i}")
                  for i, c in enumerate(costs[before])]
    pair = [register(m, h + c, bits, f"sgm_left_pair_sum{i}")
            for i, (h, c) in enumerate(zip(held, costs[loop]))]
    pair_plus = [register(m, h + c, bits, f"sgm_left_pair_plus{i}")
                 for i, (h, c) in enumerate(zip(held, costs_plus))]
    # Q of the last odd column, for its own choice and for the even column after it: loaded
    # at ``loop``, after the even column before it has chosen, from ref + P2 a clock
    # earlier (at R = 1 ref + P2 is the next position's by then).
    odd_q = copies(m, register(m, reference[0], bits, "sgm_left_last_q"), bits, units,
                   "sgm_left_odd_q", owner._valid_at(loop) & cols.odd_at(loop))

    # The state's three candidates of each lane (Lu(d), Lu(d -+ 1) + P1), and the same
    # again a clock later for the choices.
    if rounds == 1:
        near = [state_plus[0][0], *state_plus[0], state_plus[0][-1]]
        current = [[c, near[i], near[i + 2]] for i, c in enumerate(state[0])]
        chosen = current        # the state holds them through the choices
    else:
        current = _read_word(m, slots, state, state_plus, before, "sgm_left_read")
        chosen = [again(three, f"sgm_left_choice{i}_") for i, three in enumerate(current)]

    # The comparisons among the four in every clock, and Q(x) - C(x - 1) against them.
    fresh_loop = cols.lanes_at(fresh_at, loop, "sgm_left_loop_fresh")
    beats = []
    for i, three in enumerate(current):
        four = three + [odd_q[i]]
        among, _ = minimum(four, bits)
        lane = {key: register(m, b, 1, f"sgm_left_beats{i}_{key[0]}{key[1]}")
                for key, b in among.items()}
        lane.update({(4, k): register(m, less(late_q[i], c, bits) | fresh_loop[i], 1,
                                      f"sgm_left_beats{i}_4{k}") for k, c in enumerate(four)})
        beats.append(lane)
    late_q = again(late_q, "sgm_left_late_q_choice")

    # The even column's choice among five and + S, into word j (the loop).
    state_write = [cols.in_round(cols.even_at, loop + 1, j, f"sgm_left_state_write{j}")
                   for j in range(rounds)]
    news = []
    for i, three in enumerate(chosen):
        _, choose = minimum(three + [odd_q[i], late_q[i]], bits)
        best = choose(beats[i])
        new, new_plus = (pair[i] + best)[:bits], (pair_plus[i] + best)[:bits]
        for j in range(rounds):
            with m.If(state_write[j][i]):
                m.d.sync += [state[j][i].eq(new), state_plus[j][i].eq(new_plus)]
        news.append(new)
    # ... out beside the odd column's choice among four + C(x').
    evens = state[0] if rounds == 1 else again(again(news, "sgm_left_even_new"),
                                                 "sgm_left_even_out")
    out = loop + 2 + reading
    odd_out = cols.lanes_at(cols.odd_at, out, "sgm_left_odd_out")
    lu = []
    for i, (three, even) in enumerate(zip(chosen, evens)):
        _, choose = minimum(three + [odd_q[i]], bits)
        odd = (costs[out][i] + choose(beats[i]))[:bits]
        lu.append(register(m, Mux(odd_out[i], odd, even), bits, f"sgm_left_lu{i}"))
    return lu


def _read_word(m, slots, state, state_plus, at, name):
    """Per lane, word j of the state's Lu(d) and Lu(d -+ 1) + P1 in registers loaded at
    ``at`` + j, in every clock; across the round's edges the last lane of word j - 1 and the
    first of word j + 1 (the lane itself outside 0 .. D-1). The word chosen by a round
    counter copied per group of lanes."""
    units, rounds = len(state[0]), len(state)
    bits = len(state[0][0])
    select = copies(m, slots.round(at - 1), unsigned(bits_for(rounds - 1)), units,
                    f"{name}_round")

    def word(values, lane, name):
        return register(m, Array(values)[select[lane]], bits, name)
    centre = [word([w[i] for w in state], i, f"{name}_lu{i}") for i in range(units)]
    plus = [word([w[i] for w in state_plus], i, f"{name}_plus{i}") for i in range(units)]
    below = word([state_plus[0][0]] + [w[-1] for w in state_plus[:-1]], 0, f"{name}_below")
    above = word([w[0] for w in state_plus[1:]] + [state_plus[-1][-1]], units - 1,
                 f"{name}_above")
    near = [below, *plus, above]
    return [[c, near[i], near[i + 2]] for i, c in enumerate(centre)]
