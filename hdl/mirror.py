"""The back end on mirrored rows (``StereoParams.fifth_path``): the sums in reversed order
for the L/R check, and the output words turned back into raster order.

With the fifth path the SGM stage gives the sums of row y while row y + 1 streams in, in
mirrored order: slot x carries column x = W - 1 - x' of row y on its tag's x' (:mod:`.sgm_right`).
The WTA per position and the sub-pixel fit do not care about the order of the positions;
the L/R check runs on the mirrored row in its mirrored mode (:class:`~.lr_check.LRCheck`),
fed the candidates of each position from the highest disparity down
(:func:`reversed_sums`); and one row of output words (:class:`RowTurn`) turns the checked
words round, where a row of S5 did before: W words of a disparity and two flags, not W R
words of D/R sums (docs/hardware.md, "The fifth path").
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import Out

from .banks import line_memory
from .common import pipe, register, tag_layout, y_range
from .plan_timing import ROW_TURN_LATENCY, reversed_sums_clocks, reversed_sums_depth
from .ticks import tick_ports

__all__ = ["turning_rows", "reversed_sums", "RowTurn"]


def turning_rows(m, params, name, starts, y):
    """A row buffer's address direction, flipped at every row start (``starts``, a
    register), and the y of the row before: (direction, y before). The direction is the
    new one in the start's clock already; the rows' y start from a row above the frame,
    so that before a row has passed no word is of a frame row."""
    mirror = Signal(name=f"{name}_mirror")
    rows = [Signal(y.shape(), name=f"{name}_row{k}", init=y_range(params)[0])
            for k in range(2)]
    with m.If(starts):
        m.d.sync += [mirror.eq(~mirror), rows[1].eq(rows[0]), rows[0].eq(y)]
    return mirror ^ starts, Mux(starts, rows[0], rows[1])


def reversed_sums(m, params, slots, sums, at, name):
    """The lanes' sums ``sums`` (slot-aligned at ``at``), with disparity d in place of
    D - 1 - d: the lanes reversed and, with R > 1, the rounds too, round j of a slot
    carrying round R - 1 - j of the slot before
    (:func:`~.plan_timing.reversed_sums_clocks` = R + 1 clocks later).

    A ring of LUT RAM written every clock: round j of the output, at clock t, is the word
    written 2 j + 2 clocks before, read a clock ahead into a register."""
    lanes = list(reversed(list(sums)))
    if slots.rounds == 1:
        return lanes
    rounds, bits = slots.rounds, len(lanes[0])
    depth = reversed_sums_depth(rounds)
    m.submodules[name] = ring = Memory(shape=unsigned(bits * len(lanes)), depth=depth,
                                       init=[])
    write, read = ring.write_port(), ring.read_port(domain="comb")
    written = Signal(range(depth), name=f"{name}_written", reset_less=True)
    m.d.sync += written.eq(written + 1)
    # In the clock before the output's round j the ring's newest word is 2 j + 1 behind.
    later = slots.round(at + reversed_sums_clocks(params) - 1)
    m.d.comb += [write.addr.eq(written), write.data.eq(Cat(*lanes)), write.en.eq(1),
                 read.addr.eq(written - 1 - 2 * later)]
    word = register(m, read.data, bits * len(lanes), f"{name}_out")
    return [word[k * bits:(k + 1) * bits] for k in range(len(lanes))]


class RowTurn(wiring.Component):
    """The L/R check's words of the mirrored rows in raster order, one row later.

    Each tick (a retire pulse: every slot with a position) writes its word at the row
    buffer's address A(x') and reads the word there, the previous row's at the mirrored
    column: the address runs left to right and right to left in turn (flipped at each row
    start, x' = 0), so one row of W words suffices. The word that leaves is that of
    column x = x' of the previous row, which it names (``x_out``, ``y_out``); it is produced when
    the L/R check produced it and its row is a frame row (the rows' y start above the
    frame, so nothing written before a reset leaves). The row's last tick and the next
    row's first share an address: the second reads it in the clock the first's word is
    written, and takes that word from a register.

    Attributes
    ----------
    retire, produce, valid, disparity, x, y : In
        The L/R check's outputs on mirrored rows (x is x').
    retire_out, produce_out, valid_out, disparity_out, x_out, y_out : Out
        One tick per input tick, :data:`~.plan_timing.ROW_TURN_LATENCY` clocks later, and
        the word of the previous row at column ``x_out``.
    frame_start, line_end, frame_end : Out(1)
        That position is (0, 0), the last of its row, the last of its frame.
    """

    def __init__(self, params, bits):
        self.params, self.bits = params, bits
        self.latency = ROW_TURN_LATENCY
        layout = tag_layout(params)
        super().__init__({**tick_ports(params, bits), "x_out": Out(layout["x"].shape),
                          "y_out": Out(layout["y"].shape)})

    def elaborate(self, platform):
        p = self.params
        m = Module()
        word_layout = data.StructLayout({"produce": 1, "valid": 1,
                                         "disparity": unsigned(self.bits)})
        memory = line_memory(m, "row_turn", word_layout, p.width)
        # The tick registered with its row-start flag and both addresses, so that only the
        # direction's choice stands in front of the block RAM's address.
        retire = register(m, self.retire, 1, "row_turn_retire")
        starts = register(m, self.retire & (self.x == 0), 1, "row_turn_starts")
        x = register(m, self.x, self.x.shape(), "row_turn_x")
        flipped = register(m, p.width - 1 - self.x, self.x.shape(), "row_turn_flipped")
        y = register(m, self.y, self.y.shape(), "row_turn_in_y")
        mirrored, before = turning_rows(m, p, "row_turn", starts, y)
        address = Mux(mirrored, flipped, x)
        written = register(m, address, range(p.width), "row_turn_write_address")
        enable = register(m, retire, 1, "row_turn_write_enable")
        word = pipe(m, Cat(self.produce, self.valid, self.disparity), 2, "row_turn_word")
        m.d.comb += [memory.read_addr.eq(address), memory.write_addr.eq(written),
                     memory.write_data.eq(word), memory.write_en.eq(enable)]
        # The word read passes a plain register (the block RAM's output register) before
        # the forwarded word's choice.
        hit = pipe(m, (address == written) & enable, 2, "row_turn_hit")
        held = pipe(m, word, 2, "row_turn_held")
        read = pipe(m, memory.read_data, 1, "row_turn_read")
        out = data.View(word_layout, Mux(hit, held, read))
        tick = pipe(m, retire, 2, "row_turn_tick", reset=True)
        x, y = pipe(m, x, 2, "row_turn_x"), pipe(m, before, 2, "row_turn_y")
        in_frame = (y >= 0) & (y < p.height)
        m.d.sync += [
            self.retire_out.eq(tick), self.produce_out.eq(tick & out.produce & in_frame),
            self.valid_out.eq(out.valid), self.disparity_out.eq(out.disparity),
            self.x_out.eq(x), self.y_out.eq(y),
            self.frame_start.eq((x == 0) & (y == 0)),
            self.line_end.eq(x == p.width - 1),
            self.frame_end.eq((x == p.width - 1) & (y == p.height - 1)),
        ]
        return m
