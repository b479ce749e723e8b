"""Evaluation stage: WTA across the R partition results of a position.

Hardware counterpart of :func:`npstereo.golden.wta.evaluate_partitions`: the partitions
arrive in increasing order, one per round, and a running winner keeps the earlier one on a
tie (strict ``<``), so the result is the global argmin with ties to the lowest disparity.
"""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import SlotClock, better, bits_for, tag_layout

__all__ = ["EvaluationStage"]


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
        best_cost = Signal.like(self.cost, name="best_cost", reset_less=True)
        best_disparity = Signal.like(self.disparity, name="best_disparity", reset_less=True)
        take = slots.first(0) | better(self.cost, best_cost)
        disparity = Mux(take, self.disparity, best_disparity)
        m.d.sync += [best_cost.eq(Mux(take, self.cost, best_cost)), best_disparity.eq(disparity)]
        final = Signal.like(self.disparity, name="final", reset_less=True)
        with m.If(slots.first(p.rounds - 1) if p.rounds > 1 else 1):
            m.d.sync += final.eq(disparity)
        m.d.comb += [self.disparity_out.eq(final),
                     self.tag_out.eq(slots.delay(self.tag, 0, p.rounds, "evaluated_tag"))]
        return m
