"""Pipelined reduction trees: adder tree, popcount, sum of absolute differences, minimum
with argmin, as functions that build them into a module.

A reduction of n values is a binary tree of ceil(log2 n) levels. To keep the clock rate flat
in the block size (the paper's 19 x 19 census popcounts 360 bits), a register stage sits
after every ``every`` levels of logic, so only the latency -- not the critical path -- grows
with log n. ``every = 0`` builds the tree purely combinationally for small cases.

Every register stage advances only while ``en`` is high, so a caller can stall the whole
pipeline (backpressure, or R > 1 rounds) without losing data: the value presented with the
i-th ``en``-high clock appears at the output after ``latency`` further ``en``-high clocks
(right after the ``latency``-th of them counting the one that took it in).

Levels that a caller spends before the tree (a comparator, an absolute difference) are
counted against the same spacing through ``depth``, so that a register stage never sits
behind more than ``every`` levels of logic.
"""

from amaranth.hdl import Cat, Const, Mux, Signal, Value

from .common import better

__all__ = ["DEFAULT_EVERY", "PAIRED_ADDER_BITS", "tree_levels", "register_plan", "popcount_plan",
           "build_tree", "build_sum", "build_popcount", "sad_leaves", "sad_plan", "build_sad",
           "compress_three", "sad_leaf_count",
           "select_min", "min_tree_latency", "build_min_tree", "full_adder_compress"]

#: Register stage after every 2 levels: two short ripple adders (ECP5 CCU2C chains) plus
#: routing fit the 6.67 ns of 150 MHz; nextpnr places the 19 x 19 census cost at 177 MHz
#: and the 19 x 19 rank transform at 186 MHz (docs/hdl_units.md).
DEFAULT_EVERY = 2


def tree_levels(count):
    """Levels of a binary tree over ``count`` leaves: ceil(log2(count))."""
    return max(0, (count - 1).bit_length())


#: Widest adder that may follow another adder in one clock: two carry chains of 12 bits
#: and more in a row were 7.3 ns on ECP5 (ext. rank 7x7's sum of differences).
PAIRED_ADDER_BITS = 11


def register_plan(count, every, depth=0, register_output=False, leaf_width=None):
    """Which tree levels end in a register stage.

    Parameters
    ----------
    count : int
        Number of leaves.
    every : int
        Register spacing in levels of logic; 0 for none.
    depth : int
        Levels of logic in front of the leaves, counted against the spacing.
    register_output : bool
        Also register the root if the spacing did not already.
    leaf_width : int or None
        Width of the leaves of an adder tree (level t then adds (leaf_width + t)-bit
        sums): a level wider than :data:`PAIRED_ADDER_BITS` gets a clock of its own.

    Returns
    -------
    list of bool
        Entry t (t = 0 for the leaves, up to ``tree_levels(count)``) is True where the
        values after level t are registered. ``sum()`` of it is the latency.
    """
    levels = tree_levels(count)
    plan = [False] * (levels + 1)
    if every > 0:
        run = depth                 # levels of logic since the last register
        for t in range(levels + 1):
            run += t > 0
            wide_next = (leaf_width is not None and t < levels
                         and leaf_width + t + 1 > PAIRED_ADDER_BITS)
            if run > 0 and (run >= every or wide_next):
                plan[t], run = True, 0
    if register_output:
        plan[-1] = True
    return plan


def _register(m, en, items, level):
    """Registers for every value of every item, loaded while ``en`` is high."""
    out = []
    for i, item in enumerate(items):
        # No reset: pipeline registers are never trusted without their valid tag.
        regs = tuple(Signal(Value.cast(v).shape(), name=f"l{level}_{i}_{j}", reset_less=True)
                     for j, v in enumerate(item))
        with m.If(en):
            m.d.sync += [r.eq(v) for r, v in zip(regs, item)]
        out.append(regs)
    return out


