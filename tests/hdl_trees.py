"""The pipelined trees of ``hdl/trees.py`` as components of their own, for the unit tests.

The core builds its trees into its stages' modules with the ``trees.build_*`` functions;
these wrap the same functions with ports, so that ``tests/test_hdl_units.py`` can stream
values through one tree and compare it with Python's sum, popcount and minimum.
"""

from amaranth.hdl import Const, Module, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from npstereo.hdl.trees import (DEFAULT_EVERY, build_min_tree, build_popcount, build_sum,
                                build_tree, min_tree_latency, popcount_plan, register_plan,
                                select_min)


class AdderTree(wiring.Component):
    """Sum of ``count`` unsigned values of ``width`` bits.

    Parameters
    ----------
    count, width : int
        Number and width of the summands.
    every : int
        Register stage after every ``every`` adder levels; 0 for a combinational tree.

    Attributes
    ----------
    inputs : In(ArrayLayout(unsigned(width), count))
    en : In(1)
        Advances the register stages.
    sum : Out(unsigned)
        Wide enough for ``count * (2**width - 1)``.
    latency : int
        Register stages between ``inputs`` and ``sum``.
    """

    def __init__(self, count, width, every=DEFAULT_EVERY):
        self.count, self.width = count, width
        self.plan = register_plan(count, every)
        self.latency = sum(self.plan)
        super().__init__({
            "inputs": In(data.ArrayLayout(unsigned(width), count)),
            "en": In(1),
            "sum": Out(unsigned((count * (2 ** width - 1)).bit_length())),
        })

    def elaborate(self, platform):
        m = Module()
        values = [self.inputs[i] for i in range(self.count)]
        m.d.comb += self.sum.eq(build_sum(m, self.en, values, self.plan))
        return m


class PopCount(wiring.Component):
    """Number of ones in a ``width``-bit vector (full adders, then an adder tree).

    Parameters
    ----------
    width : int
        Input width.
    every : int
        Register spacing in levels; the compressor level counts as one.

    Attributes
    ----------
    bits : In(width)
    en : In(1)
    count : Out(unsigned(bitlen(width)))
    latency : int
    """

    def __init__(self, width, every=DEFAULT_EVERY):
        self.width_in = width
        self.plan = popcount_plan(width, every)
        self.latency = sum(self.plan)
        super().__init__({
            "bits": In(width),
            "en": In(1),
            "count": Out(unsigned(width.bit_length())),
        })

    def elaborate(self, platform):
        m = Module()
        bits = [self.bits[i] for i in range(self.width_in)]
        m.d.comb += self.count.eq(build_popcount(m, self.en, bits, self.plan))
        return m


class MinTree(wiring.Component):
    """Minimum of ``count`` values and the index of the minimum, ties to the lowest index.

    Each node compares a lower-index and an upper-index candidate and keeps the upper one
    only if it is strictly smaller, so equal minima resolve to the lowest index exactly as
    a strict ``<`` scan in increasing order does (the golden WTA rule).

    Parameters
    ----------
    count, width : int
        Number and width of the values.
    every : int
        Register stage after every ``every`` comparator levels; 0 for combinational.
    split : bool
        Instead: every level in two clocks (:func:`build_min_tree`), as the core's.

    Attributes
    ----------
    values : In(ArrayLayout(unsigned(width), count))
    en : In(1)
    min : Out(unsigned(width))
    index : Out(unsigned(max(1, bitlen(count - 1))))
    latency : int
    """

    def __init__(self, count, width, every=DEFAULT_EVERY, split=False):
        self.count, self.width, self.split = count, width, split
        self.plan = register_plan(count, every)
        self.latency = min_tree_latency(count) if split else sum(self.plan)
        super().__init__({
            "values": In(data.ArrayLayout(unsigned(width), count)),
            "en": In(1),
            "min": Out(unsigned(width)),
            "index": Out(unsigned(max(1, (count - 1).bit_length()))),
        })

    def elaborate(self, platform):
        m = Module()
        index_shape = self.index.shape()
        leaves = [(self.values[i], Const(i, index_shape)) for i in range(self.count)]
        if self.split:
            value, index = build_min_tree(m, self.en, leaves)
        else:
            value, index = build_tree(m, self.en, leaves, select_min, self.plan)
        m.d.comb += [self.min.eq(value), self.index.eq(index)]
        return m
