"""The 3x3 median of the output words (``StereoParams.median``), between the L/R check and
the output queue.

Hardware counterpart of :func:`npstereo.golden.median.median3` (docs/semantics.md, "3x3
median"). The words arrive in raster order, one per *tick* (a retire pulse of the L/R
check: every slot with a position, in the frame or not); the median of a word is formed
when the word W + 1 ticks after it arrives, which completes its window, so the stage delays
the stream by W + 1 positions (:func:`~.plan_timing.latency` counts them; the flush feeds
them after the last frame). Each tick enters one word and leaves one: the retire pulse
passes through, and a word comes out when the window's centre is a word of the frame, so
the core's credits (one per position) still balance.

**Rows.** Two line buffers of W entries (block RAM at any useful width) delay the stream by
W and 2 W ticks: the row below, the centre's row and the row above the centre. The first
holds the whole entry (sort key, the word flag and the centre's four frame-edge flags), the
second the key only. Each is read in every clock at its write pointer, the slot the next
tick overwrites, and at a tick at the pointer's next value: the word a tick needs was read
in the clock before it, never in the clock of a write to it, so the RAMs need no
read-during-write rule (no_rw_check), and their output registers add a clock.

**Window.** Three registers per row, shifted on the tick, form the 3x3 window; the centre's
edge flags clear the keys that lie outside the frame (which are another row's words or
another frame's). A key is 0 for an invalid word and 2^b + d for disparity d of b bits, so
the invalid ones sort first.

**Median.** A sorting network of the nine keys (Batcher's odd-even merge sort of 16 inputs,
the comparators that reach the padding removed: 9 inputs, :data:`NETWORK`), a register
after every layer; beside it the count of valid keys n chooses the ((n + 1) // 2)-th valid
key, the sorted key at index (8 + 9 - n) // 2, and keeps it iff n >= 1 and the centre is
valid or n >= 5 (:data:`~npstereo.params.MEDIAN_FILL`).
"""

import operator
from functools import reduce

from amaranth.hdl import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring

from ..params import MEDIAN_FILL
from .banks import line_memory
from .common import pipe
from .ticks import tick_ports

__all__ = ["sorting_network", "NETWORK", "network_layers", "MEDIAN_LATENCY", "Median3"]


def sorting_network(inputs):
    """Comparators (i, j), i < j (the smaller value goes to i), of Batcher's odd-even merge
    sort of the next power of two, without those that touch an index >= ``inputs``: padding
    larger than every value would never move there, so what remains sorts ``inputs``."""
    size = 1 << (inputs - 1).bit_length()
    pairs = []
    p = 1
    while p < size:
        k = p
        while k >= 1:
            for j in range(k % p, size - k, 2 * k):
                for i in range(min(k, size - j - k)):
                    if (i + j) // (2 * p) == (i + j + k) // (2 * p):
                        pairs.append((i + j, i + j + k))
            k //= 2
        p *= 2
    return [(i, j) for i, j in pairs if j < inputs]


def network_layers(pairs):
    """The comparators in layers (each as early as its two wires allow): one clock each."""
    ready, layers = {}, []
    for i, j in pairs:
        layer = max(ready.get(i, 0), ready.get(j, 0))
        if layer == len(layers):
            layers.append([])
        layers[layer].append((i, j))
        ready[i] = ready[j] = layer + 1
    return layers


#: The nine-key network, in layers.
NETWORK = network_layers(sorting_network(9))

#: Clocks from a tick at the stage's input to its output word: the entry's register, the
#: first line buffer's read register and output register, the second's output register,
#: the window, one per layer of the network, the choice.
MEDIAN_LATENCY = 4 + len(NETWORK) + 1


def _outside(centre, r, k):
    """Tap (r, k) of the window (row y - 1 + r, column x + 1 - k) lies outside the frame,
    by the centre's edge flags."""
    outside = Const(0)
    if r != 1:
        outside = outside | (centre.top if r == 0 else centre.bottom)
    if k != 1:
        outside = outside | (centre.right if k == 0 else centre.left)
    return outside


