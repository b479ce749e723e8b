"""Transformation in hardware: the four non-parametric transforms of one B x B window.

Mirrors :mod:`npstereo.golden.transform` (Eq. 1, 2, 4, 6, 7, 8): :func:`xi` and
:func:`~.common.absolute_difference` are the per-neighbour primitives, :class:`Rank`, :class:`Census`,
:class:`ExtRank` and :class:`ExtCensus` the transforms, :class:`Transform` picks one from the
parameters. The window arrives already masked (pixels outside the frame are 0), row-major:
pixel (dy, dx) is element (dy + r) * B + (dx + r); neighbours are numbered in the same
raster order without the centre, as in the golden model.

Census and rank can instead take the window unmasked with a ``keep`` flag per pixel
(``mask_after``): a neighbour outside the frame is 0, and 0 < centre is centre != 0, so
the comparison's bit is chosen after it (the A windows of a column then share one
window of pixels, see :func:`~.plan_structure.masks_after_compare`).

Each component computes one window per ``en``-high clock; pipeline registers (see
:mod:`.trees`) advance only while ``en`` is high, and ``latency`` counts them.
"""

from amaranth.hdl import Cat, Module, Mux, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..params import TRANSFORM_SPECS, check_transform_table
from .common import absolute_difference, delay
from .plan_structure import census_registers_compared, transform_plan
from .trees import DEFAULT_EVERY, build_popcount, build_sad

__all__ = ["xi", "Rank", "Census", "ExtRank", "ExtCensus", "Transform"]


def xi(centre, neighbour):
    """Eq. 1: 1 iff the centre is strictly brighter than the neighbour.

    Written as ``neighbour < centre`` on purpose: yosys maps ``<`` to the bare borrow of a
    carry chain (4 CCU2C on ECP5) but ``>`` to a chain plus an equality tree (4 CCU2C and
    14 LUT4 per 8-bit compare).
    """
    return neighbour < centre


def _check_mask_after(params, mask_after):
    if mask_after and not params.spec.compares:
        comparing = [name for name, spec in TRANSFORM_SPECS.items() if spec.compares]
        raise ValueError(f"mask_after is for the transforms of comparisons "
                         f"({', '.join(comparing)}), not {params.transform}")


