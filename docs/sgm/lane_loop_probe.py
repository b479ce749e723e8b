"""Issue 27's second question: how fast can the left path's per-lane loop run on the ECP5?

Usage: ``python docs/sgm/lane_loop_probe.py --lanes 64 --bits 11 --style onehot --out DIR``
(one probe; ``--style`` one of STYLES), placed and routed on the ECP5-85k with
the project's own flow (npstereo.gen.flow, nextpnr-ecp5 at 150 MHz); prints the figures.

Once the large step's reference no longer needs the minimum of the previous position
(docs/sgm/left_path_study.py), what is left inside the loop of one position is, per lane d,

    Lu(x, d) = C(x, d) + min(Lu(x-1, d), Lu(x-1, d-1) + P1, Lu(x-1, d+1) + P1, Q(x)),

Q = ref + P2 a scalar known ahead (registered, one copy per 8 lanes), Lu kept modulo 2^n
(a < b is the sign of a - b). Lu + P1 is kept beside Lu (its own adder from C + P1), so the
loop is a minimum of four and an addition. Styles:

- ``tree``: two minima of two, then their minimum (three comparisons, two after each other);
- ``onehot``: the six comparisons side by side, a one-hot choice, then the addition;
- ``pipelined``: ``onehot`` with a register between the comparisons and the choice: the
  loop takes two clocks, as when Lu(x-1, .) is there two clocks ahead (R >= 3, or a step
  of two positions);
- ``presummed``: ``pipelined`` with the four sums C + candidate (and C + P1 + candidate)
  formed beside the comparisons and registered with the choice's one-hot selects, so
  that the second clock is only the choice;
- ``select``: ``presummed`` in one clock (carry-select): the comparisons and the sums
  C + candidate side by side from the registers, then only the one-hot choice, C + Q and
  C + P1 + Q formed a clock ahead per lane;
- ``pairs``: the loop of the left path whose steps into even columns only stay or take the
  large step (docs/sgm.md, "Two clocks at R = 1"): Lu(x) from Lu(x - 2) in two clocks
  with one position per clock, Lu(x) = S + min(Lu(x-2, d), Lu(x-2, d +- 1) + P1, Q(x-1),
  Q(x) - C(x-1, d)), S = C(x-1, d) + C(x, d): the five candidates' comparisons and their
  sums side by side, registered, then the one-hot choice; the sums of the two references
  formed ahead per lane, the reference's copies one per two lanes.

The costs enter through one pin and a shift chain, the result leaves through a registered
XOR tree, so the probe is self-contained and measures the loop, not its harness.
"""

import argparse
import json
import sys
from pathlib import Path

from amaranth.back import verilog
from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from npstereo.gen.flow.synthesise import synthesise

COST_BITS, P1, COPY_LANES = 6, 24, 8
STYLES = ("tree", "onehot", "pipelined", "presummed", "select", "pairs")


def _less(a, b, bits):
    """a < b modulo 2^bits, for values less than 2^(bits - 1) apart."""
    return (a - b)[bits - 1]


def _one_hot(m, candidates, bits, register, name):
    """Which of ``candidates`` is the minimum (ties to the first), one bit each, from all
    comparisons side by side; with ``register`` the comparisons are registered first."""
    beats = {}
    for i in range(len(candidates)):
        for j in range(i + 1, len(candidates)):
            beats[i, j] = _less(candidates[j], candidates[i], bits)     # j beats i
    if register:
        for key, value in list(beats.items()):
            beats[key] = Signal(name=f"{name}_b{key[0]}{key[1]}")
            m.d.sync += beats[key].eq(value)
    selects = []
    for i in range(len(candidates)):
        wins = 1
        for j in range(len(candidates)):
            if j != i:
                wins = wins & (~beats[i, j] if i < j else beats[j, i])
        selects.append(wins)
    return selects


def _chosen(selects, values):
    """The value whose one-hot select is set."""
    best = 0
    for select, value in zip(selects, values):
        best = best | Mux(select, value, 0)
    return best


