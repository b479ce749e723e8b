"""Memories cut into block-RAM-sized banks, each read into its own output register.

A memory deeper than one block RAM is a cascade whose choice among the blocks stands
between the blocks and the first register, so that register cannot go into the blocks'
output registers (ECP5 OUTREG): ext. census 7x7's cost lines (70 MHz) and SGM's path rows
(74.9 MHz) were limited by that choice. Here every bank reads at the address's low bits into
its own output register, and the bank is chosen behind those registers
(:data:`~.plan_structure.BANK_CHOICE` banks per registered level,
:func:`~.plan_structure.bank_choice_levels`).
"""

from amaranth.hdl import Array, Signal
from amaranth.lib.memory import Memory

from .common import pipe
from .plan_structure import BANK_CHOICE

__all__ = ["choose_bank", "banked_memory"]


def choose_bank(m, words, bank, name):
    """The word of bank ``bank`` among the banks' output registers ``words``, two clocks
    after ``bank``: chosen among up to :data:`~.plan_structure.BANK_CHOICE` banks at a time,
    each level but the last registered (its digit of the index a clock later each time)."""
    choice = BANK_CHOICE
    digit = choice.bit_length() - 1

    def digits(low, high, level):
        """The index's digits ``low:high``, delayed to the choice of ``level``."""
        return pipe(m, bank[low:high], 2 + level, f"{name}{level}" if level else name)

    level = 0
    while len(words) > choice:
        chosen = digits(digit * level, digit * (level + 1), level)
        groups = [words[g:g + choice] for g in range(0, len(words), choice)]
        words = []
        for g, group in enumerate(groups):
            word = Signal.like(group[0], name=f"{name}{level}_{g}")
            m.d.sync += word.eq(Array(group)[chosen] if len(group) > 1 else group[0])
            words.append(word)
        level += 1
    chosen = digits(digit * level, len(bank), level)
    return Array(words)[chosen]


def banked_memory(m, name, shape, banks, read_address, write_address, write_data,
                  write_enable):
    """A memory of ``sum(banks)`` words (bank b holds the words from b * banks[0] on),
    read every clock at ``read_address`` and written at ``write_address`` when
    ``write_enable`` (or at ``write_address[b]`` into bank b: copies of the address, each
    driving one bank's block RAMs). Returns the word read, in a register: two clocks after the address
    with one bank (the read, the block RAM's output register), and with several banks a
    clock more per level of the bank's choice (:func:`choose_bank`). No collision logic
    (``no_rw_check``): the callers never read a word in the clock it is written."""
    low = (banks[0] - 1).bit_length() if len(banks) > 1 else len(read_address)
    if not isinstance(write_address, (list, tuple)):
        write_address = [write_address] * len(banks)
    words = []
    for b, depth in enumerate(banks):
        memory = Memory(shape=shape, depth=depth, init=[], attrs={"no_rw_check": 1})
        m.submodules[f"{name}_{b}" if len(banks) > 1 else name] = memory
        read, write = memory.read_port(domain="sync"), memory.write_port()
        mine = write_enable if len(banks) == 1 else \
            write_enable & (write_address[b][low:] == b)
        m.d.comb += [read.addr.eq(read_address[:low]), write.addr.eq(write_address[b][:low]),
                     write.data.eq(write_data), write.en.eq(mine)]
        words.append(pipe(m, read.data, 1, f"{name}_{b}_out"))
    if len(banks) == 1:
        return words[0]
    word = Signal(shape, name=f"{name}_word", reset_less=True)
    m.d.sync += word.eq(choose_bank(m, words, read_address[low:], f"{name}_bank"))
    return word
