"""Left/right consistency check and the invalid border (output word of each position).

Hardware counterpart of :class:`npstereo.golden.wta.RightWTA`,
:func:`npstereo.golden.lr_check.lr_check` and :func:`~npstereo.golden.lr_check.invalidate_border`.

The right-referenced winner dR(xr) collects the costs S(xr + d, d) of the positions
xr .. xr + D - 1, so it is final D - 1 positions after xr. A ring of D (cost, disparity)
slots, slot k for the right pixel k positions back, takes each round's candidates
(strict ``<`` in increasing d, only for xr = x - d >= 0 in the same row); at every
position the ring shifts and the slot leaving it is a final dR, kept in a history of the
last D. The left winners wait D + 1 positions in a delay line, then meet dR(x - dL) in
that history.

The result is registered once more before it leaves (``clock_latency``): the partner
lookup is a D:1 multiplexer and the consistency test a subtraction and a comparison,
which together with the output word's register were the longest path of the whole core
(rank 7x7, D = 100 on ECP5: 20.5 ns, 13 logic levels).
"""

from amaranth.hdl import Array, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .common import absolute_difference, better, bits_for, tag_layout
from .plan import LR_CLOCK_LATENCY, lr_latency

__all__ = ["LRCheck"]


def _consistent(difference, threshold):
    """The consistency test: |dL - dR| <= T keeps the pixel, as in the golden model's
    :func:`~npstereo.golden.lr_check.lr_check`."""
    return difference <= threshold


class LRCheck(wiring.Component):
    """Valid flag and disparity of one position per ``produce``.

    Attributes
    ----------
    en : In(1)
    costs : In(ArrayLayout(unsigned(aggregated_cost_bits), D/R))
        S(x, y, tag.round * D/R + i), from the calculation stage.
    tag : In(tag_layout)
    disparity, done : In
        From the evaluation stage: dL of ``tag``'s position when ``done``.
    produce : Out(1)
        This clock carries a result for an in-frame position (combinational).
    valid, disparity_out, x, y : Out
        The result and its position.
    latency : int
        Positions from the evaluation stage's result to ``produce``: D + 1 with the check,
        0 without (:func:`~.plan.lr_latency`), ...
    clock_latency : int
        ... and then 1 clock, the output register stage (:data:`~.plan.LR_CLOCK_LATENCY`).
    """

    clock_latency = LR_CLOCK_LATENCY

    def __init__(self, params):
        self.params = params
        self.latency = lr_latency(params)
        d_bits = bits_for(params.disparities - 1)
        layout = tag_layout(params)
        super().__init__({
            "en": In(1),
            "costs": In(data.ArrayLayout(unsigned(params.aggregated_cost_bits),
                                         params.per_round)),
            "tag": In(layout),
            "disparity": In(d_bits),
            "done": In(1),
            "produce": Out(1),
            "valid": Out(1),
            "disparity_out": Out(d_bits),
            "x": Out(layout["x"].shape),
            "y": Out(layout["y"].shape),
        })

    def _report(self, m, tag, disparity, ready, keep=None):
        """Outputs from (tag, disparity), registered; ``keep`` takes the registered values.

        ``ready``: this clock holds the final result of ``tag``'s position.
        """
        p = self.params
        staged_tag = Signal.like(tag, name="staged_tag")
        staged_disparity = Signal.like(disparity, name="staged_disparity")
        staged_produce = Signal(name="staged_produce")
        inside = tag.live & (tag.y >= 0) & (tag.y < p.height)
        with m.If(self.en):
            m.d.sync += [staged_tag.eq(tag), staged_disparity.eq(disparity),
                         staged_produce.eq(ready & inside)]
        kept = 1 if keep is None else keep(staged_tag, staged_disparity)
        m.d.comb += [
            self.produce.eq(staged_produce),
            self.valid.eq(kept & (staged_tag.x >= p.first_valid_column)),
            self.disparity_out.eq(staged_disparity),
            self.x.eq(staged_tag.x), self.y.eq(staged_tag.y),
        ]

    def elaborate(self, platform):
        p = self.params
        m = Module()
        if not p.lr_check:
            self._report(m, self.tag, self.disparity, self.done)
            return m

        depth, per_round = p.disparities, p.per_round
        cost_bits, d_bits = p.aggregated_cost_bits, bits_for(depth - 1)
        slot_layout = data.StructLayout({"cost": unsigned(cost_bits), "d": unsigned(d_bits)})
        slots = [Signal(slot_layout, name=f"right_slot{k}") for k in range(depth)]
        final = [Signal(d_bits, name=f"right_final{k}") for k in range(depth)]
        first_round = self.tag.round == 0

        def candidate(k, base):
            """Slot k's value after the candidate d = k of this round (if xr >= 0)."""
            cost = self.costs[k % per_round]
            # Candidates come in increasing d: ties keep the lowest.
            take = (self.tag.x >= k) & better(cost, base.cost)
            return [slots[k].cost.eq(Mux(take, cost, base.cost)),
                    slots[k].d.eq(Mux(take, k, base.d))]

        with m.If(self.en & first_round):
            # New position: shift; slot 0 (xr = x) starts with d = 0, always in the row.
            m.d.sync += [slots[0].cost.eq(self.costs[0]), slots[0].d.eq(0)]
            for k in range(1, depth):
                m.d.sync += (candidate(k, slots[k - 1]) if k < per_round
                             else [slots[k].eq(slots[k - 1])])
            m.d.sync += [final[0].eq(slots[depth - 1].d)]
            m.d.sync += [final[k].eq(final[k - 1]) for k in range(1, depth)]
        for j in range(1, p.rounds):
            with m.If(self.en & (self.tag.round == j)):
                for k in range(j * per_round, (j + 1) * per_round):
                    m.d.sync += candidate(k, slots[k])

        # Left winners wait until dR of every possible partner is final: after the ring
        # shift of position x + D, final[m] holds dR(x - m).
        entry_layout = data.StructLayout({"tag": tag_layout(p), "d": unsigned(d_bits)})
        waiting = [Signal(entry_layout, name=f"left_wait{k}") for k in range(depth + 1)]
        with m.If(self.en & self.done):
            m.d.sync += [waiting[0].tag.eq(self.tag), waiting[0].d.eq(self.disparity)]
            m.d.sync += [waiting[k].eq(waiting[k - 1]) for k in range(1, depth + 1)]
        entry = waiting[depth]
        # Padded to every index value so that the multiplexer is a complete case.
        partner = Array(final + final[-1:] * (2 ** d_bits - depth))[entry.d]
        staged_partner = Signal(d_bits)
        with m.If(self.en):
            m.d.sync += staged_partner.eq(partner)

        def keep(tag, d):
            difference = absolute_difference(d, staged_partner)
            return (tag.x >= d) & _consistent(difference, p.lr_threshold)

        self._report(m, entry.tag, entry.d, first_round, keep)
        return m
