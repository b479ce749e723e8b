"""Transformation in hardware: the four non-parametric transforms of one B x B window.

Mirrors :mod:`npstereo.golden.transform` (Eq. 1, 2, 4, 6, 7, 8): :func:`xi` and
:func:`absolute_difference` are the per-neighbour primitives, :class:`Rank`, :class:`Census`,
:class:`ExtRank` and :class:`ExtCensus` the transforms, :class:`Transform` picks one from the
parameters. The window arrives already masked (pixels outside the frame are 0), row-major:
pixel (dy, dx) is element (dy + r) * B + (dx + r); neighbours are numbered in the same
raster order without the centre, as in the golden model.

Each component computes one window per ``en``-high clock; pipeline registers (see
:mod:`.trees`) advance only while ``en`` is high, and ``latency`` counts them.
"""

from amaranth.hdl import Cat, Module, Mux, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .trees import DEFAULT_EVERY, _add, build_popcount, build_tree, full_adder_compress, \
    popcount_plan, register_plan

__all__ = ["xi", "absolute_difference", "sad_leaves", "sad_plan", "build_sad", "Rank", "Census", "ExtRank", "ExtCensus", "Transform"]


def xi(centre, neighbour):
    """Eq. 1: 1 iff the centre is strictly brighter than the neighbour.

    Written as ``neighbour < centre`` on purpose: yosys maps ``<`` to the bare borrow of a
    carry chain (4 CCU2C on ECP5) but ``>`` to a chain plus an equality tree (4 CCU2C and
    14 LUT4 per 8-bit compare).
    """
    return neighbour < centre


def absolute_difference(a, b):
    """Eq. 6: |a - b| of two unsigned values, as wide as the wider operand.

    Both differences and a select: yosys shares the ``<`` with the borrow of one of the
    subtractors (8 CCU2C + 7 LUT4 for 8 bits on ECP5, the cheapest of the forms tried,
    including a conditional negation).
    """
    width = max(len(a), len(b))
    return Mux(b < a, (a - b)[:width], (b - a)[:width])


def sad_leaves(pairs):
    """The leaves of an adder tree whose sum is sum |a - b| over ``pairs``.

    |a - b| costs two subtractions and a multiplexer; with one subtraction d = a - b and
    its borrow s, |d| = (d xor s...s) + s, and the k increments are collected once: the
    leaves are the k conditionally inverted differences, then the borrows counted by full
    adders (2-bit leaves, placed last so that they are added among themselves first).
    """
    inverted, borrows = [], []
    for a, b in pairs:
        width = max(len(a), len(b))
        difference = a - b
        borrow = difference[width]
        inverted.append(difference[:width] ^ borrow.replicate(width))
        borrows.append(borrow)
    return inverted + full_adder_compress(borrows)


def sad_plan(count, every, depth=0, register_output=False):
    """:func:`register_plan` of the tree over :func:`sad_leaves` of ``count`` pairs."""
    return register_plan(count + (count + 2) // 3, every, depth + 1, register_output)


def build_sad(m, en, pairs, every, depth=0, register_output=False):
    """sum |a - b| over ``pairs``; latency ``sum(sad_plan(len(pairs), ...))``.

    The subtraction counts as one level against the register spacing, the inversion is
    merged into it.
    """
    plan = sad_plan(len(pairs), every, depth, register_output)
    return build_tree(m, en, [(leaf,) for leaf in sad_leaves(pairs)], _add, plan)[0]


class _WindowTransform(wiring.Component):
    """Common signature and window unpacking of the four transforms.

    Parameters
    ----------
    params : StereoParams
        Block size and transform (for the value width).
    every : int
        Register spacing in levels of logic (see :mod:`.trees`); 0 builds the transform
        combinationally (latency 0).

    Attributes
    ----------
    window : In(ArrayLayout(unsigned(8), B * B))
    en : In(1)
    value : Out(unsigned(params.transform_bits))
    latency : int
    """

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params, self.every = params, every
        self.latency = self._latency()
        super().__init__({
            "window": In(data.ArrayLayout(unsigned(8), params.block * params.block)),
            "en": In(1),
            "value": Out(unsigned(params.transform_bits)),
        })

    def _centre_and_neighbours(self):
        block, r = self.params.block, self.params.radius
        centre_index = r * block + r
        neighbours = [self.window[i] for i in range(block * block) if i != centre_index]
        return self.window[centre_index], neighbours

    def _single_stage_latency(self):
        # One level of logic (compare or |difference|), then the output register.
        return sum(register_plan(1, self.every, 1, self.every > 0))

    def _single_stage(self, m, value):
        plan = register_plan(1, self.every, 1, self.every > 0)
        return build_tree(m, self.en, [(value,)], None, plan)[0]

    def elaborate(self, platform):
        m = Module()
        centre, neighbours = self._centre_and_neighbours()
        m.d.comb += self.value.eq(self._value(m, centre, neighbours))
        return m


class Rank(_WindowTransform):
    """Eq. 2: number of neighbours darker than the centre (compares, then a popcount)."""

    def _latency(self):
        return sum(popcount_plan(self.params.neighbours, self.every, 1, self.every > 0))

    def _value(self, m, centre, neighbours):
        bits = [xi(centre, p) for p in neighbours]
        return build_popcount(m, self.en, bits, self.every, 1, self.every > 0)


class Census(_WindowTransform):
    """Eq. 4: bit n is the comparison with neighbour n."""

    def _latency(self):
        return self._single_stage_latency()

    def _value(self, m, centre, neighbours):
        return self._single_stage(m, Cat(xi(centre, p) for p in neighbours))


class ExtRank(_WindowTransform):
    """Eq. 7: sum of |P - P'| over the neighbours (differences, then an adder tree)."""

    def _latency(self):
        return sum(sad_plan(self.params.neighbours, self.every, 0, self.every > 0))

    def _value(self, m, centre, neighbours):
        return build_sad(m, self.en, [(centre, p) for p in neighbours], self.every, 0,
                         self.every > 0)[:self.params.transform_bits]


class ExtCensus(_WindowTransform):
    """Eq. 8: byte n (bits 8n+7..8n) is |P - P'_n|."""

    def _latency(self):
        return self._single_stage_latency()

    def _value(self, m, centre, neighbours):
        return self._single_stage(m, Cat(absolute_difference(centre, p) for p in neighbours))


_TRANSFORMS = {"rank": Rank, "census": Census, "ext-rank": ExtRank, "ext-census": ExtCensus}


class Transform(wiring.Component):
    """The transform ``params.transform`` of one window per ``en``-high clock.

    Same members as the per-transform components (``window``, ``en``, ``value``,
    ``latency``), which it instantiates as its only submodule.

    Parameters
    ----------
    params : StereoParams
    every : int
        Register spacing in levels of logic; 0 for a combinational transform.
    """

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params = params
        self.impl = _TRANSFORMS[params.transform](params, every)
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
        return m
