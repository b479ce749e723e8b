"""The fifth SGM path's recursion in hardware: the left path's lane update over a row fed
right to left.

docs/semantics.md ("The fifth path") defines the fifth path as the left path of the
mirrored row, so its hardware is :func:`.sgm_left.left_path` unchanged, fed the row's
positions in mirrored order: the caller gives, slot after slot, the costs of column
x = W - 1 - x' on the tag's column x', and P2 from |I(x) - I(x + 1)|. The left path keys
everything it keeps (its files, its fresh start) on the tag's column and writes only in
slots that carry a position, so the order of the columns is the only thing that changes.

This is the recursion alone (docs/hardware.md, "The fifth path"): the row buffer that
turns a row around, the sum with the four raster-order paths and the back end in mirrored
order are not built yet, and ``hdl.plan.check_buildable`` refuses ``fifth_path``.
"""

from amaranth.hdl import Module, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .common import SlotClock, bits_for, register, tag_layout, taps
from .plan_timing import sgm_timing
from .sgm import SemiGlobalAggregation, _lanes
from .sgm_left import left_path

__all__ = ["RightPathRecursion"]


class RightPathRecursion(wiring.Component):
    """L of the fifth path per lane for a row streamed in mirrored column order.

    Parameters
    ----------
    params : StereoParams
        With ``aggregation="sgm"``, width and height (any R that divides D).

    Attributes
    ----------
    costs : In(ArrayLayout(unsigned(cost_bits), D/R))
        C(W - 1 - x', j*D/R + i) on lane i in round j, for the tag's mirrored column x'.
    p2 : In(unsigned(bitlen(P2)))
        P2 of the fifth path at that column (slot-aligned with ``costs``).
    tag : In(tag_layout)
        The position in mirrored coordinates (x' = W - 1 - x), slot-aligned at the input.
    first, round : In
        Slot timing at the input.
    lanes : Out(ArrayLayout(unsigned(left_cost_bits), D/R))
        L_right(W - 1 - x', j*D/R + i) on lane i, ``latency`` clocks after the input.
    centre : Out(tag_layout)
        The tag of ``lanes``.
    """

    # The helpers the left path asks its owner for, shared with the SGM stage rather than
    # written again: the valid flag and slot-aligned delays of the tag's values.
    _valid_at = SemiGlobalAggregation._valid_at
    _aligned = SemiGlobalAggregation._aligned

    def __init__(self, params):
        self.params = params
        self.timing = sgm_timing(params)
        self.latency = self.timing.left
        super().__init__({
            "costs": In(data.ArrayLayout(unsigned(params.cost_bits), params.per_round)),
            "p2": In(bits_for(params.p2)),
            "tag": In(tag_layout(params)),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "lanes": Out(data.ArrayLayout(unsigned(params.left_cost_bits),
                                          params.per_round)),
            "centre": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p, t = self.params, self.timing
        m = Module()
        self._slots = slots = SlotClock(m, self.first, self.round, p.rounds, "sgm_right")
        self._valid = {}
        units = p.per_round
        costs = self.costs.as_value()
        # As deep as the SGM stage's taps need for the left path alone.
        self._costs = [_lanes(word, units, p.cost_bits) for word in
                       taps(m, costs, max(t.loop + t.left_stages - 1, t.left_picks[-2] + 1),
                            "sgm_right_cost")]
        # Fresh start at the mirrored row's first column, and P2, slot-aligned at
        # ``timing.guide`` as the SGM stage gives them to the left path.
        flag = register(m, self.tag.x == 0, 1, "sgm_right_fresh")
        fresh = taps(m, flag, t.guide - 1, "sgm_right_fresh")[-1]
        p2 = self._aligned(self.p2, 0, t.guide, "sgm_right_p2")
        lanes = left_path(self, m, fresh, p2)
        for i, value in enumerate(lanes):
            m.d.comb += self.lanes[i].eq(value)
        m.d.comb += self.centre.eq(slots.delay(self.tag, 0, self.latency, "sgm_right_centre"))
        return m
