"""The memories of the core, as pure functions of the parameters.

What the components build, kind by kind (docs/hardware.md, "Memories"): ``npstereo report``
compares their bits with what Yosys infers (``tests/test_report.py``). :func:`built_memories`
cuts each kind into the memories the HDL instantiates (line buffers in slices, SGM's path
rows in banks), what synthesis maps one by one to block RAM, LUT RAM or registers
(``gen/flow/block_rams.py`` counts the block RAMs from them before anything is built).
"""

from collections import Counter
from dataclasses import dataclass

from ..params import P2_ADAPT_OFF, sgm_summed_cost_bits
from .banks import ADDRESS_SLICE_BITS, slice_widths
from .common import delay_line_rings, lane_groups, tag_layout
from .cost_term import term_memories, term_word_bits
from .plan_structure import (cost_banks, cost_rows, output_width, row_banks, store_slices,
                             vertical_bits, window_rows)
from .plan_timing import core_timing, lr_timing, reversed_sums_depth, sgm_delays, \
    sgm_fifth_forwarded, sgm_left_pairs, sgm_left_shift_store
from .trees import DEFAULT_EVERY

__all__ = ["MemoryUse", "memories", "memory_bits", "sgm_memories", "built_memories",
           "SYNC", "ASYNC", "BLOCK", "WHOLE", "LINES", "BANKED"]

#: How a memory is read. SYNC: a read port with its register, which synthesis puts in block
#: RAM, LUT RAM or flip-flops, whichever it finds cheapest; ASYNC: a combinational read
#: (``common.Store``), LUT RAM or flip-flops, never block RAM; BLOCK: a synchronous read
#: asked for in block RAM (``ram_style``, the L/R check's).
SYNC, ASYNC, BLOCK = "sync", "async", "block"
#: How the HDL cuts one memory of the list into the memories it instantiates. WHOLE: as it
#: is; LINES: ``banks.line_memory``'s slices (``slice_widths``); BANKED:
#: ``banks.banked_memory``'s banks (``plan_structure.row_banks``), each in slices of
#: ``ADDRESS_SLICE_BITS``.
WHOLE, LINES, BANKED = "whole", "lines", "banked"


@dataclass(frozen=True)
class MemoryUse:
    """One kind of memory of the core: ``count`` memories of ``depth`` words of ``width``
    bits, and what holds them (a use of memory, not Amaranth's ``Memory``): how they are
    read (:data:`SYNC`, :data:`ASYNC`, :data:`BLOCK`) and cut (:data:`WHOLE`,
    :data:`LINES`, :data:`BANKED`); ``ordered``: a read in the clock of a write to its
    address must give the old word (no ``no_rw_check``: Amaranth's FIFO), which synthesis
    emulates in front of a block RAM."""
    name: str
    count: int
    depth: int
    width: int
    read: str = SYNC
    layout: str = WHOLE
    ordered: bool = False

    @property
    def bits(self):
        return self.count * self.depth * self.width


def memories(params, every=DEFAULT_EVERY):
    """Every memory of the core for ``params`` (with width and height), as the components
    build them (docs/hardware.md, "Memories")."""
    p = params
    units, rounds, a = p.per_round, p.rounds, p.agg_radius
    result = [MemoryUse("input lines", 2, p.width, 8 * (window_rows(p) - 1), layout=LINES)]
    rows = cost_rows(p)
    if rows > 1 and p.stored_rows == "transforms":
        result.append(MemoryUse("transform lines", 1, p.width,
                                2 * (rows - 1) * p.transform_bits, layout=LINES))
    if a and p.stored_rows == "costs":
        banks = cost_banks(p)
        for depth in sorted(set(banks), reverse=True):
            result.append(MemoryUse("cost lines", units * banks.count(depth), depth,
                                    (p.aggregation - 1) * p.cost_bits))
    if p.is_sgm:
        result += sgm_memories(p, every)
    if rounds > 1:
        widths = store_slices(rows * p.transform_bits + term_word_bits(p))
        for width in sorted(set(widths)):
            result.append(MemoryUse("right-transform stores", units * widths.count(width),
                                    rounds, width, ASYNC))
        if a:
            result.append(MemoryUse("row taps", units, rounds, 2 * a * vertical_bits(p),
                                    ASYNC))
        result += [MemoryUse(*memory, ASYNC) for memory in term_memories(p)]
    if p.lr_check:
        d_bits = max(1, (p.disparities - 1).bit_length())
        timing = core_timing(p, every)
        history = lr_timing(p, timing.left - timing.check).history
        if rounds > 1:
            result.append(MemoryUse("right winners", units, rounds,
                                    p.aggregated_cost_bits + d_bits + 1, ASYNC))
        # With the sub-pixel fit the output value waits beside the level it is checked by.
        value = p.output_disparity_bits if p.subpixel_bits else 0
        result.append(MemoryUse("left winners", 1, history,
                                tag_layout(p).size + d_bits + value, BLOCK))
        result.append(MemoryUse("dR history", 1, history, d_bits, BLOCK))
    if p.fifth_path:
        # hdl/mirror.py: the L/R check's sums reversed (R > 1), and a row of output words
        # (two flags and the output disparity) turned round.
        if rounds > 1 and p.lr_check:
            result.append(MemoryUse("reversed sums ring", 1, reversed_sums_depth(rounds),
                                    units * p.aggregated_cost_bits, ASYNC))
        result.append(MemoryUse("output row", 1, p.width, p.output_disparity_bits + 2,
                                layout=LINES))
    if p.median:
        # Median3's line buffers: the entry (key of the output value's bits + 1, word
        # flag, four edge flags) and the key of the row above; with F > 0 the value
        # carries its fraction.
        bits = max(1, (p.disparities - 1).bit_length()) + p.subpixel_bits
        result += [MemoryUse("median row", 1, p.width, bits + 6, layout=LINES),
                   MemoryUse("median row above", 1, p.width, bits + 1, layout=LINES)]
    depth = core_timing(p, every).queue_depth
    result.append(MemoryUse("output queue", 1, depth - 1, output_width(p) + 2, ordered=True))
    return result


