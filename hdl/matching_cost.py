"""Matching cost in hardware: the cost of one left/right pair of transformed pixels.

Mirrors :mod:`npstereo.golden.matching_cost` (Eq. 3, 5, 9): ``_absolute_cost`` (rank and
extended rank: |TL - TR|), ``_popcount_cost`` (census: popcount of TL xor TR) and
``_sad_cost`` (ext. census: sum over the bytes of |TL_n - TR_n|), looked up by transform
name. Masking of pairs outside the image (cost 0) is the caller's business, as in the
golden model where it happens outside these functions.
"""

from amaranth.hdl import Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from ..params import check_transform_table
from .common import absolute_difference, delay
from .plan_structure import cost_plan
from .trees import DEFAULT_EVERY, build_popcount, build_sad

__all__ = ["MatchingCost"]


def _absolute_cost(unit, m):
    if unit.latency == 2:
        # Wide transforms: a - b and b - a registered (the borrow of the first says
        # which one is |a - b|), the choice a clock later.
        width = len(unit.left)
        forward, backward = unit.left - unit.right, unit.right - unit.left
        forward, backward = (delay(m, unit.en, forward, 1, "rank_forward"),
                             delay(m, unit.en, backward, 1, "rank_backward"))
        return delay(m, unit.en, Mux(forward[width], backward[:width], forward[:width]),
                     1, "rank_cost")
    return delay(m, unit.en, absolute_difference(unit.left, unit.right), unit.latency,
                 "rank_cost")


def _popcount_cost(unit, m):
    # A named signal: slicing a bare expression would copy the whole wide XOR into
    # every one of the k bit selects, which makes elaboration quadratic in k.
    differing = Signal(unit.params.neighbours)
    m.d.comb += differing.eq(unit.left ^ unit.right)
    bits = [differing[n] for n in range(unit.params.neighbours)]
    # One LUT level in front of the compressors, far shorter than an adder level: not
    # counted against the register spacing.
    return build_popcount(m, unit.en, bits, unit.plan)


def _sad_cost(unit, m):
    pairs = [(unit.left.word_select(n, 8), unit.right.word_select(n, 8))
             for n in range(unit.params.neighbours)]
    return build_sad(m, unit.en, pairs, unit.plan,
                     unit.params.lut_inputs)[:unit.params.cost_bits]


#: The cost's logic by transform name: ``cost(unit, m)`` builds it into ``m`` from the
#: :class:`MatchingCost` ``unit``'s inputs and register plan, and returns the cost.
_COSTS = check_transform_table({"rank": _absolute_cost, "census": _popcount_cost,
                                "ext-rank": _absolute_cost, "ext-census": _sad_cost},
                               "hdl.matching_cost._COSTS")


class MatchingCost(wiring.Component):
    """Cost of the transformed pair (``left``, ``right``), one pair per ``en``-high clock.

    Parameters
    ----------
    params : StereoParams
        Transform and block size (for the widths).
    every : int
        Register spacing in levels of logic (see :mod:`.trees`); 0 for a combinational
        cost (latency 0).

    Attributes
    ----------
    left, right : In(unsigned(params.transform_bits))
    en : In(1)
        Advances the pipeline registers.
    cost : Out(unsigned(params.cost_bits))
    latency : int
        Register stages between (``left``, ``right``) and ``cost``.
    """

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params = params
        #: Register plan (:func:`~.plan_structure.cost_plan`): where the registers go.
        self.plan = cost_plan(params, every)
        self.latency = sum(self.plan)
        super().__init__({
            "left": In(unsigned(params.transform_bits)),
            "right": In(unsigned(params.transform_bits)),
            "en": In(1),
            "cost": Out(unsigned(params.cost_bits)),
        })

    def elaborate(self, platform):
        m = Module()
        m.d.comb += self.cost.eq(_COSTS[self.params.transform](self, m))
        return m
