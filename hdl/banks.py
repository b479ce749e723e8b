"""Memories cut into block-RAM-sized banks, each read into its own output register.

A memory deeper than one block RAM is a cascade whose choice among the blocks stands
between the blocks and the first register, so that register cannot go into the blocks'
output registers (ECP5 OUTREG): ext. census 7x7's cost lines (70 MHz) and SGM's path rows
(74.9 MHz) were limited by that choice. Here every bank reads at the address's low bits into
its own output register, and the bank is chosen behind those registers
(:data:`~.plan_structure.BANK_CHOICE` banks per registered level,
:func:`~.plan_structure.bank_choice_levels`).
"""

from types import SimpleNamespace

from amaranth.hdl import Array, Cat, Shape, Signal, unsigned
from amaranth.lib.memory import Memory

from .common import pipe, replica
from .plan_structure import BANK_CHOICE

__all__ = ["choose_bank", "ADDRESS_SLICE_BITS", "banked_memory", "BLOCK_RAM_MODES",
           "slice_widths", "line_memory"]


#: Bits of a chosen word that one copy of the bank's index selects: a DP16KD's widest
#: word. One index register reaching every bit of a wide word was census 5x5 SGM's critical
#: path at 1280 x 720, D = 64, R = 4 (the top path rows' 224-bit word: 11.0 ns, one LUT).
CHOICE_SLICE = 36


def _chosen(m, words, index, name):
    """``Array(words)[index]``, each :data:`CHOICE_SLICE` bits of it selected by a copy of
    ``index`` of its own (``index`` a clock later: the copies are its last register)."""
    width = len(words[0])
    parts = []
    for k, low in enumerate(range(0, width, CHOICE_SLICE)):
        copy = replica(m, index, f"{name}_s{k}", reset_less=True)
        parts.append(Array(w[low:low + CHOICE_SLICE] for w in words)[copy])
    return Cat(*parts)


def choose_bank(m, words, bank, name):
    """The word of bank ``bank`` among the banks' output registers ``words``, two clocks
    after ``bank``: chosen among up to :data:`~.plan_structure.BANK_CHOICE` banks at a time,
    each level but the last registered (its digit of the index a clock later each time,
    its last register copied per :data:`CHOICE_SLICE` bits of the word)."""
    choice = BANK_CHOICE
    digit = choice.bit_length() - 1

    def digits(low, high, level):
        """The index's digits ``low:high``, a clock before the choice of ``level``."""
        return pipe(m, bank[low:high], 1 + level, f"{name}{level}" if level else name)

    level = 0
    while len(words) > choice:
        late = digits(digit * level, digit * (level + 1), level)
        groups = [words[g:g + choice] for g in range(0, len(words), choice)]
        words = []
        for g, group in enumerate(groups):
            word = Signal.like(group[0], name=f"{name}{level}_{g}")
            m.d.sync += word.eq(_chosen(m, group, late, f"{name}{level}_{g}_select")
                                if len(group) > 1 else group[0])
            words.append(word)
        level += 1
    return _chosen(m, words, digits(digit * level, len(bank), level), f"{name}_select")


#: Bits of a bank's word whose block RAMs share one copy of each address: eight DP16KD
#: at 2K x 9, two at 512 x 36. One read address register reaching all 75 block RAMs of
#: the top path rows (three banks of 224 bits) was census 5x5 SGM's critical path at
#: 1280 x 720, D = 64, R = 4 (11.65 ns of routing, no logic).
ADDRESS_SLICE_BITS = 72


