"""Input stage: line buffers and B x B windows of both images (the paper's Fig. 1, left).

Hardware counterpart of the golden model's zero-padded windows
(:func:`npstereo.golden.transform.neighbour_planes`). Pixels arrive in raster order, one
per admitted slot (``admit``). One :class:`~amaranth.lib.memory.Memory` per image (depth W,
B-1 pixels wide) holds the previous B-1 rows of every column, so each position yields a
raster-continuous column of B pixels; a shift register of B columns forms the window.
The window centre trails the newest pixel by r rows and r columns; a mask computed from the
centre's counters clears every window pixel outside the frame (zero padding without extra
cycles at line ends).

Frames may follow each other without a flush: when a frame starts right after the previous
one (``overlap``), the centre keeps the previous frame's coordinates until it reaches the
new frame's first pixel, r rows and r columns later, so the previous frame's last rows are
still computed (their window rows below the frame are masked, whatever pixels the new frame
put there).
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import SlotClock, bits_for, column_inside, pipe, tag_layout, y_range
from .plan_structure import (centre_copies, masks_after_compare, transformed_rows,
                             window_first_row, window_pixels, window_rows)
from .plan_timing import INPUT_LATENCY

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


def _offset_row_inside(y, offset, height):
    """Row ``y + offset`` lies inside the frame."""
    return (y >= -offset) & (y < height - offset)


def _offset_row_inside_at(y, offset, height):
    """:func:`_offset_row_inside` of a constant row."""
    return int(0 <= y + offset < height)


def _offset_row_before(y, offset, height):
    """Row ``y + offset`` lies in the frame before this one (rows -H .. -1)."""
    return (y < -offset) & (y >= -height - offset)


def _offset_row_before_at(y, offset, height):
    """:func:`_offset_row_before` of a constant row."""
    return int(-height <= y + offset < 0)


def _column_inside_at(x, offset, width):
    """:func:`~.common.column_inside` of a constant column."""
    return int(0 <= x + offset < width)


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
        # (_centre).
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
        admitted = pipe(m, admit, 2, "admitted", reset=True)
        written_address = pipe(m, address, 2, "written_address")

        tag, keeps = self._centre(m, slots, admit, start)
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
            m.submodules[f"lines_{name}"] = lines = Memory(
                shape=unsigned(8 * (rows - 1)), depth=width, init=[],
                attrs={"no_rw_check": 1})
            read = lines.read_port(domain="sync")
            write = lines.write_port()
            # A plain register right behind the read port: the block RAM's own output
            # register on ECP5 (the flow packs it), 5 ns shorter than its bare output.
            older_word = pipe(m, read.data, 1, f"{name}_read")
            older = [older_word[8 * s:8 * s + 8] for s in range(rows - 1)]
            newest_pixel = pixel
            m.d.comb += [
                read.addr.eq(address),
                write.addr.eq(written_address), write.en.eq(admitted),
                write.data.eq(Cat(newest_pixel, *older[:rows - 2])),
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
            # masked by flags of its own (``keeps[k]``, see _centre); census and rank
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
                copy = Signal(8, name=f"{name}_centre{k}", reset_less=True)
                with m.If(slots.private_first(SHIFTED, k, f"{name}_centre{k}_round")):
                    m.d.sync += copy.eq(centre)
                m.d.comb += copies[k].eq(pipe(m, copy, 1, f"{name}_centre{k}_late"))

        # The tag leaves with the masked window, a clock after the shift.
        m.d.comb += self.tag.eq(slots.delay(tag, SHIFTED, LATENCY - SHIFTED, "window_tag"))
        return m

    def _centre(self, m, slots, admit, start):
        """The centre's tag and the window masks, updated with the window.

        The tag is slot-aligned at offset SHIFTED (the stage delays it further with
        the masked window): x, y and live change with each
        admitted position, ``valid`` says in every slot whether it carries one.

        Two frames' coordinates coexist while frames overlap. The window masks follow the
        *window centre's* frame: a pixel's transform sees zeros outside its own frame. The
        tag that leaves the stage names the same position, but in the frame of the
        *aggregation centre*, a rows and a columns further back, for everything after the
        transforms masks rows and columns relative to that centre: the finishing frame's
        last aggregation window must see the new frame's first row as outside. So the tag
        switches to the new frame a*W + a positions after the window masks do.

        ``admit`` and ``start`` are the stage's registers of the decision (round 0 of the
        admitted slot).

        Returns the tag register and, per window of the column (the newest first),
        ``keep[row][column]``, 1 where the window pixel lies inside the window centre's
        frame.
        """
        p = self.params
        width, height, block, r, a = p.width, p.height, p.block, p.radius, p.agg_radius
        # Position 0 of a frame is centred r rows and r columns earlier.
        lag = r * width + r
        tag_lag = lag + a * width + a
        first_x, first_y = -lag % width, -lag // width
        _, highest = y_range(p)
        layout = tag_layout(p)

        # The centre steps a clock after the admission, a clock before the window shifts:
        # the step (its counters and multiplexers) and the masks (comparisons of the new
        # counters) are two clocks' work, not one. The step uses flags registered from
        # the counters (x at the line end, rows below the saturation, the countdown's two
        # events) instead of comparing them on its way.
        stepping = pipe(m, admit, 1, "stepping", reset=True)
        x = Signal(layout["x"].shape, name="centre_x")
        y = Signal(layout["y"].shape, name="centre_y")
        window_y = Signal(layout["y"].shape, name="window_y")
        live = Signal(name="centre_live")
        countdown = Signal(range(tag_lag + 1))    # positions until the tag's switch
        line_end = Signal(name="centre_line_end")              # x == W - 1
        y_room, window_room = Signal(name="y_room"), Signal(name="window_y_room")
        switch_window = Signal(name="switch_window")           # countdown == window event
        switch_tag = Signal(name="switch_tag")                 # countdown == 1
        # A register of its own, not a comparison: it feeds the admission decision.
        pending = Signal()
        m.d.comb += self.switch_pending.eq(pending)
        # Between jumps the rows change only at line ends, W > 2 steps apart: flags a clock
        # late are in time (a jump sets them itself, below).
        # The rows count up from below ``highest`` and stop there, so "below" is "not
        # equal": a comparison of the constant's bits instead of a signed comparison's
        # carry chain (ext. rank 9x9 on ECP5: y to y_room, 7 levels, 6.6 ns).
        m.d.sync += [y_room.eq(y != highest), window_room.eq(window_y != highest)]
        window_event = tag_lag - lag + 1

        # Which window rows and columns lie inside the frame: flags stepped with the
        # counters rather than comparisons of them in front of the masks (six LUT levels
        # on ECP5). A step to the next column shifts the column flags (column x + 1 + o is
        # column x + (o + 1)); the row flags shift when the window row advances. The one
        # flag past each end that a shift brings in is a comparison of its own: for the
        # columns one in the step (x changes every step), for the rows one registered every
        # clock from window_y (rows change only at line ends, W > 2 steps apart; a jump
        # sets it itself).
        top = window_rows(p) - 1 - r
        row_offsets = range(-top, r + 1)
        row_ok = [Signal(name=f"row_ok{o + top}") for o in row_offsets]
        row_next = Signal(name="row_ok_next")          # row window_y + r + 1
        offsets = range(-r, r + 1)
        col_ok = [Signal(name=f"col_ok{o + r}") for o in offsets]
        col_next = Signal(name="col_ok_next")           # column x + r + 1
        m.d.sync += row_next.eq(_offset_row_inside(window_y, r + 1, height))
        # With the rows above transformed here again (``stored_rows == "pixels"``) window
        # k is masked in the frame of its own centre, window_y - k, as the transforms
        # variant masked it when that row was the newest: while frames overlap, the
        # windows above the newest may still belong to the finishing frame (centre above
        # the new frame's row 0), whose rows are then the ones above row 0 (``prev_ok``),
        # not those of the new frame.
        windows = transformed_rows(p)
        prev_ok = [Signal(name=f"prev_ok{o + top}") for o in row_offsets]
        prev_next = Signal(name="prev_ok_next")
        old = [Signal(name=f"window_old{k}") for k in range(windows)]   # window_y < k
        if windows > 1:
            m.d.sync += prev_next.eq(_offset_row_before(window_y, r + 1, height))

        def rows_before_at(value):
            return [prev_ok[o + top].eq(_offset_row_before_at(value, o, height))
                    for o in row_offsets] + \
                   [prev_next.eq(_offset_row_before_at(value, r + 1, height))] + \
                   [old[k].eq(int(value < k)) for k in range(1, windows)]

        def rows_at(value):
            return [row_ok[o + top].eq(_offset_row_inside_at(value, o, height))
                    for o in row_offsets] + \
                   [row_next.eq(_offset_row_inside_at(value, r + 1, height))] + \
                   (rows_before_at(value) if windows > 1 else [])

        def columns_at(value):
            return [col_ok[o + r].eq(_column_inside_at(value, o, width)) for o in offsets] + \
                   [col_next.eq(_column_inside_at(value, r + 1, width))]

        # The step's cases, decoded in the admitted slot's round 0 and registered: a jump
        # to a new frame, a restart while the previous one finishes, an advance, a row
        # step at a line end, the switch to the new frame. Each group of registers they
        # step (the column counter and flags, the row counters, the row flags) decodes
        # them from copies of its own of the decision, taken a clock earlier (by an
        # enable of its own, slots.private_first): decoded at every counter bit and flag,
        # they fanned out to all of them (ext. rank 9x9 on ECP5: 6.8 ns; census 11x11:
        # 8.4 ns), and decoded once from the core's decision register, that one decoder
        # drove every group's register (census 9x9: 7.2 ns, 3.9 of them one wire). The
        # registers the cases read do not change between round 0 and the step: steps are
        # a slot apart (R >= 2), and a room flag is a clock late only right after a row
        # step, whose next step is no line end. With R = 1 a step can follow the previous
        # one at once: the cases are decoded in the step's own clock.
        if p.rounds > 1:
            def decision(copy, group):
                first = slots.private_first(-1, copy, f"decision_{group}_round")
                copies = [Signal(name=f"decision_{group}_{flag}")
                          for flag in ("admit", "start", "overlap")]
                m.d.sync += [register.eq(value & first) for register, value in
                             zip(copies, (self.admit, self.start, self.overlap))]
                return copies

            def when(flags, case, name):
                admit, start, overlap = flags
                return pipe(m, admit & case(start, overlap), 1, f"stepping_{name}",
                            reset=True)
        else:
            step_flags = [stepping, pipe(m, start, 1, "stepping_start", reset=True),
                          pipe(m, self.overlap, 2, "stepping_overlap", reset=True)]

            def decision(copy, group):
                return step_flags

            def when(flags, case, name):
                admit, start, overlap = flags
                return admit & case(start, overlap)

        def jump(start, overlap):
            return start & ~overlap

        def advance(start, overlap):
            return ~jump(start, overlap)

        def row_step(start, overlap):
            return advance(start, overlap) & line_end & window_room

        def switching(start, overlap):
            return advance(start, overlap) & switch_window

        columns, counters, flags, control = (
            decision(copy, group)
            for copy, group in enumerate(("columns", "counters", "flags", "control")))
        jump_columns = when(columns, jump, "jump_columns")
        advance_columns = when(columns, advance, "advance_columns")
        jump_counters = when(counters, jump, "jump_counters")
        row_step_counters = when(counters, row_step, "row_step_counters")
        switch_counters = when(counters, switching, "switch_counters")
        y_step = when(counters, lambda s, o: advance(s, o) & line_end & y_room, "y_step")
        switch_tag_step = when(counters, lambda s, o: advance(s, o) & switch_tag,
                               "switch_tag")
        jump_flags = when(flags, jump, "jump_flags")
        row_step_flags = when(flags, row_step, "row_step_flags")
        switch_flags = when(flags, switching, "switch_flags")
        restart = when(control, lambda s, o: s & o, "restart")

        # The previous frame is finished: jump to the new frame's coordinates. The rows'
        # flags follow at once: the first line end may be the next step.
        with m.If(jump_columns):
            m.d.sync += [x.eq(first_x), line_end.eq(first_x == width - 1)]
            m.d.sync += columns_at(first_x)
        with m.If(jump_counters):
            m.d.sync += [y.eq(first_y), window_y.eq(first_y), live.eq(1),
                         y_room.eq(first_y < highest), window_room.eq(first_y < highest)]
        with m.If(jump_flags):
            m.d.sync += rows_at(first_y)
        with m.If(advance_columns):
            m.d.sync += [x.eq(Mux(line_end, 0, x + 1)),
                         line_end.eq(~line_end & (x == width - 2))]
            with m.If(line_end):
                m.d.sync += columns_at(0)
            with m.Else():
                m.d.sync += [col_ok[i].eq(col_ok[i + 1]) for i in range(2 * r)]
                m.d.sync += [col_ok[2 * r].eq(col_next),
                             col_next.eq(column_inside(x, r + 2, width))]
        with m.If(y_step):
            m.d.sync += y.eq(y + 1)
        with m.If(row_step_counters):
            m.d.sync += window_y.eq(window_y + 1)
        with m.If(row_step_flags):
            m.d.sync += [row_ok[i].eq(row_ok[i + 1]) for i in range(top + r)]
            m.d.sync += row_ok[top + r].eq(row_next)
            if windows > 1:
                m.d.sync += [prev_ok[i].eq(prev_ok[i + 1]) for i in range(top + r)]
                m.d.sync += prev_ok[top + r].eq(prev_next)
                # window_y + 1 < k is window_y < k - 1: the flags shift (old[0] stays 0),
                # no comparison of the incremented counter (12 LUT levels on ECP5, census
                # 7x7's critical path at 147 MHz).
                m.d.sync += [old[k].eq(old[k - 1]) for k in range(1, windows)]
        # The window centre reaches the new frame's pixel (0, 0), then the aggregation
        # centre does (the window centre is at (a, a) then); x agrees in both frames.
        with m.If(switch_counters):
            m.d.sync += [window_y.eq(0), window_room.eq(0 < highest)]
        with m.If(switch_flags):
            m.d.sync += rows_at(0)
        with m.If(switch_tag_step):
            m.d.sync += [y.eq(a), live.eq(1), y_room.eq(a < highest)]
        with m.If(restart):
            m.d.sync += [countdown.eq(tag_lag), pending.eq(1),
                         switch_window.eq(tag_lag == window_event),
                         switch_tag.eq(tag_lag == 1)]
        with m.Elif(stepping):
            with m.If(pending):
                # pending is countdown != 0, switch_tag is countdown == 1: registers, not
                # comparisons of the countdown in front of its own enable.
                m.d.sync += [countdown.eq(countdown - 1), pending.eq(~switch_tag),
                             switch_window.eq(countdown == window_event + 1),
                             switch_tag.eq(countdown == 2)]

        # The tag changes with the window's shift (slot-aligned at SHIFTED).
        tag = Signal(layout)
        admitted = pipe(m, stepping, 1, "admitted_tag", reset=True)
        with m.If(slots.first(SHIFTED - 1)):
            m.d.sync += tag.valid.eq(admitted)
        with m.If(admitted):
            m.d.sync += [tag.x.eq(x), tag.y.eq(y), tag.live.eq(live)]

        # Which window pixels lie inside the frame, one register per pixel, from the
        # stepped flags: one flag per window row would fan out to a whole row of both
        # windows (5.6 ns of routing on ECP5).
        # Per window of the column (one but with ``pixels``), row by row of the window.
        # The flags they are formed from change only in the clock after a step, so a
        # flag loaded every clock equals one loaded with the tag: a large window's flags
        # run free, for the tag's enable reaching all of them was ext. rank 17x17's
        # critical path (admitted_tag_p0 to keep_r9_c0, 10.3 ns of wire, 289 flags).
        keeps = []
        for k in range(windows):
            first = window_first_row(p, k)
            keep = [[Signal(name=f"keep_r{row}_c{c}" if k == 0 else f"keep{k}_r{row}_c{c}")
                     for c in range(block)] for row in range(block)]
            with m.If(1 if _large_window(p) else admitted):
                for row in range(block):
                    inside = row_ok[first + row] if k == 0 else \
                        Mux(old[k], prev_ok[first + row], row_ok[first + row])
                    m.d.sync += [keep[row][c].eq(inside & col_ok[c]) for c in range(block)]
            keeps.append(keep)
        return tag, keeps
