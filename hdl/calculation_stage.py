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
- Vertical aggregation keeps the previous A-1 rows' costs of every (column, round) in a
  :class:`~amaranth.lib.memory.Memory` (read-modify-write); horizontal aggregation adds
  the sums of the A-1 previous positions from delay lines of R clocks each. Rows and
  columns outside the frame are masked from the tags, not from memory contents.
- WTA per partition: :class:`~.trees.MinTree`, ties to the lowest disparity.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import bits_for, delay, tag_layout
from .matching_cost import MatchingCost
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
        ``(position_latency, round_latency)``: whole positions from the window to the
        cost units' inputs, then clocks to the outputs of the same round.
    """

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params, self.every = params, every
        self.transform_left = Transform(params, every)
        self.transform_right = Transform(params, every)
        self.cost_units = [MatchingCost(params, every) for _ in range(params.per_round)]
        self.min_tree = MinTree(params.per_round, params.aggregated_cost_bits, every)
        a, rounds = params.agg_radius, params.rounds
        #: Positions from the window to the position register (transform, then the register).
        self.position_latency = self.transform_left.latency + 1
        #: Clocks from the position register to the outputs of the same round: costs,
        #: vertical (memory read), horizontal (a positions and a register), minimum tree.
        self.round_latency = (self.cost_units[0].latency + (4 if a else 0)
                              + (a * rounds + 1 if a else 0) + self.min_tree.latency)
        #: The output tag is the centre of the aggregation window, a rows and a columns
        #: behind the newest costs.
        self.latency = (self.position_latency, self.round_latency)
        window = data.ArrayLayout(unsigned(8), params.block * params.block)
        super().__init__({
            "window_left": In(window), "window_right": In(window),
            "tag_in": In(tag_layout(params)),
            "en": In(1),
            "round": In(bits_for(rounds - 1)),
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

        # Matching costs of the round's disparities.
        costs = []
        for i, unit in enumerate(self.cost_units):
            m.submodules[f"cost{i}"] = unit
            m.d.comb += [unit.left.eq(left), unit.right.eq(ring[i]), unit.en.eq(self.en)]
        cost_tag = delay(m, self.en, round_tag, self.cost_units[0].latency, "cost_tag")
        inside = (cost_tag.live & (cost_tag.y >= 0) & (cost_tag.y < p.height))
        for i, unit in enumerate(self.cost_units):
            disparity = cost_tag.round * per_round + i
            costs.append(Mux(inside & (cost_tag.x >= disparity), unit.cost, 0))

        vertical, vertical_tag = self._vertical(m, costs, cost_tag)
        summed, summed_tag = self._horizontal(m, vertical, vertical_tag)

        # WTA of the partition; costs and tag wait for the tree.
        m.submodules.min_tree = tree = self.min_tree
        m.d.comb += [tree.en.eq(self.en)] + [tree.values[i].eq(summed[i])
                                             for i in range(per_round)]
        out_tag = delay(m, self.en, summed_tag, tree.latency, "wta_tag")
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

    def _vertical(self, m, costs, tag):
        """Column sums over rows y - 2a .. y, reported for the centre row y - a."""
        p = self.params
        a = p.agg_radius
        if a == 0:
            return costs, tag
        rows, bits, per_round = 2 * a, p.cost_bits, p.per_round
        m.submodules.cost_lines = lines = Memory(
            shape=unsigned(rows * per_round * bits), depth=p.width * p.rounds, init=[])
        rd = lines.read_port(domain="sync")
        wr = lines.write_port()
        # Four registers, for the clock: the address (it fans out to every block RAM of
        # the buffer), the block RAM's read register, its data again (the RAM's
        # clock-to-output alone is a third of a cycle), and the column sums, so that
        # neither the RAM nor the adders reach into the horizontal sum. The write-back
        # lands two clocks after the read; the same address is read again only a row
        # (W * R clocks > 2) later, so no read can see a stale word.
        address = delay(m, self.en, tag.x * p.rounds + tag.round, 1, "cost_lines_address")
        m.d.comb += [rd.addr.eq(address), rd.en.eq(self.en)]
        read = delay(m, self.en, rd.data, 1, "cost_lines_data")
        held = [delay(m, self.en, c, 3, f"vertical_in{i}") for i, c in enumerate(costs)]
        held_tag = delay(m, self.en, tag, 3, "vertical_tag")

        def stored(row, i):  # row 0 = the row above held_tag.y
            start = (row * per_round + i) * bits
            return read[start:start + bits]

        sums = []
        for i in range(per_round):
            total = held[i]
            for row in range(rows):
                total = total + Mux(held_tag.y - 1 - row >= 0, stored(row, i), 0)
            sums.append(total)
        m.d.comb += [
            wr.addr.eq(delay(m, self.en, address, 2, "cost_lines_write_address")),
            wr.en.eq(self.en),
            wr.data.eq(Cat(*held, *[stored(row, i) for row in range(rows - 1)
                                    for i in range(per_round)])),
        ]
        registered = [Signal(len(total), name=f"vertical{i}") for i, total in enumerate(sums)]
        out_tag = Signal(tag_layout(p))
        with m.If(self.en):
            m.d.sync += [r.eq(total) for r, total in zip(registered, sums)]
            m.d.sync += [out_tag.eq(held_tag), out_tag.y.eq(held_tag.y - a)]
        sums = registered
        return sums, out_tag

    def _horizontal(self, m, vertical, tag):
        """Row sums over the positions x - 2a .. x, reported (registered) for x - a."""
        p = self.params
        a, rounds = p.agg_radius, p.rounds
        if a == 0:
            return vertical, tag
        taps = [Cat(*vertical)]
        for k in range(1, 2 * a + 1):
            taps.append(delay(m, self.en, taps[-1], rounds, f"row_tap{k}"))
        centre = delay(m, self.en, tag, a * rounds, "row_centre")
        bits = len(vertical[0])
        sums = [Signal(p.aggregated_cost_bits, name=f"aggregated{i}")
                for i in range(p.per_round)]
        out_tag = Signal(tag_layout(p))
        terms = [[] for _ in range(p.per_round)]
        for k, tap in enumerate(taps):
            offset = a - k  # tap k holds the column x_centre + offset
            inside = (centre.x >= -offset) if offset < 0 else (centre.x <= p.width - 1 - offset)
            for i in range(p.per_round):
                terms[i].append(Mux(inside, tap[bits * i:bits * (i + 1)], 0))
        with m.If(self.en):
            m.d.sync += [s.eq(sum(t)) for s, t in zip(sums, terms)]
            m.d.sync += out_tag.eq(centre)
        return sums, out_tag
