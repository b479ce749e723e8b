"""Aggregation in hardware: the A x A box sum of matching costs (the paper's 3 x 3).

Hardware counterpart of :func:`npstereo.golden.aggregation.aggregate`. Costs arrive one
(position, round) per ``en``-high clock, positions in raster order and R rounds each, the
D/R costs of the round's disparities side by side.

- Vertical: a :class:`~amaranth.lib.memory.Memory` of depth W*R holds the previous A-1
  rows' costs of every (column, round), read-modify-write every clock; the column sum
  covers rows y - 2a .. y and is reported for the centre row y - a.
- Horizontal: delay lines of R clocks hold the column sums of the 2a previous positions;
  the row sum covers columns x - 2a .. x and is reported for the centre column x - a.

Positions outside the image contribute 0, as in the golden model: rows above the frame and
columns beyond its left and right edges are masked from the tags, never from what the
memory or the delay lines held before (stale contents of a previous frame or of a reset in
mid-frame). Rows below the frame arrive with costs 0 from the caller.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import column_inside, delay, tag_layout
from .plan import aggregation_latency

__all__ = ["Aggregation"]


def _row_inside(y, above):
    """The stored row ``above`` + 1 rows above row ``y`` lies inside the frame."""
    return y - 1 - above >= 0


class Aggregation(wiring.Component):
    """A x A sums of one (position, round) per ``en``-high clock.

    Parameters
    ----------
    params : StereoParams
        Its ``width`` sizes the cost line buffer (W * R words) and bounds the columns.

    Attributes
    ----------
    costs : In(ArrayLayout(unsigned(cost_bits), D/R))
        C(x, y, tag_in.round * D/R + i), 0 where the caller's masks say so (x - d < 0,
        rows below the frame).
    tag_in : In(tag_layout)
        Position and round of ``costs``.
    en : In(1)
    sums : Out(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(x, y, tag.round * D/R + i).
    tag : Out(tag_layout)
        The position of ``sums``: the centre of the window whose newest costs entered
        ``latency`` clocks earlier, a rows and a columns behind them
        (:func:`~.plan.aggregation_offset`).
    latency : int
        Register stages from ``costs`` to ``sums`` (:func:`~.plan.aggregation_latency`);
        0 for A = 1, where ``sums`` and ``tag`` are the inputs.
    """

    def __init__(self, params):
        self.params = params
        self.latency = aggregation_latency(params)
        super().__init__({
            "costs": In(data.ArrayLayout(unsigned(params.cost_bits), params.per_round)),
            "tag_in": In(tag_layout(params)),
            "en": In(1),
            "sums": Out(data.ArrayLayout(unsigned(params.aggregated_cost_bits),
                                         params.per_round)),
            "tag": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        m = Module()
        costs = [self.costs[i] for i in range(self.params.per_round)]
        if self.params.agg_radius == 0:
            m.d.comb += [self.tag.eq(self.tag_in)]
            m.d.comb += [self.sums[i].eq(c) for i, c in enumerate(costs)]
            return m
        vertical, vertical_tag = self._vertical(m, costs, self.tag_in)
        summed, summed_tag = self._horizontal(m, vertical, vertical_tag)
        m.d.comb += [self.tag.eq(summed_tag)]
        m.d.comb += [self.sums[i].eq(s) for i, s in enumerate(summed)]
        return m

    def _vertical(self, m, costs, tag):
        """Column sums over rows y - 2a .. y, reported for the centre row y - a."""
        p = self.params
        a = p.agg_radius
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
                total = total + Mux(_row_inside(held_tag.y, row), stored(row, i), 0)
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
        return registered, out_tag

    def _horizontal(self, m, vertical, tag):
        """Row sums over the positions x - 2a .. x, reported (registered) for x - a."""
        p = self.params
        a, rounds = p.agg_radius, p.rounds
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
            inside = column_inside(centre.x, a - k, p.width)  # tap k: column x_centre + a - k
            for i in range(p.per_round):
                terms[i].append(Mux(inside, tap[bits * i:bits * (i + 1)], 0))
        with m.If(self.en):
            m.d.sync += [s.eq(sum(t)) for s, t in zip(sums, terms)]
            m.d.sync += out_tag.eq(centre)
        return sums, out_tag
