"""Input stage: line buffers and B x B windows of both images (the paper's Fig. 1, left).

Hardware counterpart of the golden model's zero-padded windows
(:func:`npstereo.golden.transform.neighbour_planes`). Pixels arrive in raster order, one
per admitted slot (``admit``). One line memory per image (:func:`.banks.line_memory`, depth W,
B-1 pixels wide) holds the previous B-1 rows of every column, so each position yields a
raster-continuous column of B pixels; a shift register of B columns forms the window.
The window centre trails the newest pixel by r rows and r columns; a mask computed from the
centre's counters clears every window pixel outside the frame (zero padding without extra
cycles at line ends). The centre's coordinates, the frames' overlap and the masks are
:mod:`.window_centre`'s; this module holds the line buffers, the window's shift and the
masked windows with their centres' copies.
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .banks import line_memory
from .common import SlotClock, bits_for, pipe, replica, tag_layout
from .plan_structure import (centre_copies, masks_after_compare, transformed_rows,
                             window_first_row, window_pixels, window_rows)
from .plan_timing import INPUT_LATENCY
from .window_centre import track_centre

__all__ = ["InputStage"]

LATENCY = INPUT_LATENCY
#: Clocks from the admission to the window's shift (the masked window follows a clock later).
SHIFTED = 3

#: Rows of a window column shifted by one copy of the admission pulse, and copies that
#: one early copy (a clock before) feeds.
SHIFT_ROWS, SHIFT_FANOUT = 3, 4
#: Early copies one register of the admission feeds; a window with more takes them from
#: copies of their own of the core's decision, a clock earlier still (the admission's
#: register reaching 2 x 23 early copies was census 15x15's critical path, 12.1 ns of wire,
#: and 2 x 26 rank 17x17's, 9.6 ns). Up to 11x11 a window has 6-14: unchanged.
EARLY_FANOUT = 16


def _shift_groups(params):
    """The groups of a window's registers that shift by one copy of the admission:
    (column, first row, end row), :data:`SHIFT_ROWS` rows of a column each."""
    rows = window_rows(params)
    return [(c, low, min(rows, low + SHIFT_ROWS)) for c in range(params.block)
            for low in range(0, rows, SHIFT_ROWS)]


def _early_copies(params):
    """Early shift copies a window's shift needs (see :data:`SHIFT_FANOUT`)."""
    return -(-len(_shift_groups(params)) // SHIFT_FANOUT)


def _large_window(params):
    """A window too large for one register of the admission to reach: more early shift
    copies than :data:`EARLY_FANOUT` (from 13x13 on)."""
    return _early_copies(params) > EARLY_FANOUT


class InputStage(wiring.Component):
    """Windows of both images around one centre per admitted slot.

    Parameters
    ----------
    params : StereoParams
        Needs ``width`` and ``height``.

    Attributes
    ----------
    admit : In(1)
        The admission's decision: the next clock is round 0 of a slot that carries a
        position (take ``left``/``right``).
    start : In(1)
        With ``admit``: the pixel is (0, 0) of a new frame (restarts the column counter).
    overlap : In(1)
        With ``start``: the previous frame still has centres to compute (it was not
        flushed): keep its coordinates until the new frame's first centre.
    left, right : In(8)
        The pixels of the admitted position (0 for dummy positions), three clocks after
        ``admit``.
    first, round : In
        Round 0 pulse and round of the slot timing at the admission offset.
    window_left, window_right : Out(ArrayLayout(unsigned(8), B * B))
        Masked windows, row-major (pixel (dy, dx) at (dy + r) * B + dx + r), slot-aligned
        at offset ``latency``; they change only when a position is admitted. With A
        windows per column, window k (k rows above the newest) follows window k - 1.
        With :func:`~.plan_structure.masks_after_compare`: one unmasked window of
        :func:`~.plan_structure.window_rows` rows instead, row-major, which the A windows share
        (window k from row :func:`~.plan_structure.window_first_row`).
    keep : Out(A * B * B)
        Only with :func:`~.plan_structure.masks_after_compare`: per window, bit
        (dy + r) * B + dx + r is 1 where the pixel lies inside the frame of the window's
        centre; slot-aligned with the window.
    centres_left, centres_right : Out(ArrayLayout(unsigned(8), copies))
        Copies of the windows' centre pixel (:func:`~.plan_structure.centre_copies`), each a
        register of its own, slot-aligned with the windows; not masked (a centre outside
        the frame is a position whose costs no sum takes).
    tag : Out(tag_layout)
        The windows' centre, slot-aligned at offset ``latency``.
    switch_pending : Out(1)
        A new frame started and its first centre has not been reached yet: another start
        must wait (frames shorter than the window radius).
    latency : int
        Clocks from ``admit`` to the windows and tag.
    """

    latency = LATENCY

    def __init__(self, params):
        self.params = params
        window = data.ArrayLayout(unsigned(8), window_pixels(params))
        centres = data.ArrayLayout(unsigned(8),
                                   centre_copies(params) * transformed_rows(params))
        keep = ({"keep": Out(transformed_rows(params) * params.block * params.block)}
                if masks_after_compare(params) else {})
        super().__init__({**keep,
            "admit": In(1), "start": In(1), "overlap": In(1),
            "left": In(8), "right": In(8),
            "first": In(1), "round": In(bits_for(params.rounds - 1)),
            "window_left": Out(window), "window_right": Out(window),
            "centres_left": Out(centres), "centres_right": Out(centres),
            "tag": Out(tag_layout(params)), "switch_pending": Out(1),
        })

    def elaborate(self, platform):
        p = self.params
        width, block, r = p.width, p.block, p.radius
        # The window's rows: B, or B + A - 1 when the A windows of a column are all
        # transformed here (``stored_rows == "pixels"``); ``top`` rows above the newest
        # window's centre.
        rows, windows = window_rows(p), transformed_rows(p)
        top = rows - 1 - r
        m = Module()
        slots = SlotClock(m, self.first, self.round, p.rounds, "input")
        # The decision, registered here: round 0 of the admitted slot. It arrives a clock
        # ahead so that the centre's groups of registers take copies of their own of it
        # (window_centre).
        admit = pipe(m, self.admit, 1, "admit", reset=True)
        start = pipe(m, self.start, 1, "start", reset=True)

        # Column of the admitted pixel: the line buffers' address. A start restarts it at
        # 0. With R >= 2 the address is a register, formed from the decision a clock
        # ahead (the counter steps only at the end of round 0, so it holds its value in
        # the clock before): the start's multiplexer in front of the block RAMs' address
        # was 6.8 ns, one LUT and routing (ext. rank 7x7 on ECP5).
        col = Signal(range(width))
        if p.rounds > 1:
            address = pipe(m, Mux(self.start, 0, col), 1, "line_address")
        else:
            address = Mux(start, 0, col)
        # col == W - 1 as a flag registered from the counter (it changes once per slot,
        # R >= 2 clocks apart), not a comparison behind the start's multiplexer (census
        # 9x9 on ECP5: 6.9 ns); a start moves to column 1 (W > 2 always).
        if p.rounds > 1:
            line_end = Signal(name="col_line_end")
            m.d.sync += line_end.eq(col == width - 1)
        else:
            line_end = col == width - 1
        with m.If(admit):
            m.d.sync += col.eq(Mux(start, 1, Mux(line_end, 0, col + 1)))

        # Two clocks later the line buffers' rows of that column have left the block RAM
        # and its output register; the pixel, the address and the flags wait for them.
        # Each line buffer takes its read address and, in the second clock, its write
        # enable and address from registers of its own (below): one register into both
        # images' block RAMs was census 7x7 SGM's path at R = 10 (6.2-6.6 ns of wire, the
        # write enable) and census 5x5's at 1920 x 1080 (10.8 ns, the start through the
        # read address's multiplexer).
        admitted = pipe(m, admit, 1, "admitted", reset=True)
        written_address = pipe(m, address, 1, "written_address")

        tag, keeps = track_centre(m, self, slots, admit, start, shifted=SHIFTED,
                                  large_window=_large_window(p))
        # First row (in the column) of window k, k rows above the newest.
        firsts = [window_first_row(p, k) for k in range(windows)]
        assert firsts[0] == top - r
        if masks_after_compare(p):
            # The flags travel with the window (its register, then the one by the
            # comparisons), in the same order as the window's pixels.
            m.d.comb += self.keep.eq(pipe(m, Cat(keeps[k][row][c] for k in range(windows)
                                                 for row in range(block)
                                                 for c in range(block)), 2, "keep_late"))
        for name, pixel in (("left", self.left), ("right", self.right)):
            # Slot s of the line buffer holds the pixel s + 1 rows above the newest one.
            # Every read address differs from the address written in the same clock (the
            # write trails the read of the same column by two clocks, the next read of it
            # comes a row later), so Yosys needs no collision logic (no_rw_check).
            lines = line_memory(m, f"lines_{name}", 8 * (rows - 1), width)
            if p.rounds > 1:
                read_address = replica(m, Mux(self.start, 0, col), f"lines_{name}_address",
                                       reset_less=True)
            else:
                read_address = Mux(replica(m, self.start, f"lines_{name}_start"), 0, col)
            # A plain register right behind the read port: the block RAM's own output
            # register on ECP5 (the flow packs it), 5 ns shorter than its bare output.
            older_word = pipe(m, lines.read_data, 1, f"{name}_read")
            older = [older_word[8 * s:8 * s + 8] for s in range(rows - 1)]
            newest_pixel = pixel
            m.d.comb += [
                lines.read_addr.eq(read_address),
                lines.write_addr.eq(replica(m, written_address, f"lines_{name}_write_address",
                                            reset_less=True)),
                lines.write_en.eq(replica(m, admitted, f"lines_{name}_write_enable")),
                lines.write_data.eq(Cat(newest_pixel, *older[:rows - 2])),
            ]
            # Column c (0 = oldest, dx = -r) packs its pixels top (dy = -top) to bottom.
            columns = [Signal(8 * rows, name=f"{name}_column{c}", reset_less=True)
                       for c in range(block)]
            # Each group of SHIFT_ROWS rows of a column shifts by an enable of its own, a
            # copy of ``admitted`` from a tree of copies (SHIFT_FANOUT groups to a copy a
            # clock earlier): one register reaching them all was 10 ns of routing (census
            # 9x9 on ECP5), one per column still 7 ns (rank 9x9).
            groups = _shift_groups(p)
            count = _early_copies(p)
            sources = [admit] if not _large_window(p) else [
                slots.private_copy(self.admit, -1, j, f"{name}_shift_admit{j}")
                for j in range(-(-count // EARLY_FANOUT))]
            early = [slots.private_copy(sources[g // EARLY_FANOUT], 0, g,
                                        f"{name}_shift_early{g}") for g in range(count)]
            arriving = Cat(*reversed(older), newest_pixel)
            for g, (c, low, high) in enumerate(groups):
                shift = slots.private_copy(early[g // SHIFT_FANOUT], 1, g,
                                           f"{name}_shift{g}")
                source = columns[c + 1] if c + 1 < block else arriving
                with m.If(shift):
                    m.d.sync += columns[c][8 * low:8 * high].eq(source[8 * low:8 * high])
            window = self.window_left if name == "left" else self.window_right
            # The masked window is a register of its own: a mask in front of the
            # transform's comparisons was the longest path (11 ns for census 9x9 on ECP5,
            # the masks reaching 16 pixels each). One assignment of the whole window:
            # per-element assignments would each cost a full-width assignment cell.
            # With the rows above transformed here, each of the A windows of the column is
            # masked by flags of its own (``keeps[k]``, see window_centre); census and rank
            # instead share the unmasked rows and mask their comparisons
            # (plan_structure.masks_after_compare).
            masked = Signal.like(window, name=f"{name}_window", reset_less=True)
            if masks_after_compare(p):
                m.d.sync += masked.eq(Cat(columns[c][8 * row:8 * (row + 1)]
                                          for row in range(rows) for c in range(block)))
            else:
                m.d.sync += masked.eq(Cat(
                    Mux(keeps[k][row][c], columns[c][8 * (first + row):8 * (first + row + 1)],
                        0)
                    for k, first in enumerate(firsts)
                    for row in range(block) for c in range(block)))
            # And once more, with the centres' copies: each copy is then a register next to
            # the comparisons it feeds, a clock away from the columns it is taken from (a
            # copy feeding the comparisons straight from the columns was 5 ns of routing,
            # census 9x9 on ECP5).
            m.d.comb += window.eq(pipe(m, masked, 1, f"{name}_window_late"))
            # The centres' copies take what the window register takes, in the clock the
            # window shifts (the value then holds for the slot), each by an enable of its
            # own; window k (k rows above the newest) has its centre at row top - k.
            # The centre is not masked: a window's centre is its own position, whose
            # column always lies in the frame, and whose transform matters only when its
            # row does too (every sum masks the rows outside the frame). The mask flag
            # reaching every copy was 9.1 ns of routing (ext. rank 13x13 on ECP5, 42
            # copies).
            copies = self.centres_left if name == "left" else self.centres_right
            per_window = len(copies) // windows
            for k in range(len(copies)):
                row = firsts[k // per_window] + r
                centre = columns[r][8 * row:8 * row + 8]
                copy = Signal(8, name=f"{name}_centre{k}", reset_less=True,
                              attrs=slots.private_attrs())
                with m.If(slots.private_first(SHIFTED, k, f"{name}_centre{k}_round")):
                    m.d.sync += copy.eq(centre)
                m.d.comb += copies[k].eq(pipe(m, copy, 1, f"{name}_centre{k}_late"))

        # The tag leaves with the masked window, a clock after the shift.
        m.d.comb += self.tag.eq(slots.delay(tag, SHIFTED, LATENCY - SHIFTED, "window_tag"))
        return m
