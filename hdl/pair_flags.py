"""Which of a round's cost units have a pair: x - d >= n for unit i's disparity d.

x - j*D/R is formed once; then per unit x - d >= n <=> x - j*D/R >= i + n, for i + n < D/R:
beyond D/R every unit's pair exists, below it only the low bits decide (ten comparisons of
one signed word with constants were five LUT levels for census 9x9 on ECP5). The three
sources (all pairs, some pairs, the low bits) come in a copy per group of units
(:func:`~.common.unit_copies`).
"""

from amaranth.hdl import Signal

from .common import bits_for, round_base, unit_copies

__all__ = ["pair_flags"]


def pair_flags(m, slots, x, offset, params, beyond_needed):
    """``at_least(i, n)``: a flag, x - d >= n for unit i's d (0 <= n <= 2), two clocks after
    ``x`` (slot-aligned at ``offset``). ``beyond_needed``: n = 2 is asked for the last
    unit (the cost term's x - d >= 2)."""
    units = params.per_round
    x_minus_round = Signal(range(-params.disparities, params.width), name="x_minus_round")
    m.d.sync += x_minus_round.eq(x - round_base(m, slots, offset, units))
    all_pairs = unit_copies(m, x_minus_round >= units, units, "all_pairs")
    some_pairs = unit_copies(m, x_minus_round >= 0, units, "some_pairs")
    if units > 1:
        low = unit_copies(m, x_minus_round[:bits_for(units - 1)], units, "x_minus_round_low")
    if beyond_needed:
        beyond = Signal(name="all_pairs_beyond")
        m.d.sync += beyond.eq(x_minus_round >= units + 1)

    def at_least(i, n):
        """x - d >= n for unit i's d. Unit 0's x - d >= 0 is x - j*D/R >= 0 alone (a
        constant comparison fails Verilator's lint)."""
        flag = Signal(name=f"x_minus_d{i}_at_least{n}")
        if i + n < units:
            m.d.sync += flag.eq(all_pairs[i] | (some_pairs[i] & (low[i] >= i + n))
                                if i + n else some_pairs[i])
        else:
            m.d.sync += flag.eq(all_pairs[i] if i + n == units else beyond)
        return flag
    return at_least