def build_tree(m, en, leaves, combine, plan):
    """Reduce ``leaves`` pairwise with ``combine``, inserting registers as ``plan`` says.

    Parameters
    ----------
    m : Module
        Where the logic goes.
    en : Value
        Register enable.
    leaves : list of tuple of Value
        The items; an item is a tuple so that a value can travel with its index.
    combine : callable
        ``combine(lower, upper)`` of two items (``lower`` covers the lower leaf indices)
        returns their reduced item.
    plan : list of bool
        From :func:`register_plan` for ``len(leaves)`` leaves.

    Returns
    -------
    tuple of Value
        The root item.
    """
    items = [tuple(item) for item in leaves]
    assert len(plan) == tree_levels(len(items)) + 1
    for level, registered in enumerate(plan):
        if level > 0:
            # An odd item out passes through to the next level unchanged.
            items = [combine(items[i], items[i + 1]) if i + 1 < len(items) else items[i]
                     for i in range(0, len(items), 2)]
        if registered:
            items = _register(m, en, items, level)
    assert len(items) == 1
    return items[0]


def _add(lower, upper):
    # Amaranth widens a + b by one bit: widths grow with the level, not full width everywhere.
    return (lower[0] + upper[0],)


def full_adder_compress(bits):
    """Popcount's first level: 3:2 compressors (full adders) as plain LUT logic.

    A sum of 1-bit values written as ``+`` would become a carry chain per pair; a full
    adder is two 3-input functions, i.e. two LUT4s, and turns 3 bits into one 2-bit count.

    Parameters
    ----------
    bits : list of Value
        1-bit values.

    Returns
    -------
    list of Value
        2-bit partial counts (the last one 1 bit wide if a single bit was left), whose sum
        is the number of ones in ``bits``.
    """
    counts = []
    for i in range(0, len(bits), 3):
        group = bits[i:i + 3]
        if len(group) == 3:
            a, b, c = group
            counts.append(Cat(a ^ b ^ c, (a & b) | (a & c) | (b & c)))
        elif len(group) == 2:
            a, b = group
            counts.append(Cat(a ^ b, a & b))
        else:
            counts.append(group[0])
    return counts


