"""Evaluation stage: WTA across the R partition results of a position.

Hardware counterpart of :func:`npstereo.golden.wta.evaluate_partitions`: the partitions
arrive in increasing order, one per round, and a running winner keeps the earlier one on a
tie (strict ``<``), so the result is the global argmin with ties to the lowest disparity.
"""

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import better, bits_for, tag_layout

__all__ = ["EvaluationStage"]


class EvaluationStage(wiring.Component):
    """Running WTA over the rounds of one position.

    Attributes
    ----------
    en : In(1)
    cost, disparity : In
        The partition winner of ``tag.round``.
    tag : In(tag_layout)
    disparity_out : Out
        Winner over rounds 0 .. tag.round; final when ``done``.
    done : Out(1)
        This clock carries the last round (combinational from ``tag``).
    latency : int
        0: the final winner is available in the clock of the last round.
    """

    latency = 0

    def __init__(self, params):
        self.params = params
        super().__init__({
            "en": In(1),
            "cost": In(params.aggregated_cost_bits),
            "disparity": In(bits_for(params.disparities - 1)),
            "tag": In(tag_layout(params)),
            "disparity_out": Out(bits_for(params.disparities - 1)),
            "done": Out(1),
        })

    def elaborate(self, platform):
        m = Module()
        best_cost = Signal.like(self.cost)
        best_disparity = Signal.like(self.disparity)
        # A later partition replaces the running winner only if strictly better.
        take = (self.tag.round == 0) | better(self.cost, best_cost)
        cost = Mux(take, self.cost, best_cost)
        disparity = Mux(take, self.disparity, best_disparity)
        with m.If(self.en):
            m.d.sync += [best_cost.eq(cost), best_disparity.eq(disparity)]
        m.d.comb += [self.disparity_out.eq(disparity),
                     self.done.eq(self.tag.round == self.params.rounds - 1)]
        return m
