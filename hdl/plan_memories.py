"""The memories of the core, as pure functions of the parameters.

What the components build, kind by kind (docs/hardware.md, "Memories"): ``npstereo report``
compares their bits with what Yosys infers (``tests/test_report.py``).
"""

from dataclasses import dataclass

from ..params import P2_ADAPT_OFF, sgm_summed_cost_bits
from .common import tag_layout
from .cost_term import term_memories, term_word_bits
from .plan_structure import (cost_banks, cost_rows, output_width, store_slices,
                             vertical_bits, window_rows)
from .plan_timing import core_timing, lr_timing, sgm_left_shift_store
from .trees import DEFAULT_EVERY

__all__ = ["MemoryUse", "memories", "memory_bits", "sgm_memories"]


@dataclass(frozen=True)
class MemoryUse:
    """One kind of memory of the core: ``count`` memories of ``depth`` words of ``width``
    bits, and what holds them (a use of memory, not Amaranth's ``Memory``)."""
    name: str
    count: int
    depth: int
    width: int

    @property
    def bits(self):
        return self.count * self.depth * self.width


def memories(params, every=DEFAULT_EVERY):
    """Every memory of the core for ``params`` (with width and height), as the components
    build them (docs/hardware.md, "Memories")."""
    p = params
    units, rounds, a = p.per_round, p.rounds, p.agg_radius
    result = [MemoryUse("input lines", 2, p.width, 8 * (window_rows(p) - 1))]
    rows = cost_rows(p)
    if rows > 1 and p.stored_rows == "transforms":
        result.append(MemoryUse("transform lines", 1, p.width,
                                2 * (rows - 1) * p.transform_bits))
    if a and p.stored_rows == "costs":
        banks = cost_banks(p)
        for depth in sorted(set(banks), reverse=True):
            result.append(MemoryUse("cost lines", units * banks.count(depth), depth,
                                    (p.aggregation - 1) * p.cost_bits))
    if p.is_sgm:
        result += sgm_memories(p)
    if rounds > 1:
        widths = store_slices(rows * p.transform_bits + term_word_bits(p))
        for width in sorted(set(widths)):
            result.append(MemoryUse("right-transform stores", units * widths.count(width),
                                    rounds, width))
        if a:
            result.append(MemoryUse("row taps", units, rounds, 2 * a * vertical_bits(p)))
        result += [MemoryUse(*memory) for memory in term_memories(p)]
    if p.lr_check:
        d_bits = max(1, (p.disparities - 1).bit_length())
        timing = core_timing(p, every)
        history = lr_timing(p, timing.left - timing.sums).history
        if rounds > 1:
            result.append(MemoryUse("right winners", units, rounds,
                                    p.aggregated_cost_bits + d_bits + 1))
        # With the sub-pixel fit the output value waits beside the level it is checked by.
        value = p.output_disparity_bits if p.subpixel_bits else 0
        result.append(MemoryUse("left winners", 1, history,
                                tag_layout(p).size + d_bits + value))
        result.append(MemoryUse("dR history", 1, history, d_bits))
    if p.median:
        # Median3's line buffers: the entry (key of d_bits + 1, word flag, four edge
        # flags) and the key of the row above.
        d_bits = max(1, (p.disparities - 1).bit_length())
        result += [MemoryUse("median row", 1, p.width, d_bits + 6),
                   MemoryUse("median row above", 1, p.width, d_bits + 1)]
    depth = core_timing(p, every).queue_depth
    result.append(MemoryUse("output queue", 1, depth - 1, output_width(p) + 2))
    return result


def memory_bits(params, every=DEFAULT_EVERY):
    """Bits the core's memories hold (what Yosys counts in its ``$mem_v2`` cells)."""
    return sum(memory.bits for memory in memories(params, every))


def sgm_memories(params):
    """The SGM stage's memories (docs/hardware.md, "Memories").

    Block RAM: the previous row's path costs, one word per (column, round) of D/R values,
    top and top-left in one memory (both read the position's own column), top-right in
    another (it reads the next column); the three paths' minima, one word per column.
    LUT RAM (R > 1; registers at R = 1): the top-left words held for the next position, and
    from R = 3 (shifting registers below, ``plan_timing.sgm_left_shift_store``) the left
    path's Lu(x - 1, .) and Lu(x - 1, .) + P1 (2 D/R values of ``left_loop_bits`` per
    round) and the first of them + P1 again (the neighbour across the next round's edge). With the fifth path
    (:mod:`.sgm_right`) its recursion's two stores again, and three rows of W R words in
    block RAM: the costs (and P2), S4 and S5.
    """
    p = params
    word = p.per_round * p.path_cost_bits
    result = [MemoryUse("path rows (top, top-left)", 1, p.width * p.rounds, 2 * word),
              MemoryUse("path rows (top-right)", 1, p.width * p.rounds, word),
              MemoryUse("path minima", 1, p.width, 3 * p.path_cost_bits)]
    if not sgm_left_shift_store(p.rounds):
        # The fifth path's recursion has the left path's stores again.
        copies = 2 if p.fifth_path else 1
        result += [MemoryUse("left path store", copies, p.rounds,
                             2 * p.per_round * p.left_loop_bits),
                   MemoryUse("left path first lanes", copies, p.rounds, p.left_loop_bits)]
    if p.rounds > 1:
        result.append(MemoryUse("top-left store", 1, p.rounds, word))
    if p.fifth_path:
        # hdl/sgm_right.py: a row of the costs (and the left path's P2 when adaptive), of
        # S4 and of S5, one word per (column, round).
        adaptive = p.p2_adapt != P2_ADAPT_OFF
        p2_bits = max(1, p.p2.bit_length()) if adaptive else 0
        depth = p.width * p.rounds
        result += [MemoryUse("fifth path costs row", 1, depth,
                             p.per_round * p.cost_bits + p2_bits),
                   MemoryUse("fifth path S4 row", 1, depth,
                             p.per_round * sgm_summed_cost_bits(p.max_cost, p.p2)),
                   MemoryUse("fifth path S5 row", 1, depth,
                             p.per_round * p.aggregated_cost_bits)]
    return result