def _priming_ticks(width):
    """The ticks after a reset before the one whose centre was written after it, less one
    (the flag is set at that tick and holds from the next): W."""
    return width


def _rank_choice(valid_count):
    """Index in the sorted nine of the lower median of the ``valid_count`` valid keys."""
    return (8 + 9 - valid_count) // 2


class Median3(wiring.Component):
    """3x3 median of the words of :class:`~.lr_check.LRCheck`, :data:`MEDIAN_LATENCY`
    clocks later.

    Parameters
    ----------
    params : StereoParams
        ``width`` and ``height`` are used.
    bits : int
        Width of a disparity (the L/R check's ``disparity_out``).

    Attributes
    ----------
    retire, produce, valid, disparity, x, y : In
        The L/R check's outputs: a tick, a word of the frame with it, the word and its
        position.
    retire_out, produce_out, valid_out, disparity_out : Out
        One tick per input tick; with ``produce_out`` the median word of the position
        W + 1 ticks back.
    frame_start, line_end, frame_end : Out(1)
        That position is (0, 0), the last of its row, the last of its frame.
    """

    def __init__(self, params, bits):
        self.params, self.bits = params, bits
        self.latency = MEDIAN_LATENCY
        super().__init__(tick_ports(params, bits))

    def elaborate(self, platform):
        p, bits = self.params, self.bits
        m = Module()
        key_shape = unsigned(bits + 1)
        entry = data.StructLayout({"key": key_shape, "word": 1, "left": 1, "right": 1,
                                   "top": 1, "bottom": 1})
        # Clock 1: the entry of the tick (an invalid word's key is 0 whatever its d).
        new = Signal(entry, name="median_new", reset_less=True)
        tick = Signal(name="median_tick")
        m.d.sync += [
            tick.eq(self.retire),
            new.key.eq(Mux(self.valid, Cat(self.disparity, Const(1, 1)), 0)),
            new.word.eq(self.produce),
            new.left.eq(self.x == 0), new.right.eq(self.x == p.width - 1),
            new.top.eq(self.y == 0), new.bottom.eq(self.y == p.height - 1),
        ]
        # Clock 2: the entry W ticks back; clock 3: the key 2 W ticks back, all aligned.
        middle = self._line(m, "median_row1", new, tick, entry)
        tick2 = pipe(m, tick, 1, "median_tick2", reset=True)
        above = self._line(m, "median_row2", middle.key, tick2, key_shape)
        tick3 = pipe(m, tick2, 1, "median_tick3", reset=True)
        middle = pipe(m, middle, 1, "median_middle")
        rows = [above, middle.key, pipe(m, new, 2, "median_below").key]
        # The taps: taps[r][k] is column x + 1 - k of row y - 1 + r for the centre (x, y),
        # the middle row's entry of the tick before (W + 1 ticks back).
        taps = []
        for r, row in enumerate(rows):
            late = [row]
            for k in range(2):
                reg = Signal(key_shape, name=f"median_tap{r}_{k + 1}", reset_less=True)
                with m.If(tick3):
                    m.d.sync += reg.eq(late[-1])
                late.append(reg)
            taps.append(late)
        centre = Signal(entry, name="median_centre", reset_less=True)
        with m.If(tick3):
            m.d.sync += centre.eq(middle)
        # Primed after W + 1 ticks since reset: the centre was written after it.
        seen = Signal(range(p.width + 1), name="median_seen")
        primed = Signal(name="median_primed")
        with m.If(tick3 & ~primed):
            m.d.sync += seen.eq(seen + 1)
            with m.If(seen == _priming_ticks(p.width)):
                m.d.sync += primed.eq(1)
        # Clock 4: the window, outside the frame cleared.
        window = []
        for r in range(3):
            for k in range(3):
                key = Signal(key_shape, name=f"median_window{r}{k}", reset_less=True)
                m.d.sync += key.eq(Mux(_outside(centre, r, k), 0, taps[r][k]))
                window.append(key)
        flags = data.StructLayout({"tick": 1, "word": 1, "centre_valid": 1,
                                   "frame_start": 1, "line_end": 1, "frame_end": 1})
        stage = Signal(flags, name="median_flags")
        m.d.sync += [stage.tick.eq(tick3), stage.word.eq(tick3 & primed & centre.word),
                     stage.centre_valid.eq(centre.key[bits]),
                     stage.frame_start.eq(centre.left & centre.top),
                     stage.line_end.eq(centre.right),
                     stage.frame_end.eq(centre.right & centre.bottom)]
        # The network, a register after every layer; beside it the count of valid keys
        # and, a clock later, the choice of the sorted index and whether to keep it.
        keys = window
        for n, layer in enumerate(NETWORK):
            following = list(keys)
            for i, j in layer:
                swap = keys[j] < keys[i]
                following[i], following[j] = Mux(swap, keys[j], keys[i]), \
                    Mux(swap, keys[i], keys[j])
            keys = [pipe(m, value, 1, f"median_sorted{n}_{i}")
                    for i, value in enumerate(following)]
        count = Signal(range(10), name="median_valid_count", reset_less=True)
        m.d.sync += count.eq(sum(key[bits] for key in window))
        choices = sorted({_rank_choice(n) for n in range(1, 10)})
        choice = Signal(len(choices), name="median_choice", reset_less=True)
        keep = Signal(name="median_keep", reset_less=True)
        centre_valid = pipe(m, stage.centre_valid, 1, "median_centre_valid")
        m.d.sync += [choice.eq(Cat(Cat(*[count == n for n in range(1, 10)
                                            if _rank_choice(n) == index]).any()
                                       for index in choices)),
                     keep.eq((count != 0) & (centre_valid | (count >= MEDIAN_FILL)))]
        late = len(NETWORK) - 2
        choice, keep = pipe(m, choice, late, "median_choice"), pipe(m, keep, late, "median_keep")
        stage = pipe(m, stage, len(NETWORK), "median_flags", reset=True)
        chosen = Signal(key_shape, name="median_chosen")
        m.d.comb += chosen.eq(reduce(operator.or_, (Mux(choice[n], keys[index], 0)
                                                    for n, index in enumerate(choices))))
        # The output registers.
        m.d.sync += [self.retire_out.eq(stage.tick), self.produce_out.eq(stage.word),
                     self.valid_out.eq(keep), self.disparity_out.eq(chosen[:bits]),
                     self.frame_start.eq(stage.frame_start), self.line_end.eq(stage.line_end),
                     self.frame_end.eq(stage.frame_end)]
        return m

    def _line(self, m, name, value, tick, shape):
        """``value`` of W ticks back, a clock after ``tick`` (see the module docstring)."""
        width = self.params.width
        memory = line_memory(m, name, shape, width)
        # The pointer's next value kept in a register of its own: formed from the pointer
        # (its increment and wrap) in front of the read address's multiplexer, it was the
        # recommended configuration's critical path at 1280 x 720 (9.47 ns, 4 levels).
        pointer = Signal(range(width), name=f"{name}_pointer")
        following = Signal(range(width), name=f"{name}_following", init=1 % width)
        with m.If(tick):
            m.d.sync += [pointer.eq(following),
                         following.eq(Mux(following == width - 1, 0, following + 1))]
        m.d.comb += [memory.write_addr.eq(pointer), memory.write_data.eq(value),
                     memory.write_en.eq(tick), memory.read_addr.eq(Mux(tick, following, pointer))]
        out = Signal(shape, name=f"{name}_out", reset_less=True)
        m.d.sync += out.eq(memory.read_data)
        return out
