"""Matching cost in hardware: the cost of one left/right pair of transformed pixels.

Mirrors :mod:`npstereo.golden.matching_cost` (Eq. 3, 5, 9): ``_rank_cost`` (rank and
extended rank: |TL - TR|), ``_census_cost`` (popcount of TL xor TR) and ``_ext_census_cost``
(sum over the bytes of |TL_n - TR_n|). Masking of pairs outside the image (cost 0) is the
caller's business, as in the golden model where it happens outside these functions.
"""

from amaranth.hdl import Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .common import absolute_difference, delay
from .plan import cost_plan
from .trees import DEFAULT_EVERY, build_popcount, build_sad

__all__ = ["MatchingCost"]


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
        #: Register plan (:func:`~.plan.cost_plan`): where the registers go.
        self.plan = cost_plan(params, every)
        self.latency = sum(self.plan)
        self._cost = {"rank": self._rank_cost, "ext-rank": self._rank_cost,
                      "census": self._census_cost,
                      "ext-census": self._ext_census_cost}[params.transform]
        super().__init__({
            "left": In(unsigned(params.transform_bits)),
            "right": In(unsigned(params.transform_bits)),
            "en": In(1),
            "cost": Out(unsigned(params.cost_bits)),
        })

    def _rank_cost(self, m):
        if self.latency == 2:
            # Wide transforms: a - b and b - a registered (the borrow of the first says
            # which one is |a - b|), the choice a clock later.
            width = len(self.left)
            forward, backward = self.left - self.right, self.right - self.left
            forward, backward = (delay(m, self.en, forward, 1, "rank_forward"),
                                 delay(m, self.en, backward, 1, "rank_backward"))
            return delay(m, self.en, Mux(forward[width], backward[:width], forward[:width]),
                         1, "rank_cost")
        return delay(m, self.en, absolute_difference(self.left, self.right), self.latency,
                     "rank_cost")

    def _census_cost(self, m):
        # A named signal: slicing a bare expression would copy the whole wide XOR into
        # every one of the k bit selects, which makes elaboration quadratic in k.
        differing = Signal(self.params.neighbours)
        m.d.comb += differing.eq(self.left ^ self.right)
        bits = [differing[n] for n in range(self.params.neighbours)]
        # One LUT level in front of the compressors, far shorter than an adder level: not
        # counted against the register spacing.
        return build_popcount(m, self.en, bits, self.plan)

    def _ext_census_cost(self, m):
        pairs = [(self.left.word_select(n, 8), self.right.word_select(n, 8))
                 for n in range(self.params.neighbours)]
        return build_sad(m, self.en, pairs, self.plan,
                         self.params.lut_inputs)[:self.params.cost_bits]

    def elaborate(self, platform):
        m = Module()
        m.d.comb += self.cost.eq(self._cost(m))
        return m
