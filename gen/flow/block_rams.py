"""ECP5 block RAMs (DP16KD) of a core, counted from its parameters before anything is built.

Yosys's ``synth_ecp5`` maps each memory the HDL instantiates on its own
(:func:`npstereo.hdl.plan_memories.built_memories`: the line buffers' slices, the SGM rows'
banks) with ``memory_libmap``: to block RAM, to LUT RAM or to flip-flops, whichever its cost
estimate finds cheapest (Yosys 0.70, ``passes/memory/memory_libmap.cc`` with
``share/lattice/brams_16kd.txt`` and ``lutrams_trellis.txt``):

- flip-flops cost one per bit (1/16 for a ROM) and win a tie;
- a DP16KD (or its 36-bit simple dual-port mode, PDPW16KD) costs 128 and a TRELLIS_DPR16X4
  (16 x 4, read combinationally: a registered read gets its register behind it) 4, each
  times the cells of the cheapest shape: ``ceil(depth / words)`` address ranges side by
  side, the word padded to whole 9-bit bytes where a block's width is 9 or more, and the
  ranges' bits packed into ``ceil(ranges * padded / bits)`` cells (a block's byte enables
  write one range's bytes beside another's);
- plus half a point per bit of the read multiplexer among the ranges and per range of the
  write decoder, and twice the emulation score: a point for the read port that does not
  share the write port's address, and in front of a block RAM six more for a memory whose
  reads must see the old word when its address is written in the same clock (a DP16KD's
  two ports do not order them: read-first emulation, 3 points, and transparency, 3);
  the output queue's (Amaranth's FIFO) is one, and at 127 x 10 that keeps it in LUT
  RAM.

A memory read combinationally (``common.Store``) cannot be a DP16KD; one with
``ram_style = "block"`` (the L/R check's) always is. The count is checked against Yosys's
for the configurations of docs/resources.md, "Block RAM before synthesis".
"""

import math

from ...hdl.plan_memories import ASYNC, BLOCK, SYNC, built_memories

__all__ = ["BLOCK_RAM_SHAPES", "block_rams", "core_block_rams"]

#: (words, bits) of one DP16KD in each of its shapes; 512 x 36 is its simple dual-port mode
#: (PDPW16KD), which every memory of one write and one read port may take.
BLOCK_RAM_SHAPES = ((16384, 1), (8192, 2), (4096, 4), (2048, 9), (1024, 18), (512, 36))
#: memory_libmap's cost of one cell (``cost`` in the library files).
_BLOCK_COST, _LUT_RAM_COST = 128, 4
#: A TRELLIS_DPR16X4: 16 words of 4 bits.
_LUT_RAM_SHAPE = (16, 4)
#: Write-enable granularity of a DP16KD (``byte 9``): a word is padded to whole bytes in the
#: shapes at least that wide.
_BYTE = 9
#: memory_libmap's FACTOR_MUX and FACTOR_DEMUX, and FACTOR_EMU times the emulation score of
#: a read port not shared with the write port (1), and of the read-first and transparency
#: logic an ordered read needs in front of a block RAM (3 + 3).
_MUX, _DEMUX, _EMULATION, _ORDER_EMULATION = 0.5, 0.5, 2, 12


def _cost(depth, width, words, bits, cell_cost, byte):
    """``(cost, cells)`` of a memory of ``depth`` x ``width`` in cells of ``words`` x
    ``bits``, as memory_libmap's geometry estimate counts them."""
    ranges = math.ceil(depth / words)
    step = byte if byte and byte <= bits else bits
    padded = math.ceil(width / step) * step
    cells = math.ceil(ranges * padded / bits)
    cost = cell_cost * cells + _MUX * (ranges - 1) * width + _EMULATION
    if ranges > 1:
        cost += _DEMUX * ranges
    return cost, cells


def block_rams(depth, width, read=SYNC, rom=False, ordered=False):
    """DP16KD that Yosys maps one memory of ``depth`` words of ``width`` bits to: 0 when
    LUT RAM or flip-flops cost less (or it is read combinationally, ``read`` ASYNC), the
    cells of its cheapest block shape otherwise (always with ``read`` BLOCK). ``rom``: no
    write port (flip-flops then cost 1/16 per bit, and LUT RAM is not used for ROMs);
    ``ordered``: its reads keep their order with a write to the same address
    (:class:`~npstereo.hdl.plan_memories.MemoryUse`)."""
    if read == ASYNC:
        return 0
    cost, cells = min(_cost(depth, width, words, bits, _BLOCK_COST, _BYTE)
                      for words, bits in BLOCK_RAM_SHAPES)
    cost += _ORDER_EMULATION if ordered else 0
    if read == BLOCK:
        return cells
    # memory_libmap compares with the flip-flops' cost truncated to an integer, and keeps
    # them on a tie.
    cheaper = [int(depth * width / (16 if rom else 1))]
    if not rom:
        cheaper.append(_cost(depth, width, *_LUT_RAM_SHAPE, _LUT_RAM_COST, 0)[0])
    return cells if cost < min(cheaper) else 0


def core_block_rams(params):
    """DP16KD of the core for ``params`` (with width and height): :func:`block_rams` of each
    memory it instantiates."""
    return sum(use.count * block_rams(use.depth, use.width, use.read, ordered=use.ordered)
               for use in built_memories(params))
