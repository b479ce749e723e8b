"""The left path's lane arithmetic, shared by its loop over one position
(:mod:`.sgm_left`) and over two (:mod:`.sgm_left_pairs`): which columns take the small
step, comparisons of values kept modulo 2^n, the minimum of a few candidates as
comparisons then a one-hot choice, and copies of a scalar per group of lanes."""

from amaranth.hdl import Const, Mux

from ..params import SGM_LEFT_P1_PARITY
from .common import replica

__all__ = ["small_step", "less", "minimum", "winners", "pick", "LANES_PER_COPY", "copies"]


def small_step(x):
    """Whether column ``x`` takes the small step (P1) from its neighbours: the columns of
    ``params.SGM_LEFT_P1_PARITY`` (docs/semantics.md, "The left path")."""
    return x[0] if SGM_LEFT_P1_PARITY else ~x[0]


def less(a, b, bits):
    """a < b for values kept modulo 2^bits that differ by less than 2^(bits - 1)."""
    return (a - b)[bits - 1]


def minimum(candidates, bits, small=None):
    """The smallest of ``candidates`` (ties to the first): all comparisons side by side,
    then a one-hot choice. Returns (comparison bits, choice from them).

    With ``small`` (a flag), candidates 1 and 2 (the neighbours + P1) take part only where
    it is set: there the comparisons they win are cleared and those they lose set, one more
    input of the comparisons' LUTs, nothing in front of them."""
    count = len(candidates)
    beats = {(i, k): less(candidates[i], candidates[k], bits)
             for i in range(count) for k in range(count) if i > k}
    if small is not None:
        for (i, k), bit in beats.items():
            if k == 0 and i in (1, 2):
                beats[(i, k)] = bit & small
            elif i == 3 and k in (1, 2):
                beats[(i, k)] = bit | ~small

    def choose(beats):
        return pick(candidates, winners(beats, count), bits)
    return beats, choose


def winners(beats, count=None):
    """One flag per candidate, set for the smallest (ties to the first) of the first
    ``count`` (all that ``beats`` compares by default), from :func:`minimum`'s comparison
    bits: candidate i beats every earlier one and no later one beats it."""
    count = 1 + max(i for i, _ in beats) if count is None else count
    flags = []
    for i in range(count):
        wins = Const(1)
        for k in range(count):
            if k < i:
                wins &= beats[(i, k)]
            elif k > i:
                wins &= ~beats[(k, i)]
        flags.append(wins)
    return flags


def pick(candidates, wins, bits):
    """The candidate whose flag in the one-hot ``wins`` is set."""
    value = Const(0, bits)
    for flag, candidate in zip(wins, candidates):
        value |= Mux(flag, candidate, 0)
    return value


#: Lanes per copy of a scalar that every lane uses (ref + P2, the fresh start).
LANES_PER_COPY = 8


def copies(m, value, shape, lanes, name, enable=None, per=LANES_PER_COPY):
    """``value`` registered once per group of ``per`` lanes: the list of each lane's
    copy."""
    groups = [replica(m, value, f"{name}_copy{k}", shape, enable, reset_less=True)
              for k in range(-(-lanes // per))]
    return [groups[i // per] for i in range(lanes)]