def _registered(m, values, bits, name):
    held = [Signal(bits, name=f"{name}{i}") for i in range(len(values))]
    m.d.sync += [h.eq(v) for h, v in zip(held, values)]
    return held


class LaneLoop(wiring.Component):
    cost_in: In(COST_BITS)
    reference: In(32)
    result: Out(1)

    def __init__(self, lanes, bits, style):
        self.lanes, self.bits, self.style = lanes, bits, style
        super().__init__()

    def elaborate(self, platform):
        m, n, bits = Module(), self.lanes, self.bits
        costs = [Signal(COST_BITS, name=f"c{d}") for d in range(n)]
        m.d.sync += costs[0].eq(self.cost_in)
        m.d.sync += [costs[d].eq(costs[d - 1] ^ self.cost_in) for d in range(1, n)]
        pipelined = self.style in ("pipelined", "presummed")
        # C and C + P1 where the loop's addition is (a clock later when pipelined).
        late = [Signal(COST_BITS, name=f"cl{d}") for d in range(n)] if pipelined else costs
        plus = [Signal(bits, name=f"cp{d}") for d in range(n)]
        if pipelined:
            m.d.sync += [lc.eq(c) for lc, c in zip(late, costs)]
        m.d.sync += [p.eq(c + P1) for p, c in zip(plus, late)]
        # The copies are kept: identical registers would be merged back into one by
        # synthesis (the core's ``replica`` does the same).
        copies = [Signal(bits, name=f"q{g}", attrs={"keep": 1})
                  for g in range(-(-n // COPY_LANES))]
        m.d.sync += [q.eq(self.reference[:bits]) for q in copies]
        path = [Signal(bits, name=f"l{d}") for d in range(n)]
        path_p1 = [Signal(bits, name=f"lp{d}") for d in range(n)]
        if self.style == "pairs":
            # S = C(x-1) + C(x) and S + P1 per lane, and Q(x-1) one copy per two lanes.
            pair_sums = [Signal(bits, name=f"ps{d}") for d in range(n)]
            pair_sums_p1 = [Signal(bits, name=f"pp{d}") for d in range(n)]
            m.d.sync += [v.eq(c + late[d]) for d, (v, c) in enumerate(zip(pair_sums, costs))]
            m.d.sync += [v.eq(c + plus[d]) for d, (v, c) in enumerate(zip(pair_sums_p1, costs))]
            pair_copies = [Signal(bits, name=f"qq{g}", attrs={"keep": 1})
                           for g in range(-(-n // 2))]
            m.d.sync += [q.eq(self.reference[:bits]) for q in pair_copies]
        for d in range(n):
            candidates = [path[d], copies[d // COPY_LANES]]
            candidates += [path_p1[d - 1]] if d else []
            candidates += [path_p1[d + 1]] if d < n - 1 else []
            if self.style == "tree":
                def smaller(a, b):
                    return Mux(_less(b, a, bits), b, a)
                pairs = [smaller(*candidates[:2]), *(
                    [smaller(*candidates[2:])] if len(candidates) == 4 else candidates[2:])]
                best = pairs[0] if len(pairs) == 1 else smaller(*pairs)
            elif self.style == "select":
                # One clock: comparisons and sums side by side, then only the choice.
                # The reference's sums are formed a clock ahead (Q is known ahead).
                # (The probe's costs change every clock, so these registers have the
                # loop's timing, not its arithmetic.)
                q_sum = Signal(bits, name=f"qs{d}")
                q_sum_p1 = Signal(bits, name=f"qp{d}")
                m.d.sync += [q_sum.eq(self.reference[:bits] + costs[d]),
                             q_sum_p1.eq(self.reference[:bits] + P1 + costs[d])]
                selects = _one_hot(m, candidates, bits, False, f"min{d}")
                sums = [costs[d] + c for c in candidates]
                sums_p1 = [plus[d] + c for c in candidates]
                sums[1], sums_p1[1] = q_sum, q_sum_p1
                m.d.sync += [path[d].eq(_chosen(selects, sums)),
                             path_p1[d].eq(_chosen(selects, sums_p1))]
                continue
            elif self.style == "pairs":
                q_prev = pair_copies[d // 2]
                q_adj = Signal(bits, name=f"qa{d}")       # Q(x) - C(x-1, d), formed ahead
                m.d.sync += q_adj.eq(self.reference[:bits] - costs[d])
                candidates = [path[d], q_prev, q_adj]
                candidates += [path_p1[d - 1]] if d else []
                candidates += [path_p1[d + 1]] if d < n - 1 else []
                selects = _registered(m, _one_hot(m, candidates, bits, False, f"min{d}"), 1,
                                      f"sel{d}_")
                # Sums formed ahead for the references (their values are known ahead);
                # the probe's costs change every clock: timing, not arithmetic.
                ahead = [Signal(bits, name=f"qs{d}_{k}") for k in range(4)]
                m.d.sync += [ahead[0].eq(self.reference[:bits] + pair_sums[d]),
                             ahead[1].eq(self.reference[:bits] + pair_sums_p1[d]),
                             ahead[2].eq(self.reference[:bits] + costs[d]),
                             ahead[3].eq(self.reference[:bits] + plus[d])]
                loop_sums = [pair_sums[d] + c for c in candidates[3:]]
                loop_sums_p1 = [pair_sums_p1[d] + c for c in candidates[3:]]
                sums = _registered(m, [pair_sums[d] + path[d], ahead[0], ahead[2], *loop_sums],
                                   bits, f"s{d}_")
                sums_p1 = _registered(m, [pair_sums_p1[d] + path[d], ahead[1], ahead[3],
                                          *loop_sums_p1], bits, f"sp{d}_")
                m.d.sync += [path[d].eq(_chosen(selects, sums)),
                             path_p1[d].eq(_chosen(selects, sums_p1))]
                continue
            elif self.style == "presummed":
                selects = _registered(m, _one_hot(m, candidates, bits, False, f"min{d}"), 1,
                                      f"sel{d}_")
                sums = _registered(m, [costs[d] + c for c in candidates], bits, f"s{d}_")
                sums_p1 = _registered(m, [costs[d] + P1 + c for c in candidates], bits,
                                      f"sp{d}_")
                m.d.sync += [path[d].eq(_chosen(selects, sums)),
                             path_p1[d].eq(_chosen(selects, sums_p1))]
                continue
            else:
                selects = _one_hot(m, candidates, bits, pipelined, f"min{d}")
                if pipelined:
                    candidates = _registered(m, candidates, bits, f"h{d}_")
                best = _chosen(selects, candidates)
            m.d.sync += [path[d].eq(late[d] + best), path_p1[d].eq(plus[d] + best)]
        level = [s[i] for s in (*path, *path_p1) for i in range(bits)]
        depth = 0
        while len(level) > 1:
            folded = []
            for i in range(0, len(level), 4):
                bit = Signal(name=f"x{depth}_{i}")
                m.d.sync += bit.eq(Cat(*level[i:i + 4]).xor())
                folded.append(bit)
            level, depth = folded, depth + 1
        m.d.comb += self.result.eq(level[0])
        return m


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lanes", type=int, default=64)
    parser.add_argument("--bits", type=int, default=11)
    parser.add_argument("--style", choices=STYLES, default="onehot")
    parser.add_argument("--out", type=Path, required=True, help="build folder to keep")
    args = parser.parse_args(argv)
    text = verilog.convert(LaneLoop(args.lanes, args.bits, args.style), name="lane_loop",
                           emit_src=False)
    result = synthesise(text, "ecp5", "lane_loop", pnr=True, freq=150.0, keep=args.out)
    figures = {k: result.get(k) for k in ("status", "logic", "registers", "fmax_mhz",
                                          "logic_levels", "critical_path")}
    print(json.dumps(dict(lanes=args.lanes, bits=args.bits, style=args.style, **figures)))
    return 0 if result["status"] == "ok" else 1


if __name__ == "__main__":
    sys.exit(main())
