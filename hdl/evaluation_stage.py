"""Evaluation stage: WTA across the R partition results of a position.

Hardware counterpart of :func:`npstereo.golden.wta.evaluate_partitions`: the partitions
arrive one per round; a running winner takes a later partition's (cost, disparity) only if
the pair is smaller, compared as one number with the cost in the high bits, so equal costs
keep the lower disparity whichever round it came from (the partitions are strided, see
:mod:`npstereo.golden.wta`). The result is the global argmin with ties to the lowest
disparity.
"""

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import SlotClock, bits_for, tag_layout

__all__ = ["EvaluationStage"]


def _better(candidate, best):
    """A partition's (cost, disparity) replaces the running winner only if smaller."""
    return candidate < best


class EvaluationStage(wiring.Component):
    """Running WTA over the rounds of one position.

    Attributes
    ----------
    cost, disparity : In
        The partition winner of the round, one per clock.
    first, round : In
        Slot timing at the input.
    tag : In(tag_layout)
        The position, slot-aligned at the input.
    disparity_out : Out
        The winner over all rounds, slot-aligned at ``latency``.
    tag_out : Out(tag_layout)
        ``tag`` at ``latency``.
    latency : int
        R: the winner is latched in the last round's clock.
    """

    def __init__(self, params):
        self.params = params
        self.latency = params.rounds
        super().__init__({
            "cost": In(params.aggregated_cost_bits),
            "disparity": In(bits_for(params.disparities - 1)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "tag": In(tag_layout(params)),
            "disparity_out": Out(bits_for(params.disparities - 1)),
            "tag_out": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p = self.params
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "evaluation")
        candidate = Cat(self.disparity, self.cost)
        best = Signal.like(candidate, name="best", reset_less=True)
        running = Mux(slots.first(0) | _better(candidate, best), candidate, best)
        m.d.sync += best.eq(running)
        final = Signal.like(self.disparity, name="final", reset_less=True)
        with m.If(slots.first(p.rounds - 1) if p.rounds > 1 else 1):
            m.d.sync += final.eq(running[:len(self.disparity)])
        m.d.comb += [self.disparity_out.eq(final),
                     self.tag_out.eq(slots.delay(self.tag, 0, p.rounds, "evaluated_tag"))]
        return m
