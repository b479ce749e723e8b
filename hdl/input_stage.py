"""Input stage: line buffers and B x B windows of both images (the paper's Fig. 1, left).

Hardware counterpart of the golden model's zero-padded windows
(:func:`npstereo.golden.transform.neighbour_planes`). Pixels arrive in raster order, one
*position* per ``advance``. One :class:`~amaranth.lib.memory.Memory` per image (depth W,
B-1 pixels wide) holds the previous B-1 rows of every column, so each position yields a
raster-continuous column of B pixels; a shift register of B columns forms the window.
The window centre trails the newest pixel by r rows and r columns; a mask computed from the
centre's counters clears every window pixel outside the frame (zero padding without extra
cycles at line ends).
"""

from amaranth.hdl import Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from .common import column_inside, tag_layout, y_range
from .plan import input_latency

__all__ = ["InputStage"]


def _row_inside(y, offset, height):
    """Window row ``offset`` (-r .. r) of a centre in row ``y`` lies inside the frame."""
    return (y >= -offset) & (y < height - offset)


class InputStage(wiring.Component):
    """Windows of both images around one centre per ``advance``.

    Parameters
    ----------
    params : StereoParams
        Needs ``width`` and ``height``.

    Attributes
    ----------
    left, right : In(8)
        The pixel entering with this ``advance`` (0 for dummy flush positions).
    advance : In(1)
        Take one position: shift the window, write the line buffers, step the counters.
    start : In(1)
        With ``advance``: this pixel is (0, 0) of a new frame (restarts the counters).
    window_left, window_right : Out(ArrayLayout(unsigned(8), B * B))
        Masked windows, row-major (pixel (dy, dx) at (dy + r) * B + dx + r).
    tag : Out(tag_layout)
        Centre of the windows; ``round`` is 0 (positions have no rounds here).
    latency : int
        Positions from a pixel's entry to the window centred on it: r * W + r
        (:func:`~.plan.input_latency`).
    """

    def __init__(self, params):
        self.params = params
        self.latency = input_latency(params)
        window = data.ArrayLayout(unsigned(8), params.block * params.block)
        super().__init__({
            "left": In(8), "right": In(8), "advance": In(1), "start": In(1),
            "window_left": Out(window), "window_right": Out(window),
            "tag": Out(tag_layout(params)),
        })

    def elaborate(self, platform):
        p = self.params
        width, height, block, r = p.width, p.height, p.block, p.radius
        m = Module()

        # The line buffers' read address is the column after the incoming pixel's; it is
        # kept in a register (col_after) rather than incremented in front of the block
        # RAMs' address inputs.
        col = Signal(range(width))
        col_after = Signal(range(width))
        addr = Mux(self.start, 0, col)
        next_addr = Mux(self.start, 1, col_after)
        with m.If(self.advance):
            m.d.sync += [col.eq(next_addr),
                         col_after.eq(Mux(next_addr == width - 1, 0, next_addr + 1))]

        # Centre counters: position 0 of a frame is centred r rows and r columns earlier.
        first = -(r * width + r)
        first_x, first_y = first % width, first // width
        _, highest = y_range(p)
        tag = Signal(tag_layout(p))
        next_x = Signal.like(tag.x)
        next_y = Signal.like(tag.y)
        with m.If(self.start):
            m.d.comb += [next_x.eq(first_x), next_y.eq(first_y)]
        with m.Elif(tag.x == width - 1):
            m.d.comb += [next_x.eq(0), next_y.eq(Mux(tag.y < highest, tag.y + 1, tag.y))]
        with m.Else():
            m.d.comb += [next_x.eq(tag.x + 1), next_y.eq(tag.y)]
        with m.If(self.advance):
            m.d.sync += [tag.live.eq(1), tag.x.eq(next_x), tag.y.eq(next_y)]
        m.d.comb += self.tag.eq(tag)

        # Which window rows/columns lie inside the frame, registered with the counters
        # from their next values: comparing the counters in the same clock would put two
        # carry chains (this one and the transform's comparison) in front of the
        # transform's first register.
        row_ok = [Signal(name=f"row_ok{k}") for k in range(block)]
        col_ok = [Signal(name=f"col_ok{k}") for k in range(block)]
        for k, offset in enumerate(range(-r, r + 1)):
            with m.If(self.advance):
                m.d.sync += row_ok[k].eq(_row_inside(next_y, offset, height))
                m.d.sync += col_ok[k].eq(column_inside(next_x, offset, width))
        keep = [[Signal(name=f"keep_r{row}_c{c}") for c in range(block)]
                for row in range(block)]
        m.d.comb += [keep[row][c].eq(row_ok[row] & col_ok[c])
                     for row in range(block) for c in range(block)]
        for name, pixel, window in (("left", self.left, self.window_left),
                                    ("right", self.right, self.window_right)):
            # Slot s of the line buffer holds the pixel s + 1 rows above the newest one.
            m.submodules[f"lines_{name}"] = lines = Memory(
                shape=unsigned(8 * (block - 1)), depth=width, init=[])
            rd = lines.read_port(domain="sync")
            wr = lines.write_port()
            older = [rd.data[8 * s:8 * s + 8] for s in range(block - 1)]
            m.d.comb += [
                rd.addr.eq(next_addr), rd.en.eq(self.advance),
                wr.addr.eq(addr), wr.en.eq(self.advance),
                wr.data.eq(Cat(pixel, *older[:block - 2])),
            ]
            # Column c (0 = oldest, dx = -r) packs its B pixels top (dy = -r) to bottom.
            newest_column = Cat(*reversed(older), pixel)
            columns = [Signal(8 * block, name=f"{name}_column{c}") for c in range(block)]
            with m.If(self.advance):
                m.d.sync += [columns[c].eq(columns[c + 1]) for c in range(block - 1)]
                m.d.sync += columns[block - 1].eq(newest_column)
            # One assignment of the whole window: per-element assignments would each cost a
            # full-width assignment cell in the netlist.
            m.d.comb += window.eq(Cat(Mux(keep[row][c], columns[c][8 * row:8 * row + 8], 0)
                                      for row in range(block) for c in range(block)))
        return m
