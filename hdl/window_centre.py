"""Window centre of the input stage: its coordinates, the frames' overlap, the window masks.

The input stage's windows (:class:`~.input_stage.InputStage`) are centred r rows and r
columns behind the newest pixel. :func:`track_centre` counts that centre's coordinates, one
step per admitted position, and forms from them the tag that leaves with the windows and the
masks that clear every window pixel outside the frame (zero padding without extra cycles at
line ends).

Frames may follow each other without a flush: when a frame starts right after the previous
one (``overlap``), the centre keeps the previous frame's coordinates until it reaches the
new frame's first pixel, r rows and r columns later, so the previous frame's last rows are
still computed (their window rows below the frame are masked, whatever pixels the new frame
put there).
"""

from amaranth.hdl import Mux, Signal

from .common import column_inside, pipe, replica, tag_layout, y_range
from .plan_structure import transformed_rows, window_first_row, window_rows

__all__ = ["track_centre"]


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


def track_centre(m, stage, slots, admit, start, *, shifted, large_window):
    """The centre's tag and the window masks, updated with the window.

    The tag is slot-aligned at offset ``shifted`` (the stage delays it further with
    the masked window): x, y and live change with each
    admitted position, ``valid`` says in every slot whether it carries one.

    Two frames' coordinates coexist while frames overlap. The window masks follow the
    *window centre's* frame: a pixel's transform sees zeros outside its own frame. The
    tag that leaves the stage names the same position, but in the frame of the
    *aggregation centre*, a rows and a columns further back, for everything after the
    transforms masks rows and columns relative to that centre: the finishing frame's
    last aggregation window must see the new frame's first row as outside. So the tag
    switches to the new frame a*W + a positions after the window masks do.

    ``stage`` is the :class:`~.input_stage.InputStage`: its parameters, its ports of the
    core's decision (``admit``, ``start``, ``overlap``, a clock ahead of the stage's
    registers of them) and ``switch_pending``, which this drives. ``admit`` and ``start``
    are the stage's registers of the decision (round 0 of the admitted slot). ``shifted``
    is the clock of the window's shift after the admission; with ``large_window``
    (:func:`~.input_stage._large_window`) the mask flags load every clock (see below).

    Returns the tag register and, per window of the column (the newest first),
    ``keep[row][column]``, 1 where the window pixel lies inside the window centre's
    frame.
    """
    p = stage.params
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
    # line_end & window_room, set with line_end: the row step's case one flag instead of
    # two (the row flags' step was four LUTs deep, census 5x5 box at 1280 x 720, R = 1:
    # 7.68 ns from the step's start flag through window_y_room to prev_ok3).
    line_end_room = Signal(name="centre_line_end_room")
    y_room, window_room = Signal(name="y_room"), Signal(name="window_y_room")
    switch_window = Signal(name="switch_window")           # countdown == window event
    switch_tag = Signal(name="switch_tag")                 # countdown == 1
    # A register of its own, not a comparison: it feeds the admission decision.
    pending = Signal()
    m.d.comb += stage.switch_pending.eq(pending)
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
    # one at once: the cases are decoded in the step's own clock, from copies of the
    # decision of each group's own (one register of the overlap flag for all groups was
    # census 5x5 box's critical path at 1280 x 720: 10.18 ns to the row counter, 3
    # levels).
    if p.rounds > 1:
        def decision(copy, group):
            first = slots.private_first(-1, copy, f"decision_{group}_round")
            copies = [Signal(name=f"decision_{group}_{flag}")
                      for flag in ("admit", "start", "overlap")]
            m.d.sync += [register.eq(value & first) for register, value in
                         zip(copies, (stage.admit, stage.start, stage.overlap))]
            return copies

        def when(flags, case, name):
            admit, start, overlap = flags
            return pipe(m, admit & case(start, overlap), 1, f"stepping_{name}",
                        reset=True)
    else:
        overlap = pipe(m, stage.overlap, 1, "stepping_overlap", reset=True)

        def decision(copy, group):
            return [replica(m, value, f"stepping_{group}_{flag}") for flag, value in
                    (("admit", admit), ("start", start), ("overlap", overlap))]

        def when(flags, case, name):
            admit, start, overlap = flags
            return admit & case(start, overlap)

    def jump(start, overlap):
        return start & ~overlap

    def advance(start, overlap):
        return ~jump(start, overlap)

    def row_step(start, overlap):
        return advance(start, overlap) & line_end_room

    def switching(start, overlap):
        return advance(start, overlap) & switch_window

    columns, counters, flags, control = (
        decision(copy, group)
        for copy, group in enumerate(("columns", "counters", "flags", "control")))
    jump_columns = when(columns, jump, "jump_columns")
    advance_columns = when(columns, advance, "advance_columns")
    switch_columns = when(columns, switching, "switch_columns")
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
        m.d.sync += [x.eq(first_x), line_end.eq(first_x == width - 1),
                     line_end_room.eq(first_x == width - 1 and first_y < highest)]
        m.d.sync += columns_at(first_x)
    with m.If(jump_counters):
        m.d.sync += [y.eq(first_y), window_y.eq(first_y), live.eq(1),
                     y_room.eq(first_y < highest), window_room.eq(first_y < highest)]
    with m.If(jump_flags):
        m.d.sync += rows_at(first_y)
    with m.If(advance_columns):
        # window_room holds until the line end (rows change only there, W > 2 steps
        # apart) unless this step switches the window to row 0.
        room = Mux(switch_columns, int(0 < highest), window_room)
        next_line_end = ~line_end & (x == width - 2)
        m.d.sync += [x.eq(Mux(line_end, 0, x + 1)), line_end.eq(next_line_end),
                     line_end_room.eq(next_line_end & room)]
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

    # The tag changes with the window's shift (slot-aligned at ``shifted``).
    tag = Signal(layout)
    admitted = pipe(m, stepping, 1, "admitted_tag", reset=True)
    with m.If(slots.first(shifted - 1)):
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
        with m.If(1 if large_window else admitted):
            for row in range(block):
                inside = row_ok[first + row] if k == 0 else \
                    Mux(old[k], prev_ok[first + row], row_ok[first + row])
                m.d.sync += [keep[row][c].eq(inside & col_ok[c]) for c in range(block)]
        keeps.append(keep)
    return tag, keeps
