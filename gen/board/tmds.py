"""DVI's TMDS: the 8b/10b encoder of one channel, and the serialiser of the four lanes.

The encoder is the DVI 1.0 specification's (section 3.3.1): the 8 data bits become 9 with
the fewest transitions (XOR or XNOR chain), then the 9th bit chooses whether the 8 are
sent inverted to keep the running disparity near 0; in blanking, the two control bits
(hsync and vsync on the blue channel) are sent as one of four fixed symbols.

The serialiser sends a symbol, least significant bit first, in 5 clocks of the ``shift``
domain (5x the pixel clock) through ECP5 DDR output registers (ODDRX1F via Amaranth's
:class:`~amaranth.lib.io.DDRBuffer`): 10 bits per pixel clock, 250 Mbit/s per lane at
25 MHz, as the ULX3S DVI examples do. Both clocks come from one PLL, in phase: a symbol
changes on a pixel clock edge, which is also a ``shift`` edge, so the load 5 edges later
reads it a whole ``shift`` period after it changed.
"""

from amaranth.hdl import Cat, Const, Module, Mux, Signal, signed
from amaranth.lib import io, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["CONTROL_SYMBOLS", "CLOCK_SYMBOL", "TMDSEncoder", "Serialiser"]

#: The symbol of each (c1, c0) in blanking (DVI 1.0, section 3.3.3), indexed c1 * 2 + c0.
CONTROL_SYMBOLS = (0b1101010100, 0b0010101011, 0b0101010100, 0b1010101011)
#: The clock lane: five ones, five zeros each pixel clock.
CLOCK_SYMBOL = 0b0000011111


def _ones(value, width):
    return sum(value[i] for i in range(width))


class TMDSEncoder(wiring.Component):
    """One channel: ``data`` when ``de``, else the control symbol of (``c1``, ``c0``);
    ``symbol`` is registered (a clock later)."""

    data: In(8)
    c0: In(1)
    c1: In(1)
    de: In(1)
    symbol: Out(10)

    def elaborate(self, platform):
        m = Module()
        d = self.data
        # Stage 1: the transition-minimised 9 bits (and the counts the balance needs),
        # registered with the controls.
        ones = _ones(d, 8)
        use_xnor = (ones > 4) | ((ones == 4) & ~d[0])
        chain = [d[0]]
        for i in range(1, 8):
            chain.append(Mux(use_xnor, ~(chain[-1] ^ d[i]), chain[-1] ^ d[i]))
        q_m = Signal(9)
        de, c0, c1 = Signal(), Signal(), Signal()
        m.d.sync += [q_m.eq(Cat(*chain, ~use_xnor)), de.eq(self.de), c0.eq(self.c0),
                     c1.eq(self.c1)]

        # Stage 2: DC balance against the running disparity (ones minus zeros sent).
        count = Signal(signed(6))
        ones_q = _ones(q_m, 8)
        balance = Signal(signed(5))                 # ones minus zeros of q_m[0:8]
        m.d.comb += balance.eq(2 * ones_q - 8)
        low, kept = q_m[:8], q_m[8]
        with m.If(~de):
            m.d.sync += [count.eq(0),
                         self.symbol.eq(Mux(c1, Mux(c0, CONTROL_SYMBOLS[3], CONTROL_SYMBOLS[2]),
                                            Mux(c0, CONTROL_SYMBOLS[1], CONTROL_SYMBOLS[0])))]
        with m.Elif((count == 0) | (balance == 0)):
            m.d.sync += [self.symbol.eq(Cat(Mux(kept, low, ~low), kept, ~kept)),
                         count.eq(count + Mux(kept, balance, -balance))]
        with m.Elif(((count > 0) & (balance > 0)) | ((count < 0) & (balance < 0))):
            m.d.sync += [self.symbol.eq(Cat(~low, kept, Const(1, 1))),
                         count.eq(count + Mux(kept, 2, 0) - balance)]
        with m.Else():
            m.d.sync += [self.symbol.eq(Cat(low, kept, Const(0, 1))),
                         count.eq(count - Mux(kept, 0, 2) + balance)]
        return m


class Serialiser(wiring.Component):
    """The four lanes' symbols (``sync``) onto DDR output buffers (``shift``, 5x).

    ``data_port``: the three data lanes (blue, green, red: DVI channels 0, 1, 2);
    ``clock_port``: the clock lane. Ports as ``platform.request(..., dir="-")`` gives them.
    """

    blue: In(10)
    green: In(10)
    red: In(10)

    def __init__(self, data_port, clock_port):
        self.data_port, self.clock_port = data_port, clock_port
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        m.submodules.data = data = io.DDRBuffer("o", self.data_port, o_domain="shift")
        m.submodules.clock = clock = io.DDRBuffer("o", self.clock_port, o_domain="shift")
        phase = Signal(range(5))
        m.d.shift += phase.eq(Mux(phase == 4, 0, phase + 1))
        lanes = []
        for symbol in (self.blue, self.green, self.red, Const(CLOCK_SYMBOL, 10)):
            shifter = Signal(10)
            with m.If(phase == 0):
                m.d.shift += shifter.eq(symbol)
            with m.Else():
                m.d.shift += shifter.eq(shifter >> 2)
            lanes.append(shifter)
        m.d.comb += [
            data.o[0].eq(Cat(lane[0] for lane in lanes[:3])),
            data.o[1].eq(Cat(lane[1] for lane in lanes[:3])),
            clock.o[0].eq(lanes[3][0]), clock.o[1].eq(lanes[3][1]),
        ]
        return m
