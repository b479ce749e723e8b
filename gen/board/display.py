"""The board's design up to the TMDS encoders: a stored stereo pair, the core, a frame
buffer of its disparity map and the scan-out of the colour-mapped map.

:class:`DepthDisplay` runs in one clock domain (``sync``), the pixel clock: the core
computes a frame of W x H positions in W x H x R clocks (160 x 120, R = 4: 3 ms at
25 MHz), far within a video frame, so it needs no clock of its own.

- The pair is a ROM of :class:`~npstereo.hdl.stream.PixelPair` words, streamed through
  the core frame after frame (the core takes frames back to back), honouring its
  ``ready``.
- Every output word goes into the frame buffer, at 0 on the frame's ``first`` beat and at
  the next address after that; ``map_ready`` rises once a whole map is in.
- The scan-out (:class:`Scanout`) reads the buffer at the video beam's map position and
  looks the disparity up in the colour ROM (:func:`~.video.colour_table`); invalid
  positions and the screen around the map are black.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import Out

from ...hdl.core import NpStereoCore
from ...hdl.stream import WordCodec
from .video import colour_table, placement

__all__ = ["DepthDisplay", "Scanout", "PIPELINE"]

#: Clocks from the beam counters to the colour: the map position, the frame buffer's
#: read, the colour ROM's read.
PIPELINE = 3


class Scanout(wiring.Component):
    """Video timing and the colour-mapped frame buffer at the beam's position.

    ``address``/``word`` are the frame buffer's read port (registered read: the word of an
    address comes a clock later), ``word`` being an output value (a disparity scaled by
    2^``bits``) with its valid flag on top.
    ``r``, ``g``, ``b``, ``hsync``, ``vsync`` and ``de`` are what the TMDS encoders take.
    """

    def __init__(self, timing, width, height, disparities, colours=None, bits=0):
        self.timing = timing
        self.where = placement(width, height, timing)
        self.colours = colour_table(disparities, bits) if colours is None else colours
        self.disparity_bits = max(1, (disparities - 1).bit_length()) + bits
        super().__init__({
            "address": Out(range(width * height)),
            "word": wiring.In(self.disparity_bits + 1),
            "r": Out(8), "g": Out(8), "b": Out(8),
            "hsync": Out(1), "vsync": Out(1), "de": Out(1),
        })

    def elaborate(self, platform):
        t, where = self.timing, self.where
        m = Module()
        # The beam.
        h = Signal(range(t.h_total))
        v = Signal(range(t.v_total))
        end_of_line = h == t.h_total - 1
        m.d.sync += h.eq(Mux(end_of_line, 0, h + 1))
        with m.If(end_of_line):
            m.d.sync += v.eq(Mux(v == t.v_total - 1, 0, v + 1))
        de = (h < t.h_active) & (v < t.v_active)
        hsync = (h >= t.h_active + t.h_front) & (h < t.h_active + t.h_front + t.h_sync)
        vsync = (v >= t.v_active + t.v_front) & (v < t.v_active + t.v_front + t.v_sync)

        # Stage 1, a clock after the beam: the map position of the beam's pixel. The
        # columns restart where the map starts on every line, the rows where it starts in
        # the frame (updated as a line begins); both advance every ``scale`` beam pixels
        # or lines, so no division.
        scale, width = where.scale, where.width
        column = Signal(range(width + 1))
        sub_column = Signal(range(scale))
        row_base = Signal(range(width * (where.height + 1)))
        sub_row = Signal(range(scale))
        inside_x = Signal()
        inside_y = Signal()
        m.d.sync += inside_x.eq((h >= where.x0) & (h < where.x0 + scale * width))
        with m.If(h == where.x0):
            m.d.sync += [column.eq(0), sub_column.eq(0)]
        with m.Elif(sub_column == scale - 1):
            m.d.sync += [column.eq(column + 1), sub_column.eq(0)]
        with m.Else():
            m.d.sync += sub_column.eq(sub_column + 1)
        with m.If(h == 0):
            m.d.sync += inside_y.eq((v >= where.y0) & (v < where.y0 + scale * where.height))
            with m.If(v == where.y0):
                m.d.sync += [row_base.eq(0), sub_row.eq(0)]
            with m.Elif(sub_row == scale - 1):
                m.d.sync += [row_base.eq(row_base + width), sub_row.eq(0)]
            with m.Else():
                m.d.sync += sub_row.eq(sub_row + 1)
        inside = inside_x & inside_y
        m.d.comb += self.address.eq(Mux(inside, row_base + column, 0))

        # Stage 2: the frame buffer's word; stage 3: its colour.
        entries = len(self.colours)
        m.submodules.colours = rom = Memory(
            shape=unsigned(24), depth=entries,
            init=[int(r) | int(g) << 8 | int(b) << 16 for r, g, b in self.colours])
        colour = rom.read_port()
        disparity = self.word[:self.disparity_bits]
        m.d.comb += colour.addr.eq(disparity)
        inside_2, shown_3 = Signal(), Signal()
        m.d.sync += [inside_2.eq(inside),
                     shown_3.eq(inside_2 & self.word[-1] & (disparity < entries))]

        flags = Cat(de, hsync, vsync)
        delayed = flags
        for stage in range(PIPELINE):
            registered = Signal(3, name=f"sync_{stage + 1}")
            m.d.sync += registered.eq(delayed)
            delayed = registered
        polarity = Const(1 if t.negative else 0, 1)
        m.d.comb += [
            self.de.eq(delayed[0]),
            self.hsync.eq(delayed[1] ^ polarity), self.vsync.eq(delayed[2] ^ polarity),
            Cat(self.r, self.g, self.b).eq(Mux(shown_3 & delayed[0], colour.data, 0)),
        ]
        return m


class DepthDisplay(wiring.Component):
    """The stored pair through an :class:`NpStereoCore` onto a video output.

    Parameters
    ----------
    params : StereoParams
        The core's, with the pair's width and height.
    left, right : (H, W) uint8 arrays
        The stored pair.
    timing : VideoTiming
    colours : ((D-1) 2^F + 1, 3) uint8 array, optional
        The colour ROM of the output values (default :func:`~.video.colour_table`; with
        F = 0 one entry a disparity).

    Members
    -------
    r, g, b, hsync, vsync, de : Out
        The video output (to the TMDS encoders).
    map_ready : Out(1)
        High from the clock after the first whole map is in the frame buffer.
    """

    def __init__(self, params, left, right, timing, colours=None):
        self.params = params
        self.words = WordCodec(params).pack_pixels(left, right).tolist()
        self.core = NpStereoCore(params)
        self.scanout = Scanout(timing, params.width, params.height, params.disparities,
                               colours, params.subpixel_bits)
        super().__init__({"r": Out(8), "g": Out(8), "b": Out(8), "hsync": Out(1),
                          "vsync": Out(1), "de": Out(1), "map_ready": Out(1)})

    def elaborate(self, platform):
        p = self.params
        pixels, width = p.width * p.height, p.width
        m = Module()
        m.submodules.core = core = self.core
        m.submodules.scanout = scan = self.scanout

        # The pair, frame after frame. The ROM's registered read gives the word of the
        # address of the previous clock: the address is the next index when the current
        # beat is taken, so the word on the port is always the one of ``index``.
        m.submodules.pair = pair = Memory(shape=unsigned(16), depth=pixels, init=self.words)
        read = pair.read_port()
        index = Signal(range(pixels))
        column = Signal(range(width))
        primed = Signal()           # the port holds the word of ``index`` (from reset's next clock)
        sink = core.sink
        taken = sink.valid & sink.ready
        following = Mux(index == pixels - 1, 0, index + 1)
        m.d.comb += [
            read.addr.eq(Mux(taken, following, index)),
            sink.valid.eq(primed),
            sink.payload.data.eq(read.data),
            sink.payload.first.eq(index == 0),
            sink.payload.last.eq(column == width - 1),
        ]
        m.d.sync += primed.eq(1)
        with m.If(taken):
            m.d.sync += [index.eq(following), column.eq(Mux(column == width - 1, 0, column + 1))]

        # The frame buffer: one word per output beat, the value with the valid flag on top.
        word_bits = scan.disparity_bits + 1
        m.submodules.frame = frame = Memory(shape=unsigned(word_bits), depth=pixels, init=[])
        write, shown = frame.write_port(), frame.read_port()
        source = core.source
        written = Signal(range(pixels))     # the address after the last word written
        at = Mux(source.payload.first, 0, written)
        m.d.comb += [
            source.ready.eq(1),
            write.en.eq(source.valid), write.addr.eq(at),
            write.data.eq(Cat(source.payload.data.disparity[:scan.disparity_bits],
                              source.payload.data.valid)),
            shown.addr.eq(scan.address), scan.word.eq(shown.data),
        ]
        with m.If(source.valid):
            m.d.sync += written.eq(Mux(at == pixels - 1, 0, at + 1))
            with m.If(at == pixels - 1):
                m.d.sync += self.map_ready.eq(1)

        m.d.comb += [self.r.eq(scan.r), self.g.eq(scan.g), self.b.eq(scan.b),
                     self.hsync.eq(scan.hsync), self.vsync.eq(scan.vsync), self.de.eq(scan.de)]
        return m
