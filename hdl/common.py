"""Pieces shared by the pipeline stages: the position tag, enable-gated delay lines, and the
two primitives several stages compute (the WTA's tie rule and the absolute difference).

Every stage carries, next to its data, the *tag* of the position the data belongs to
(centre column ``x``, row ``y``, calculation ``round`` and ``live``). Stages derive every
border mask from the tag instead of relying on what their registers or memories held
before, so stale contents (previous frame, reset in mid-frame, dummy flush positions)
can never leak into a result.
"""

from amaranth.hdl import Mux, Signal, signed, unsigned
from amaranth.lib import data

__all__ = ["bits_for", "tag_layout", "delay", "y_range", "column_inside", "better",
           "absolute_difference"]


def bits_for(maximum):
    """Width of an unsigned value up to ``maximum`` (at least 1 bit, so no 0-width ports)."""
    return max(1, int(maximum).bit_length())


def y_range(params):
    """(lowest, highest) row a tag can hold.

    The input stage's first position of a frame has its window centre r rows and r columns
    behind the pixel that entered, i.e. above the frame; rows stop counting (saturate) a
    few rows below the frame, where no stage needs them any more.
    """
    r, a, width = params.radius, params.agg_radius, params.width
    lowest = -(r * width + r) // width - a
    highest = params.height + a + 1
    return lowest, highest


def tag_layout(params):
    """Layout of a position tag; ``live`` is 0 for positions never produced since reset."""
    lowest, highest = y_range(params)
    y_bits = max(abs(lowest), highest).bit_length() + 1
    return data.StructLayout({
        "x": unsigned(bits_for(params.width - 1)),
        "y": signed(y_bits),
        "round": unsigned(bits_for(params.rounds - 1)),
        "live": unsigned(1),
    })


def delay(m, en, value, steps, name):
    """``value`` delayed by ``steps`` ``en``-high clocks (a shift register; 0 steps: itself)."""
    for step in range(steps):
        reg = Signal(value.shape(), name=f"{name}_d{step}")
        with m.If(en):
            m.d.sync += reg.eq(value)
        value = reg
    return value


def column_inside(x, offset, width):
    """Column ``x + offset`` lies inside the frame, for a column counter ``x`` that is
    always in 0 .. W-1 (so only one side can fail, and offset 0 never does)."""
    if offset < 0:
        return x >= -offset
    return x < width - offset if offset > 0 else 1


def better(candidate, best):
    """The tie rule of every WTA: a candidate replaces the best so far only if strictly
    smaller.

    Candidates are visited (or, in a tree, paired) in increasing disparity order, so among
    equal costs the lowest disparity stays, as in the golden model's ``wta._better``.
    """
    return candidate < best


def absolute_difference(a, b):
    """Eq. 6: |a - b| of two unsigned values, as wide as the wider operand.

    Both differences and a select: yosys shares the ``<`` with the borrow of one of the
    subtractors (8 CCU2C + 7 LUT4 for 8 bits on ECP5, the cheapest of the forms tried,
    including a conditional negation).
    """
    width = max(len(a), len(b))
    return Mux(b < a, (a - b)[:width], (b - a)[:width])