def popcount_plan(width, every, depth=0, register_output=False):
    """:func:`register_plan` of a popcount over ``width`` bits (one compressor level first,
    then 2-bit counts)."""
    return register_plan((width + 2) // 3, every, depth + 1, register_output, 2)


def build_popcount(m, en, bits, plan):
    """Number of ones in ``bits``: full adders, then an adder tree of growing width.

    ``plan`` comes from :func:`popcount_plan` for ``len(bits)`` bits; its sum is the latency.
    """
    return build_tree(m, en, [(c,) for c in full_adder_compress(list(bits))], _add, plan)[0]


def sad_leaves(pairs, lut_inputs=4):
    """The leaves of an adder tree whose sum is sum |a - b| over ``pairs``.

    |a - b| costs two subtractions and a multiplexer; with one subtraction d = a - b and
    its borrow s, |d| = (d xor s...s) + s, and the k increments are collected once: the
    leaves are the k conditionally inverted differences, then the borrows counted by full
    adders (2-bit leaves, placed last so that they are added among themselves first).
    On Cyclone V this is 12 % fewer ALUTs than k absolute differences (ext. census 9x9
    cost: 2,593 against 2,940).

    With ``lut_inputs`` 6 the inverted differences go three at a time into 3:2
    compressors (:func:`compress_three`): each output bit is a function of three bits and
    three borrows, one 6-input LUT that also does the inversion, and three leaves become
    two. A sum of 360 pairs on Cyclone V: 8,877 ALUTs against 11,295 (48 pairs: 1,175
    against 1,496). On 4-input LUTs the same logic is larger (48 pairs: 1,928 LUT4 on
    ECP5 against 1,560), hence the parameter.
    """
    inverted, borrows = [], []
    for a, b in pairs:
        width = max(len(a), len(b))
        difference = a - b
        borrow = difference[width]
        inverted.append(difference[:width] ^ borrow.replicate(width))
        borrows.append(borrow)
    if lut_inputs >= 6:
        inverted = compress_three(inverted)
    return inverted + full_adder_compress(borrows)


def compress_three(values):
    """3:2 compressors (a full adder per bit) over three values at a time, as plain logic.

    Returns, per group of three, the bitwise sum and the carries one place up, whose sum
    is the group's sum; a group of fewer than three passes through. Written as gates, not
    ``+``, so that synthesis maps each output bit to one LUT together with the logic in
    front of it (a carry chain would keep that logic in LUTs of its own).
    """
    out = []
    for i in range(0, len(values), 3):
        group = values[i:i + 3]
        if len(group) < 3:
            out += group
            continue
        x, y, z = group
        out += [x ^ y ^ z, Cat(Const(0, 1), (x & y) | (x & z) | (y & z))]
    return out


def sad_leaf_count(count, lut_inputs=4):
    """Leaves of :func:`sad_leaves` over ``count`` pairs."""
    inverted = count if lut_inputs < 6 else 2 * (count // 3) + count % 3
    return inverted + (count + 2) // 3


def sad_plan(count, every, depth=0, register_output=False, lut_inputs=4):
    """:func:`register_plan` of the tree over :func:`sad_leaves` of ``count`` pairs; the
    subtraction counts as one level (the inversion, and with 6-input LUTs the compressor,
    is merged into it: one LUT level, like census's XOR in front of its popcount); the
    leaves are 8-bit differences (9-bit carries of the compressors)."""
    return register_plan(sad_leaf_count(count, lut_inputs), every, depth + 1,
                         register_output, 8 if lut_inputs < 6 else 9)


def build_sad(m, en, pairs, plan, lut_inputs=4):
    """sum |a - b| over ``pairs``; ``plan`` from :func:`sad_plan` with the same
    ``lut_inputs``, its sum is the latency."""
    return build_tree(m, en, [(leaf,) for leaf in sad_leaves(pairs, lut_inputs)], _add,
                      plan)[0]


def build_sum(m, en, values, plan):
    """Sum of ``values`` by an adder tree; ``plan`` from :func:`register_plan` for
    ``len(values)`` leaves, its sum is the latency."""
    return build_tree(m, en, [(v,) for v in values], _add, plan)[0]


def select_min(lower, upper):
    """Combine two (value, index) items of a minimum tree."""
    # The upper-index candidate is the later one: it wins only if strictly better, so ties
    # keep the lowest index.
    upper_wins = better(upper[0], lower[0])
    return (Mux(upper_wins, upper[0], lower[0]), Mux(upper_wins, upper[1], lower[1]))


def min_tree_latency(count, split=True):
    """Clocks of :func:`build_min_tree` over ``count`` leaves."""
    return tree_levels(count) * (2 if split else 1)


def build_min_tree(m, en, leaves, split=True, name="min", compare=None):
    """Minimum of ``(value, index)`` leaves, ties to the lowest leaf, a register after
    every level.

    With ``split`` each level takes two clocks: the comparison is registered with both
    candidates, then the choice (a comparison of wide costs and the multiplexers of the
    whole pair it selects were 7.3 ns in one clock, ext. rank 7x7 on ECP5). Registers
    advance while ``en`` is high; the latency is :func:`min_tree_latency`. ``compare``
    (default :func:`~.common.better`) says whether the upper candidate replaces the lower.
    """
    compare = better if compare is None else compare
    items = [tuple(item) for item in leaves]
    level = 0
    while len(items) > 1:
        level += 1
        paired = []
        for i in range(0, len(items), 2):
            if i + 1 == len(items):          # the odd item out waits with the others
                item = items[i]
                for step in range(2 if split else 1):
                    item = _register(m, en, [item], f"{name}{level}_{i}_{step}")[0]
                paired.append(item)
                continue
            lower, upper = items[i], items[i + 1]
            if split:
                wins = Signal(name=f"{name}{level}_{i}_wins")
                with m.If(en):
                    m.d.sync += wins.eq(compare(upper[0], lower[0]))
                lower, upper = _register(m, en, [lower, upper], f"{name}{level}_{i}")
                chosen = tuple(Mux(wins, u, l) for l, u in zip(lower, upper))
            else:
                wins = compare(upper[0], lower[0])
                chosen = tuple(Mux(wins, u, l) for l, u in zip(lower, upper))
            paired.append(_register(m, en, [chosen], f"{name}{level}_{i}_min")[0])
        items = paired
    return items[0]
