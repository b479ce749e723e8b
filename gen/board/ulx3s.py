"""The ULX3S top: the 25 MHz oscillator through the ECP5 PLL, the resets, the design
(:class:`~.display.DepthDisplay`) in the pixel clock, TMDS onto the GPDI (HDMI) connector.

amaranth-boards' ``ULX3S_85F_Platform`` names the pins: ``clk25`` and ``hdmi`` (the GPDI
connector: ``d`` the three data pairs, blue, green, red; ``clk`` the clock pair,
LVCMOS33D). The PLL's dividers are ecppll's (Project Trellis) for 25 MHz in, 125 MHz
(CLKOP, the DDR serialisers' ``shift`` domain) and 25 MHz (CLKOS, the pixel clock
``sync``) out, both from one 625 MHz VCO and in phase. LED 0 lights once the first
disparity map is in the frame buffer, LED 1 while the PLL is locked.

The buttons are not used: the core holds one configuration (one transform, one penalty
set), chosen when the bitstream is built.
"""

from amaranth.hdl import ClockDomain, ClockSignal, Instance, Module, Signal
from amaranth.lib import io, wiring
from amaranth.lib.cdc import ResetSynchronizer

from .tmds import Serialiser, TMDSEncoder

__all__ = ["ULX3STop"]

#: EHXPLLL parameters from ``ecppll -i 25 -o 125 --clkout1 25``.
_PLL = dict(
    p_PLLRST_ENA="DISABLED", p_INTFB_WAKE="DISABLED", p_STDBY_ENABLE="DISABLED",
    p_DPHASE_SOURCE="DISABLED", p_OUTDIVIDER_MUXA="DIVA", p_OUTDIVIDER_MUXB="DIVB",
    p_OUTDIVIDER_MUXC="DIVC", p_OUTDIVIDER_MUXD="DIVD", p_CLKI_DIV=1,
    p_CLKOP_ENABLE="ENABLED", p_CLKOP_DIV=5, p_CLKOP_CPHASE=2, p_CLKOP_FPHASE=0,
    p_CLKOS_ENABLE="ENABLED", p_CLKOS_DIV=25, p_CLKOS_CPHASE=2, p_CLKOS_FPHASE=0,
    p_FEEDBK_PATH="CLKOP", p_CLKFB_DIV=5,
    a_FREQUENCY_PIN_CLKI="25", a_FREQUENCY_PIN_CLKOP="125", a_FREQUENCY_PIN_CLKOS="25",
    a_ICP_CURRENT="12", a_LPF_RESISTOR="8", a_MFG_ENABLE_FILTEROPAMP="1",
    a_MFG_GMCREF_SEL="2",
)


class ULX3STop(wiring.Component):
    """The whole board design around a :class:`~.display.DepthDisplay` (built for the
    640x480 timing)."""

    def __init__(self, display):
        self.display = display
        super().__init__({})

    def elaborate(self, platform):
        m = Module()
        m.submodules.clk25 = clk25 = io.Buffer("i", platform.request("clk25", 0, dir="-"))
        m.domains.sync = ClockDomain("sync")
        m.domains.shift = ClockDomain("shift")
        locked = Signal()
        # No constraint of our own on the PLL's outputs: nextpnr derives them (125 and
        # 25 MHz) from the oscillator's, which the platform sets on clk25; constraints on
        # named nets were lost to Yosys' net merging and ignored.
        m.submodules.pll = Instance(
            "EHXPLLL", **_PLL,
            i_RST=0, i_STDBY=0, i_CLKI=clk25.i, i_CLKFB=ClockSignal("shift"),
            i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=1, i_PHASESTEP=1, i_PHASELOADREG=1,
            i_PLLWAKESYNC=0, i_ENCLKOP=0,
            o_CLKOP=ClockSignal("shift"), o_CLKOS=ClockSignal("sync"), o_LOCK=locked)
        m.submodules.sync_reset = ResetSynchronizer(~locked, domain="sync")
        m.submodules.shift_reset = ResetSynchronizer(~locked, domain="shift")

        m.submodules.display = display = self.display
        hdmi = platform.request("hdmi", 0, dir={name: "-" for name in
                                                ("d", "clk", "cec", "eth", "scl", "sda")})
        m.submodules.serialiser = serialiser = Serialiser(hdmi.d, hdmi.clk)
        for name, lane in (("blue", display.b), ("green", display.g), ("red", display.r)):
            encoder = m.submodules[f"tmds_{name}"] = TMDSEncoder()
            m.d.comb += [encoder.data.eq(lane), encoder.de.eq(display.de),
                         getattr(serialiser, name).eq(encoder.symbol)]
            if name == "blue":
                m.d.comb += [encoder.c0.eq(display.hsync), encoder.c1.eq(display.vsync)]

        for index, lit in enumerate((display.map_ready, locked)):
            led = m.submodules[f"led_{index}"] = io.Buffer("o", platform.request("led", index,
                                                                                 dir="-"))
            m.d.comb += led.o.eq(lit)
        return m
