"""Calculation stage: transforms, matching costs, aggregation and WTA per partition.

Hardware counterpart of :mod:`npstereo.golden.transform`, :mod:`~npstereo.golden.matching_cost`,
:mod:`~npstereo.golden.aggregation` and :func:`npstereo.golden.wta.wta_partition`, in that
order. Each position takes R clocks (rounds); round j evaluates disparities
j*D/R .. (j+1)*D/R - 1 on the same D/R matching-cost units.

- One left and one right :class:`~.transform.Transform` per position.
- The right transforms of the last D positions sit in a ring of registers. Between rounds
  the ring rotates by D/R, so cost unit i always reads ring slot i (no R:1 multiplexers);
  the last round rotates by D/R - 1 and inserts the new right transform.
- Costs are 0 where x - d < 0 or the position lies outside the frame.
- :class:`~.aggregation.Aggregation` sums them over A x A positions.
- WTA per partition: :class:`~.trees.MinTree`, ties to the lowest disparity.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .aggregation import Aggregation
from .common import bits_for, delay, tag_layout
from .matching_cost import MatchingCost
from .plan import calculation_latency
from .transform import Transform
from .trees import DEFAULT_EVERY, MinTree

__all__ = ["CalculationStage"]


class CalculationStage(wiring.Component):
    """Aggregated costs and the partition winner of one (position, round) per clock.

    Parameters
    ----------
    params : StereoParams
    every : int
        Register spacing of the transform, cost and minimum trees (see :mod:`.trees`).

    Attributes
    ----------
    window_left, window_right : In(ArrayLayout(unsigned(8), B * B))
        From the input stage; change only with a position-advancing ``en``.
    tag_in : In(tag_layout)
        Centre of those windows.
    en : In(1)
        One clock of the pipeline (one round).
    round : In(range(R))
        Round of this clock; the input stage advances on ``en`` in round R-1.
    costs : Out(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(x, y, round * D/R + i) for unit i.
    best_cost, best_disparity : Out
        The partition's winner.
    tag : Out(tag_layout)
        Position (centre of the aggregation window) and round of the outputs.
    latency : (int, int)
        ``(positions, clocks)`` (:func:`~.plan.calculation_latency`): whole positions from
        the window to the cost units' inputs, then clocks to the outputs of the same round.
    """

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params = params
        self.transform_left = Transform(params, every)
        self.transform_right = Transform(params, every)
        self.cost_units = [MatchingCost(params, every) for _ in range(params.per_round)]
        self.aggregation = Aggregation(params)
        self.min_tree = MinTree(params.per_round, params.aggregated_cost_bits, every)
        self.latency = calculation_latency(params, every)
        window = data.ArrayLayout(unsigned(8), params.block * params.block)
        super().__init__({
            "window_left": In(window), "window_right": In(window),
            "tag_in": In(tag_layout(params)),
            "en": In(1),
            "round": In(bits_for(params.rounds - 1)),
            "costs": Out(data.ArrayLayout(unsigned(params.aggregated_cost_bits),
                                          params.per_round)),
            "best_cost": Out(params.aggregated_cost_bits),
            "best_disparity": Out(bits_for(params.disparities - 1)),
            "tag": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p = self.params
        m = Module()
        rounds, per_round, depth = p.rounds, p.per_round, p.disparities
        advance = self.en & (self.round == rounds - 1)

        # Transforms advance once per position.
        m.submodules.transform_left = tl = self.transform_left
        m.submodules.transform_right = tr = self.transform_right
        m.d.comb += [tl.window.eq(self.window_left), tr.window.eq(self.window_right),
                     tl.en.eq(advance), tr.en.eq(advance)]
        transformed_tag = delay(m, advance, self.tag_in, tl.latency, "transform_tag")

        # Position register and right-transform ring (slot k = TR of the position k back).
        left = Signal(p.transform_bits)
        ring = [Signal(p.transform_bits, name=f"ring{k}") for k in range(depth)]
        position = Signal(tag_layout(p))
        with m.If(advance):
            m.d.sync += [left.eq(tl.value), position.eq(transformed_tag),
                         ring[0].eq(tr.value)]
            m.d.sync += [ring[k].eq(ring[(k + per_round - 1) % depth])
                         for k in range(1, depth)]
        with m.Elif(self.en):
            m.d.sync += [ring[k].eq(ring[(k + per_round) % depth]) for k in range(depth)]
        round_tag = Signal(tag_layout(p))
        m.d.comb += [round_tag.eq(position), round_tag.round.eq(self.round)]

        # Matching costs of the round's disparities, then their A x A sums.
        for i, unit in enumerate(self.cost_units):
            m.submodules[f"cost{i}"] = unit
            m.d.comb += [unit.left.eq(left), unit.right.eq(ring[i]), unit.en.eq(self.en)]
        cost_tag = delay(m, self.en, round_tag, self.cost_units[0].latency, "cost_tag")
        inside = (cost_tag.live & (cost_tag.y >= 0) & (cost_tag.y < p.height))
        m.submodules.aggregation = aggregation = self.aggregation
        m.d.comb += [aggregation.en.eq(self.en), aggregation.tag_in.eq(cost_tag)]
        for i, unit in enumerate(self.cost_units):
            disparity = cost_tag.round * per_round + i
            m.d.comb += aggregation.costs[i].eq(
                Mux(inside & (cost_tag.x >= disparity), unit.cost, 0))
        summed = [aggregation.sums[i] for i in range(per_round)]

        # WTA of the partition; costs and tag wait for the tree.
        m.submodules.min_tree = tree = self.min_tree
        m.d.comb += [tree.en.eq(self.en)] + [tree.values[i].eq(summed[i])
                                             for i in range(per_round)]
        out_tag = delay(m, self.en, aggregation.tag, tree.latency, "wta_tag")
        out_costs = delay(m, self.en, Cat(*summed), tree.latency, "wta_costs")
        bits = p.aggregated_cost_bits
        m.d.comb += [
            self.tag.eq(out_tag),
            self.best_cost.eq(tree.min),
            self.best_disparity.eq(out_tag.round * per_round + tree.index),
        ]
        m.d.comb += [self.costs[i].eq(out_costs[bits * i:bits * (i + 1)])
                     for i in range(per_round)]
        return m
