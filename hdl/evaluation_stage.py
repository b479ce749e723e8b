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
    before, after : In
        With F > 0 (:mod:`.subpixel`): the partition winner's S(d-1), S(d+1).
    disparity_out : Out
        The winner over all rounds, slot-aligned at ``latency``.
    cost_out, before_out, after_out : Out
        With F > 0: its S(d), S(d-1), S(d+1), with it.
    tag_out : Out(tag_layout)
        ``tag`` at ``latency``.
    latency : int
        :func:`~.plan_timing.evaluation_latency`: the last round, the tree, the winner's register.
    """

    def __init__(self, params):
        self.params = params
        self.latency = evaluation_latency(params)
        cost = params.aggregated_cost_bits
        neighbours = ({"before": In(cost), "after": In(cost), "cost_out": Out(cost),
                       "before_out": Out(cost), "after_out": Out(cost)}
                      if params.subpixel_bits else {})
        super().__init__({**neighbours,
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
        # Each leaf: cost, disparity and with F > 0 the neighbours S(d-1), S(d+1).
        fields = {"cost": self.cost, "disparity": self.disparity}
        if p.subpixel_bits:
            fields.update(before=self.before, after=self.after)
        columns = [[pipe(m, field, rounds - 1 - j, f"partition_{name}{j}")
                    for j in range(rounds)] for name, field in fields.items()]
        leaves = list(zip(*columns))
        best = dict(zip(fields, build_min_tree(m, 1, leaves, name="rounds", compare=better)))
        # The cost leaves with the winner only for the fit.
        kept = [name for name in fields if name != "cost" or p.subpixel_bits]
        finals = {name: Signal.like(fields[name], reset_less=True,
                                    name="final" if name == "disparity" else f"final_{name}")
                  for name in kept}
        # The tree's result for this position, a clock after it leaves the tree.
        with m.If(slots.first(self.latency - 1) if rounds > 1 else 1):
            m.d.sync += [finals[name].eq(best[name]) for name in kept]
        if p.subpixel_bits:
            m.d.comb += [self.cost_out.eq(finals["cost"]), self.before_out.eq(finals["before"]),
                         self.after_out.eq(finals["after"])]
        m.d.comb += [self.disparity_out.eq(finals["disparity"]),
                     self.tag_out.eq(slots.delay(self.tag, 0, self.latency, "evaluated_tag"))]
        return m
