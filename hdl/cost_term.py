"""The ``ad3`` cost term in hardware, one per cost unit, beside the census cost
(docs/semantics.md, "The ad3 cost term"; golden model: :mod:`npstereo.golden.cost_term`).

Where the pixels come from. The term of (x, y, d) sums A over columns x - 1 .. x + 1 and
rows y - 1 .. y + 1. Column sums do not depend on the neighbours' disparities, so each unit
computes one column sum per (position, round), that of column x + 1 at its own d, and keeps
the two before it, which it computed at the two positions before (the unit's disparity
stays the same from one position to the next): a 3 x 8-bit left column and a 3 x 8-bit
right column per unit instead of a 3 x 3 window per unit. The left column is the left
window's column to the right of the centre (rows -1 .. 1, masked by the frame as the window
is), handed from unit to unit with the left transform. The right column x + 1 - d travels
with the right transform of column x - d through the right stores: the newest word carries
the right window's column to the right of its centre. Right column 0 would be carried by
the word of column -1, which does not exist: the golden model leaves it out (a column sum
counts where its right column x' - d >= 1).

Against AD line buffers (W x D 5-bit differences of two rows, e.g. 1280 x 64 x 10 bits =
45 DP16KD at 1280 x 720, D = 64, any R): 24 bits more per store word (LUT RAM at R > 1,
flip-flops at R = 1) and 2 x 7 bits of column sums per (unit, round), no block RAM.

Timing (clocks after the unit's operands, :data:`COST_TERM_CLOCKS` in all; every step
registered, so that the term adds no logic to the census cost's path): the three absolute
differences; their clips to 31; the column sum; the history's read (the word of this
round) and write-back, with the two older sums gated by x - d >= 1 and >= 2 and added; the
fresh sum added; the clip to 255 and the shift.
"""

from amaranth.hdl import Cat, Mux, unsigned

from ..params.cost_terms import AD3_CLIP, AD3_LIMIT, AD3_SHIFT
from .common import Store, absolute_difference, pipe

__all__ = ["COST_TERM_CLOCKS", "COLUMN_BITS", "term_clocks", "term_word_bits",
           "term_memories", "right_column", "Ad3Term"]

#: Clocks from a unit's operands to its term (module docstring).
COST_TERM_CLOCKS = 6
#: Bits of a column of three pixels, which the left and right words carry.
COLUMN_BITS = 3 * 8
_SUM_BITS = (3 * AD3_CLIP).bit_length()


def term_clocks(params):
    """Clocks from the operands to the cost term: 0 without one."""
    return COST_TERM_CLOCKS if params.cost_term else 0


def term_word_bits(params):
    """Bits the term adds to each right-store word (and left word): 0 without one."""
    return COLUMN_BITS if params.cost_term else 0


def term_memories(params):
    """The term's LUT RAM (R > 1; registers at R = 1) as (name, count, depth, width): each
    unit's history of two column sums per round (the stores' wider words are counted with
    the stores)."""
    if not params.cost_term or params.rounds == 1:
        return []
    return [("cost term histories", params.per_round, params.rounds, 2 * _SUM_BITS)]


def right_column(window, block):
    """The three pixels (rows -1, 0, 1) of the column right of a masked B x B window's
    centre (row-major, as :class:`~.input_stage.InputStage` gives it), top first."""
    r = (block - 1) // 2
    return Cat(window[(r + dy) * block + r + 1] for dy in (-1, 0, 1))


class Ad3Term:
    """The term of one cost unit: builds its logic into ``m`` and holds the result.

    Parameters
    ----------
    m : Module
    slots : SlotClock
        The calculation stage's.
    params : StereoParams
    unit : int
        Cost unit i (its history's address counter runs with its own phase).
    left, right : Value
        :data:`COLUMN_BITS` each: the left column x + 1 and the right column x + 1 - d of
        the unit's round, at the unit's operand offset ``at``.
    at : int
        The operands' offset (slot-aligned, round j a clock later per round).
    older, oldest : Value
        x - d >= 1 and x - d >= 2 of the unit's round, at ``at + 3``: the column sums of
        x and x - 1 count.
    write : Value
        The slot carries a position, at ``at + 3``: its column sum enters the history.

    Attributes
    ----------
    value : Signal(3)
        T, at ``at + COST_TERM_CLOCKS``.
    """

    def __init__(self, m, slots, params, unit, left, right, at, older, oldest, write):
        name = f"ad3_{unit}"
        differences = [pipe(m, absolute_difference(left.word_select(k, 8),
                                                   right.word_select(k, 8)), 1,
                            f"{name}_difference{k}") for k in range(3)]
        clipped = [pipe(m, Mux(d >= AD3_CLIP, AD3_CLIP, d[:AD3_CLIP.bit_length()]), 1,
                        f"{name}_clipped{k}") for k, d in enumerate(differences)]
        fresh = pipe(m, (clipped[0] + clipped[1] + clipped[2])[:_SUM_BITS], 1,
                     f"{name}_column")
        # The history of this unit's round: the column sums of x and x - 1 (this round's
        # disparity, the two positions before), read and written back in the same clock.
        history = Store(m, f"{name}_history", unsigned(2 * _SUM_BITS), params.rounds)
        address = 0 if params.rounds == 1 else slots.phased_round(at + 3, unit,
                                                                  f"{name}_address")
        word = history.read(address)
        previous, before = word[:_SUM_BITS], word[_SUM_BITS:]
        history.write(address, Cat(fresh, previous), write)
        old = pipe(m, Mux(older, previous, 0) + Mux(oldest, before, 0), 1, f"{name}_old")
        total = pipe(m, old + pipe(m, fresh, 1, f"{name}_fresh"), 1, f"{name}_total")
        self.value = pipe(m, Mux(total > AD3_LIMIT, AD3_LIMIT >> AD3_SHIFT,
                                 total[AD3_SHIFT:AD3_LIMIT.bit_length()]), 1, f"{name}_term")
