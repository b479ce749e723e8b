"""Evaluation stage: WTA across the R partition results of a position.

Hardware counterpart of :func:`npstereo.golden.wta.evaluate_partitions`: the partitions
arrive in increasing order, one per round. After round R-1 the R winners stand in a shift
register, and a minimum tree over them (:func:`~.trees.build_min_tree`, ties to the lower
leaf, i.e. to the earlier partition) gives the global argmin with ties to the lowest
disparity. A running winner would be a loop of one clock (a comparison of wide costs and
the multiplexers it drives: 7.8 ns for census 9x9 on ECP5); the tree has a register after
every comparison and every choice.
"""

from amaranth.hdl import Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import SlotClock, better, bits_for, pipe, tag_layout
from .plan_timing import evaluation_latency
from .trees import build_min_tree

__all__ = ["EvaluationStage"]


class EvaluationStage(wiring.Component):
    """WTA over the rounds of one position.

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
        :func:`~.plan_timing.evaluation_latency`: the last round, the tree, the winner's register.
    """

    def __init__(self, params):
        self.params = params
        self.latency = evaluation_latency(params)
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
        rounds = p.rounds
        # Round j's winner, R-1-j clocks old when round R-1's arrives.
        leaves = [pipe(m, self.cost, rounds - 1 - j, f"partition_cost{j}")
                  for j in range(rounds)]
        disparities = [pipe(m, self.disparity, rounds - 1 - j, f"partition_disparity{j}")
                       for j in range(rounds)]
        _, best = build_min_tree(m, 1, list(zip(leaves, disparities)), name="rounds",
                                 compare=better)
        final = Signal.like(self.disparity, name="final", reset_less=True)
        # The tree's result for this position, a clock after it leaves the tree.
        with m.If(slots.first(self.latency - 1) if rounds > 1 else 1):
            m.d.sync += final.eq(best)
        m.d.comb += [self.disparity_out.eq(final),
                     self.tag_out.eq(slots.delay(self.tag, 0, self.latency, "evaluated_tag"))]
        return m