class _WindowTransform(wiring.Component):
    """Common signature and window unpacking of the four transforms.

    Parameters
    ----------
    params : StereoParams
        Block size and transform (for the value width).
    every : int
        Register spacing in levels of logic (see :mod:`.trees`); 0 builds the transform
        combinationally (latency 0).
    copies : int
        Copies of the centre pixel the caller gives in ``centres`` (registers of their
        own, see :func:`~.plan_structure.centre_copies`); neighbour n is compared with copy
        n * copies // k. With 1 the centre is taken from the window.
    mask_after : bool
        Census and rank only: the window arrives unmasked, with ``keep``.

    Attributes
    ----------
    window : In(ArrayLayout(unsigned(8), B * B))
    centres : In(ArrayLayout(unsigned(8), copies))
        Only with ``copies`` > 1.
    keep : In(B * B)
        Only with ``mask_after``: bit i is 1 where window pixel i lies inside the frame.
    en : In(1)
    value : Out(unsigned(params.transform_bits))
    latency : int
    """

    def __init__(self, params, every=DEFAULT_EVERY, copies=1, mask_after=False):
        _check_mask_after(params, mask_after)
        self.params, self.every = params, every
        self.copies, self.mask_after = copies, mask_after
        #: Register plan (:func:`~.plan_structure.transform_plan`): where the registers go.
        self.plan = transform_plan(params, every, mask_after)
        self.latency = sum(self.plan)
        members = {"window": In(data.ArrayLayout(unsigned(8), params.block * params.block))}
        if copies > 1:
            members["centres"] = In(data.ArrayLayout(unsigned(8), copies))
        if mask_after:
            members["keep"] = In(params.block * params.block)
        super().__init__({**members, "en": In(1),
                          "value": Out(unsigned(params.transform_bits))})

    @property
    def _centre_index(self):
        """Index of the centre pixel in ``window`` (and in ``keep``)."""
        return self.params.radius * self.params.block + self.params.radius

    def _neighbour_indices(self):
        """Window indices of the k neighbours, in order."""
        return [i for i in range(self.params.block ** 2) if i != self._centre_index]

    def _centres_and_neighbours(self):
        """Per neighbour (in order) the centre copy it is compared with, and the
        neighbours."""
        k = self.params.neighbours
        neighbours = [self.window[i] for i in self._neighbour_indices()]
        if self.copies == 1:
            return [self.window[self._centre_index]] * k, neighbours
        return [self.centres[n * self.copies // k] for n in range(k)], neighbours

    def _compared(self, m, centres, neighbours, registered=False):
        """Eq. 1 of every neighbour, with ``mask_after`` the bit of a neighbour outside
        the frame (a 0 pixel) chosen after the comparison; ``registered``: after the
        comparisons' register, which then also holds the flags and each centre copy's
        centre != 0."""
        bits = [xi(c, p) for c, p in zip(centres, neighbours)]
        if not self.mask_after:
            return bits
        bits, k = Cat(bits), self.params.neighbours
        keeps = Cat(self.keep[i] for i in self._neighbour_indices())
        copies = ([self.window[self._centre_index]] if self.copies == 1 else
                  [self.centres[j] for j in range(self.copies)])
        nonzero = Cat(c != 0 for c in copies)
        if registered:
            bits = delay(m, self.en, bits, 1, "census_compared")
            keeps = delay(m, self.en, keeps, 1, "census_keep")
            nonzero = delay(m, self.en, nonzero, 1, "census_nonzero")
        return [Mux(keeps[n], bits[n], nonzero[n * len(copies) // k]) for n in range(k)]

    def elaborate(self, platform):
        m = Module()
        centres, neighbours = self._centres_and_neighbours()
        m.d.comb += self.value.eq(self._value(m, centres, neighbours))
        return m


class Rank(_WindowTransform):
    """Eq. 2: number of neighbours darker than the centre (compares, then a popcount)."""

    def _value(self, m, centres, neighbours):
        compared = Cat(self._compared(m, centres, neighbours))
        if self.plan[0]:
            compared = delay(m, self.en, compared, 1, "rank_compared")
        return build_popcount(m, self.en, [compared[n] for n in range(len(neighbours))],
                              self.plan[1:])


class Census(_WindowTransform):
    """Eq. 4: bit n is the comparison with neighbour n (then the output register)."""

    def _value(self, m, centres, neighbours):
        registered = census_registers_compared(self.params, self.every, self.mask_after)
        return delay(m, self.en, Cat(self._compared(m, centres, neighbours, registered)),
                     self.latency - registered, "census")


class ExtRank(_WindowTransform):
    """Eq. 7: sum of |P - P'| over the neighbours (differences, then an adder tree)."""

    def _value(self, m, centres, neighbours):
        total = build_sad(m, self.en, list(zip(centres, neighbours)), self.plan,
                          self.params.lut_inputs)
        return total[:self.params.transform_bits]


class ExtCensus(_WindowTransform):
    """Eq. 8: byte n (bits 8n+7..8n) is |P - P'_n| (then the output register)."""

    def _value(self, m, centres, neighbours):
        return delay(m, self.en, Cat(absolute_difference(c, p)
                                     for c, p in zip(centres, neighbours)),
                     self.latency, "ext_census")


#: The components of the transforms by transform name.
_TRANSFORMS = check_transform_table(
    {"rank": Rank, "census": Census, "ext-rank": ExtRank, "ext-census": ExtCensus},
    "hdl.transform._TRANSFORMS")


class Transform(wiring.Component):
    """The transform ``params.transform`` of one window per ``en``-high clock.

    Same members as the per-transform components (``window``, ``centres``, ``keep``,
    ``en``, ``value``, ``latency``), which it instantiates as its only submodule.

    Parameters
    ----------
    params : StereoParams
    every : int
        Register spacing in levels of logic; 0 for a combinational transform.
    """

    def __new__(cls, params, every=DEFAULT_EVERY, copies=1, mask_after=False):
        # Refused before the object exists (a component that raises in __init__ is
        # garbage Amaranth reports as created but never used), as the core does.
        _check_mask_after(params, mask_after)
        return super().__new__(cls, src_loc_at=1)

    def __init__(self, params, every=DEFAULT_EVERY, copies=1, mask_after=False):
        self.params = params
        self.impl = _TRANSFORMS[params.transform](params, every, copies, mask_after)
        self.latency = self.impl.latency
        super().__init__(self.impl.signature)

    def elaborate(self, platform):
        m = Module()
        m.submodules.transform = self.impl
        m.d.comb += [
            self.impl.window.eq(self.window),
            self.impl.en.eq(self.en),
            self.value.eq(self.impl.value),
        ]
        if self.impl.copies > 1:
            m.d.comb += self.impl.centres.eq(self.centres)
        if self.impl.mask_after:
            m.d.comb += self.impl.keep.eq(self.keep)
        return m