def memory_bits(params, every=DEFAULT_EVERY):
    """Bits the core's memories hold (what Yosys counts in its ``$mem_v2`` cells)."""
    return sum(memory.bits for memory in memories(params, every))


def built_memories(params, every=DEFAULT_EVERY):
    """The memories the HDL instantiates for ``params``, one :class:`MemoryUse` per shape
    (``count`` of them): :func:`memories` with each kind cut as the HDL cuts it (its
    ``layout``), the unit that synthesis maps to block RAM, LUT RAM or registers. The bits
    are :func:`memories`' (``tests/test_memory_fit.py`` checks the shapes against the
    ``Memory`` objects an elaborated core makes)."""
    found = {}
    for use in memories(params, every):
        if use.layout == LINES:
            pieces = [(use.depth, width) for width in slice_widths(use.width, use.depth)]
        elif use.layout == BANKED:
            slices = [min(ADDRESS_SLICE_BITS, use.width - low)
                      for low in range(0, use.width, ADDRESS_SLICE_BITS)]
            pieces = [(depth, width) for depth in row_banks(params) for width in slices]
        else:
            pieces = [(use.depth, use.width)]
        for depth, width in pieces:
            key = (use.name, depth, width, use.read, use.ordered)
            found[key] = found.get(key, 0) + use.count
    return [MemoryUse(name, count, depth, width, read, ordered=ordered)
            for (name, depth, width, read, ordered), count in found.items()]


def sgm_memories(params, every=DEFAULT_EVERY):
    """The SGM stage's memories (docs/hardware.md, "Memories").

    Block RAM: the previous row's path costs, one word per (column, round) of D/R values,
    top and top-left in one memory (both read the position's own column), top-right in
    another (it reads the next column); the three paths' minima, one word per column.
    LUT RAM (R > 1; registers at R = 1): the top-left words held for the next position, and
    from R = 3 (registers below, ``plan_timing.sgm_left_shift_store``, ``sgm_left_pairs``) the left
    path's Lu(x - 1, .) and Lu(x - 1, .) + P1 (2 D/R values of ``left_loop_bits`` per
    round) and the first of them + P1 again (the neighbour across the next round's edge). With the fifth path
    (:mod:`.sgm_right`) its recursion's two stores again, and two rows of W R words in
    block RAM: the costs (and P2) and S4.
    """
    p = params
    word = p.per_round * p.path_cost_bits
    result = [MemoryUse("path rows (top, top-left)", 1, p.width * p.rounds, 2 * word,
                        layout=BANKED),
              MemoryUse("path rows (top-right)", 1, p.width * p.rounds, word, layout=BANKED),
              MemoryUse("path minima", 1, p.width, 3 * p.path_cost_bits, layout=LINES)]
    # The left path's and the top-left stores: one LUT RAM per group of lanes
    # (common.LaneStores).
    sizes = Counter(len(group) for group in lane_groups(p.per_round))
    if not sgm_left_shift_store(p.rounds) and not sgm_left_pairs(p.rounds):
        # The fifth path's recursion has the left path's stores again.
        copies = 2 if p.fifth_path else 1
        result += [MemoryUse("left path store", copies * count, p.rounds,
                             2 * lanes * p.left_loop_bits, ASYNC)
                   for lanes, count in sorted(sizes.items())]
        result.append(MemoryUse("left path first lanes", copies, p.rounds, p.left_loop_bits,
                                ASYNC))
    if p.rounds > 1:
        result += [MemoryUse("top-left store", count, p.rounds, lanes * p.path_cost_bits,
                             ASYNC) for lanes, count in sorted(sizes.items())]
    # The long free-running delays, rings of LUT RAM (common.delay_line): the three paths'
    # sum (three L from above: 2 bits wider) and the left path's L to their addition, the
    # left path's Lu (the fifth path's again) to its normalisation.
    delays = sgm_delays(p, every)
    lines = [("above", p.path_cost_bits + 2, 1), ("left", p.left_cost_bits, 1),
             ("lu", p.left_loop_bits, 2 if p.fifth_path else 1)]
    for key, bits, copies in lines:
        rings = Counter(delay_line_rings(p.per_round * bits, delays[key]))
        result += [MemoryUse(f"delay line ({key})", copies * count, depth, width, ASYNC)
                   for (width, depth), count in sorted(rings.items())]
    if p.fifth_path:
        # hdl/sgm_right.py: a row of the costs (and the left path's P2 when adaptive) and
        # of S4, one word per (column, round), banked as the path rows.
        adaptive = p.p2_adapt != P2_ADAPT_OFF
        p2_bits = max(1, p.p2.bit_length()) if adaptive else 0
        depth = p.width * p.rounds
        rows = [MemoryUse("fifth path costs row", 1, depth,
                          p.per_round * p.cost_bits + p2_bits, layout=BANKED),
                MemoryUse("fifth path S4 row", 1, depth,
                          p.per_round * sgm_summed_cost_bits(p.max_cost, p.p2), layout=BANKED)]
        # The words each row forwards (written while a read is in its banks) in delay lines.
        result += rows + [MemoryUse("fifth path forwarded words", 1, ring_depth, bits, ASYNC)
                          for row in rows for k in sgm_fifth_forwarded(p)
                          for bits, ring_depth in delay_line_rings(row.width, k)]
    return result
