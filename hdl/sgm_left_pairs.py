"""The left path's loop over two positions (R = 1): part of :func:`.sgm_left.left_path`
(docs/hardware.md, "The left path at R = 1").

With the small step only into odd columns (``params.SGM_LEFT_P1_PARITY``), an even column x
has

    Lu(x) = min(S + Lu(x-2, d), S + Lu(x-2, d +- 1) + P1, S + Q(x-1), C(x) + Q(x)),

S = C(x-1, d) + C(x, d) and Q = ref + P2: the five candidates are compared as Lu(x-2, d),
Lu(x-2, d +- 1) + P1, Q(x-1) and Q(x) - C(x-1, d), then chosen and added to S. The loop's
state is Lu of the last even column; an odd column x' takes the first four's comparisons
over Lu(x' - 1) and chooses and adds C(x') outside the loop. Every state below is written
only in slots with a position (gaps hold it).
"""

from amaranth.hdl import Mux, Signal

from .common import register
from .sgm_left_choice import copies, less, minimum, small_step

__all__ = ["pair_update"]


class _Columns:
    """The column's parity and per-lane registers of an owner's loop over two positions."""

    def __init__(self, owner, m):
        self.owner, self.m = owner, m
        self.units, self.bits = owner.params.per_round, owner.params.left_loop_bits

    def odd_at(self, offset):
        """Whether the slot at ``offset`` is a column with the small step (slot-aligned)."""
        return self.owner._aligned(small_step(self.owner.tag.x), 0, offset, "sgm_left_odd")

    def even_at(self, offset):
        """A position without the small step in the slot at ``offset``."""
        return self.owner._valid_at(offset) & ~self.odd_at(offset)

    def lanes_at(self, flag, offset, name):
        """A slot-aligned flag (a function of the offset) at ``offset``, a copy per group of
        lanes."""
        return self.owner._lane_copies(self.m, flag(offset - 1), offset - 1, offset, name)

    def lane_registers(self, name, shape=None):
        return [Signal(shape or self.bits, name=f"{name}{i}", reset_less=True)
                for i in range(self.units)]


def pair_update(owner, m, reference, fresh_at, column):
    """Lu(x, .) per lane in a register at ``timing.left_lu``.

    The state, Lu and Lu + P1 of the last even column, is a register per lane, compared
    as it is. In every clock the six comparisons among its three candidates and Q of the
    last odd column (``odd_q``) are registered; they are what both columns need (between
    an odd column x - 1 and the even column x only gaps come, which write nothing):

    - an even column x compares Q(x) - C(x-1, d) against those four at ``loop`` (a fresh
      start makes it win: S = C(0, d) and Q - C = 0), then chooses among five and adds S
      at ``loop`` + 1: the next even column compares the state two clocks after it is
      written;
    - an odd column x' takes the comparisons made a clock after its slot's ``loop``
      (Lu(x' - 1) is written by then) and chooses among four and adds C(x') in the next,
      outside the loop.

    S, S + P1 and Q(x) - C(x - 1) run free through registers from ``loop`` - 1 to the
    choice: registers loaded in even slots only were overwritten by the next row's first
    column (even) when it followed an even last column directly (odd widths).
    """
    p, t, cols = owner.params, owner.timing, _Columns(owner, m)
    units, bits, costs, loop = p.per_round, p.left_loop_bits, owner._costs, t.loop
    assert p.rounds == 1 and t.left_reference == loop - 2 and t.left_lu == loop + 3
    state, state_plus = cols.lane_registers("sgm_left_even"), \
        cols.lane_registers("sgm_left_even_plus")

    # In the clock before the comparisons (``loop`` - 1), ref + P2 holds Q(x); C(x - 1) is
    # the last position's (kept across gaps).
    before = loop - 1
    previous = [_last_position(m, c, owner._valid_at(before), f"sgm_left_last_cost{i}")
                for i, c in enumerate(costs[before])]
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
    # earlier (ref + P2 is the next position's by then).
    odd_q = copies(m, register(m, reference[0], bits, "sgm_left_last_q"), bits, units,
                   "sgm_left_odd_q", owner._valid_at(loop) & cols.odd_at(loop))

    # The comparisons among the four in every clock, and Q(x) - C(x - 1) against them;
    # outside 0 .. D-1 the lane itself stands in (Lu(d) + P1 never beats Lu(d)).
    near = [state_plus[0], *state_plus, state_plus[-1]]
    fours = [[c, near[i], near[i + 2], q] for i, (c, q) in enumerate(zip(state, odd_q))]
    fresh_loop = cols.lanes_at(fresh_at, loop, "sgm_left_loop_fresh")
    beats = []
    for i, four in enumerate(fours):
        among, _ = minimum(four, bits)
        lane = {key: register(m, b, 1, f"sgm_left_beats{i}_{key[0]}{key[1]}")
                for key, b in among.items()}
        lane.update({(4, k): register(m, less(late_q[i], c, bits) | fresh_loop[i], 1,
                                      f"sgm_left_beats{i}_4{k}") for k, c in enumerate(four)})
        beats.append(lane)
    late_q = [register(m, v, bits, f"sgm_left_late_q_choice{i}") for i, v in enumerate(late_q)]

    # The even column's choice among five and + S (the loop); the state holds the four
    # candidates through both columns' choices.
    write = cols.lanes_at(cols.even_at, loop + 1, "sgm_left_state_write")
    odd_out = cols.lanes_at(cols.odd_at, loop + 2, "sgm_left_odd_out")
    lu = []
    for i, four in enumerate(fours):
        _, choose = minimum(four + [late_q[i]], bits)
        best = choose(beats[i])
        with m.If(write[i]):
            m.d.sync += [state[i].eq((pair[i] + best)[:bits]),
                         state_plus[i].eq((pair_plus[i] + best)[:bits])]
        # ... and the odd column's among four + C(x'), outside it.
        _, choose = minimum(four, bits)
        odd = (costs[loop + 2][i] + choose(beats[i]))[:bits]
        lu.append(register(m, Mux(odd_out[i], odd, state[i]), bits, f"sgm_left_lu{i}"))
    return lu


def _last_position(m, value, valid, name):
    """``value`` of the last slot with a position (``valid`` set), a clock later: what the
    loop over two positions keeps of x - 1 across the gaps before x."""
    return register(m, value, len(value), name, valid)