def banked_memory(m, name, shape, banks, read_early, write_early, write_data,
                  enable_early):
    """A memory of ``sum(banks)`` words (bank b holds the words from b * banks[0] on),
    read every clock at the address ``read_early`` had a clock before and written when
    ``enable_early`` was high a clock before, at the address ``write_early`` had then: each
    :data:`ADDRESS_SLICE_BITS` bits of each bank are a memory of their own with copies of
    both addresses and of the write enable of their own, so that no address or enable
    register reaches more than a few block RAMs. Returns the word read, in a register:
    two clocks after the address with one bank (the read, the block RAM's output
    register), and with several banks a clock more for a register behind each bank's and
    a clock more per level of the bank's choice (:func:`choose_bank`). No collision logic
    (``no_rw_check``): the callers never read a word in the clock it is written."""
    width = Shape.cast(shape).width
    low = (banks[0] - 1).bit_length() if len(banks) > 1 else len(read_early)
    slices = [(first, min(ADDRESS_SLICE_BITS, width - first))
              for first in range(0, width, ADDRESS_SLICE_BITS)]
    words = []
    for b, depth in enumerate(banks):
        parts = []
        for k, (first, bits) in enumerate(slices):
            part = f"{name}_{b}" if len(banks) > 1 else name
            part += f"_{k}" if len(slices) > 1 else ""
            memory = Memory(shape=unsigned(bits), depth=depth, init=[],
                            attrs={"no_rw_check": 1})
            m.submodules[part] = memory
            read, write = memory.read_port(domain="sync"), memory.write_port()
            read_address = replica(m, read_early[:low], f"{part}_read_address",
                                   reset_less=True)
            write_address = replica(m, write_early, f"{part}_write_address",
                                    reset_less=True)
            # The bank's enable decoded a clock ahead into a copy of its own: one enable
            # register through each bank's decoder into all 61 block RAMs was 6.26 ns
            # routed and 7.70 ns in the placement's estimate (census 7x7 SGM, R = 10).
            # A control bit, so it resets.
            mine = replica(m, enable_early if len(banks) == 1 else
                           enable_early & (write_early[low:] == b), f"{part}_write_enable")
            m.d.comb += [read.addr.eq(read_address), write.addr.eq(write_address[:low]),
                         write.data.eq(write_data[first:first + bits]), write.en.eq(mine)]
            parts.append(read.data)
        # The block RAM's output register, and with several banks a register in the
        # fabric after it: the banks' block RAMs lie apart, and their output registers
        # straight into the choice were census 7x7 SGM's second path at R = 10 (7.61 ns,
        # 6.25 of it routing, one LUT).
        words.append(pipe(m, Cat(*parts), 1 if len(banks) == 1 else 2, f"{name}_{b}_out"))
    if len(banks) == 1:
        return words[0]
    bank = pipe(m, read_early[low:], 2, f"{name}_read_bank")
    word = Signal(shape, name=f"{name}_word", reset_less=True)
    m.d.sync += word.eq(choose_bank(m, words, bank, f"{name}_bank"))
    return word


#: (words, bits) of one ECP5 DP16KD in each of its shapes.
BLOCK_RAM_MODES = ((512, 36), (1024, 18), (2048, 9), (4096, 4), (8192, 2), (16384, 1))


def slice_widths(width, depth):
    """Widths of the slices of a memory of ``depth`` words of ``width`` bits: as wide as one
    block RAM is at that depth (all of it up to 512 words). Left whole, a memory deeper
    than 512 words is a cascade of block RAMs with a multiplexer between them and its read
    register, which then cannot be the block RAM's output register: the 1280-word input
    line buffers were census 5x5's critical path at 1280 x 720 (the read, 5.83 ns, and the
    cascade's multiplexer into the register, 10.2 ns)."""
    if depth <= BLOCK_RAM_MODES[0][0]:
        return [width]
    bits = next((b for words, b in BLOCK_RAM_MODES if depth <= words), 1)
    return [min(bits, width - low) for low in range(0, width, bits)]


def line_memory(m, name, shape, depth):
    """A memory of ``depth`` words of ``shape`` with a synchronous read port, cut into
    :func:`slice_widths` slices (one memory of ``shape`` where one slice holds it). Returns
    its ports as signals of ``shape``'s width: ``read_addr``, ``read_en`` (1 unless driven),
    ``read_data``, ``write_addr``, ``write_data``, ``write_en``. No collision logic
    (``no_rw_check``): the callers never read a word in the clock it is written."""
    width = Shape.cast(shape).width
    ports = SimpleNamespace(
        read_addr=Signal(range(depth), name=f"{name}_read_addr"),
        read_en=Signal(name=f"{name}_read_en", init=1),
        read_data=Signal(width, name=f"{name}_read_data"),
        write_addr=Signal(range(depth), name=f"{name}_write_addr"),
        write_data=Signal(width, name=f"{name}_write_data"),
        write_en=Signal(name=f"{name}_write_en"))
    low, data = 0, []
    widths = slice_widths(width, depth)
    for k, bits in enumerate(widths):
        memory = Memory(shape=shape if len(widths) == 1 else unsigned(bits), depth=depth,
                        init=[], attrs={"no_rw_check": 1})
        m.submodules[name if len(widths) == 1 else f"{name}_{k}"] = memory
        read, write = memory.read_port(domain="sync"), memory.write_port()
        m.d.comb += [read.addr.eq(ports.read_addr), read.en.eq(ports.read_en),
                     write.addr.eq(ports.write_addr), write.en.eq(ports.write_en),
                     write.data.eq(ports.write_data[low:low + bits])]
        data.append(read.data)
        low += bits
    m.d.comb += ports.read_data.eq(Cat(*data))
    return ports
