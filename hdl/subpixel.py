"""Sub-pixel disparity in hardware: the winner's neighbours through the WTA, and the fit.

Hardware counterpart of :mod:`npstereo.golden.subpixel` (docs/semantics.md, "Sub-pixel
disparity"); built only with F = ``params.subpixel_bits`` > 0.

**Neighbours.** The partition's minimum tree carries (S(d), i, S(d-1), S(d+1)) per unit
instead of (S(d), i) (:func:`partition_leaves`), the evaluation stage the same four
across the rounds, so the winner leaves the WTA with both neighbours. Inside a round they
are the adjacent units' sums; across a round's edge (unit 0's d - 1, the last unit's
d + 1) they are the previous and the next clock's: the leaves are taken a clock late
(:func:`~.plan_timing.neighbour_clocks`), so that the next round's unit 0 is there. A
neighbour across a position's edge (round 0's d - 1, round R-1's d + 1) belongs to another
position, but d is then 0 or D - 1, where the fraction is 0 and no neighbour is used.

**Fit** (:class:`SubpixelFit`). With a = S(d-1) - S(d), b = S(d+1) - S(d), the quotient
q = floor((a 2^(F+1) + a + b) / (2 (a + b))) of 0 .. 2^F comes from a restoring divider
of F + 1 stages, a compare-subtract and a register each (no division or wide arithmetic
in one clock: the core aims at 150 MHz on ECP5), and the value is d 2^F - 2^(F-1) + q,
or d 2^F at d = 0 and D - 1.
"""

from amaranth.hdl import Const, Module, Mux, Signal, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import bits_for, pipe
from .plan_timing import subpixel_clocks

__all__ = ["partition_leaves", "round_neighbours", "numerator", "SubpixelFit"]


def round_neighbours(m, current, sums):
    """S of the previous round's last unit and of the next round's unit 0, beside the
    leaves ``current`` (``sums`` a clock late): the last unit a clock later still, unit 0
    of ``sums`` itself."""
    return pipe(m, current[len(current) - 1], 1, "neighbour_before"), sums[0]


def partition_leaves(m, sums, index_shape, params):
    """The partition tree's leaves (S(d), i, S(d-1), S(d+1)) of the units' ``sums``."""
    units = len(sums)
    if params.rounds == 1:
        # All D disparities in one clock: the outer neighbours are never used.
        current = [sums[i] for i in range(units)]
        none = Const(0, len(current[0]))
        before, after = none, none
    else:
        current = pipe(m, sums, 1, "neighbour_sums")
        current = [current[i] for i in range(units)]
        before, after = round_neighbours(m, current, sums)
    return [(current[i], Const(i, index_shape),
             current[i - 1] if i else before,
             current[i + 1] if i + 1 < units else after) for i in range(units)]


def numerator(a, denominator, bits):
    """a 2^(F+1) + (a + b): the quotient by 2 (a + b) is (a - b) 2^F / (2 (a + b)) + 1/2
    + 2^(F-1), so the added a + b is the rounding half up."""
    return (a << (bits + 1)) + denominator


class SubpixelFit(wiring.Component):
    """The value d 2^F + offset of a winner and its summed costs, ``latency`` clocks later.

    A pipeline of registers without enable: a slot-aligned input (constant for its slot's
    R clocks) gives a slot-aligned output.

    Attributes
    ----------
    disparity : In
        The winner d (whole levels).
    before, centre, after : In
        S(d-1), S(d), S(d+1).
    disparity_out : Out
        d, ``latency`` clocks later (the L/R check's level).
    value : Out(output_disparity_bits)
        The output disparity, scaled by 2^F.
    latency : int
        :func:`~.plan_timing.subpixel_clocks`.
    """

    def __init__(self, params):
        self.params = params
        self.latency = subpixel_clocks(params)
        cost = params.aggregated_cost_bits
        d_bits = bits_for(params.disparities - 1)
        super().__init__({
            "disparity": In(d_bits),
            "before": In(cost), "centre": In(cost), "after": In(cost),
            "disparity_out": Out(d_bits),
            "value": Out(params.output_disparity_bits),
        })

    def elaborate(self, platform):
        p = self.params
        bits, cost = p.subpixel_bits, p.aggregated_cost_bits
        out_bits = p.output_disparity_bits
        m = Module()
        # Clock 1: the differences (a >= 1, b >= 0 for a true minimum), the edge, the value
        # at the edges and the base d 2^F - 2^(F-1) of the others.
        a, b = Signal(cost, name="fit_a"), Signal(cost, name="fit_b")
        edge = Signal(name="fit_edge")
        whole = Signal(out_bits, name="fit_whole")
        base = Signal(out_bits, name="fit_base")
        d = self.disparity
        m.d.sync += [a.eq(self.before - self.centre), b.eq(self.after - self.centre),
                     edge.eq((d == 0) | (d == p.disparities - 1)),
                     whole.eq(d << bits), base.eq((d << bits) - (1 << (bits - 1)))]
        # Clock 2: a + b; clock 3: the numerator (one adder per clock).
        denominator = Signal(cost + 1, name="fit_denominator")
        a2 = Signal(cost, name="fit_a2")
        m.d.sync += [denominator.eq(a + b), a2.eq(a)]
        wide = cost + bits + 2
        remainder = Signal(wide, name="fit_numerator")
        divisor = Signal(cost + 1, name="fit_divisor")
        m.d.sync += [remainder.eq(numerator(a2, denominator, bits)), divisor.eq(denominator)]
        side = pipe(m, Mux(edge, whole, base), 2, "fit_side")
        at_edge = pipe(m, edge, 2, "fit_at_edge")
        quotient = Const(0, bits + 1)
        # Clocks 4 .. F + 4: quotient bit k = F .. 0, a compare-subtract of 2 (a + b) 2^k.
        for k in range(bits, -1, -1):
            trial = Signal(signed(wide + 1), name=f"fit_trial{k}")
            m.d.comb += trial.eq(remainder - (divisor << (k + 1)))
            fits = ~trial[-1]
            next_remainder = Signal(wide, name=f"fit_remainder{k}")
            next_quotient = Signal(bits + 1, name=f"fit_quotient{k}")
            m.d.sync += [next_remainder.eq(Mux(fits, trial[:wide], remainder)),
                         next_quotient.eq(quotient | (fits << k))]
            remainder, quotient = next_remainder, next_quotient
            divisor = pipe(m, divisor, 1, f"fit_divisor{k}")
            side, at_edge = pipe(m, side, 1, f"fit_side{k}"), pipe(m, at_edge, 1,
                                                                   f"fit_at_edge{k}")
        # Clock F + 5: the value.
        value = Signal(unsigned(out_bits), name="fit_value")
        m.d.sync += value.eq(Mux(at_edge, side, side + quotient))
        m.d.comb += [self.value.eq(value),
                     self.disparity_out.eq(pipe(m, d, self.latency, "fit_disparity"))]
        return m
