"""The ports of ``npstereo_core`` and how they group into interfaces, for every package
format.

One table, read from the hardware's own widths (:class:`~npstereo.hdl.stream.PixelPair`,
:func:`~npstereo.hdl.plan_structure.output_width`), so that the IP-XACT component and the
Platform Designer component cannot disagree with each other or with the Verilog
(``tests/test_ip.py`` checks all three against the Verilog's ports).
"""

from dataclasses import dataclass

from amaranth.lib import data

from ...hdl.plan_structure import output_width
from ...hdl.stream import PixelPair

__all__ = ["Port", "CLOCK", "RESET", "FRAMING_ERROR", "stream_ports", "STREAMS"]


@dataclass(frozen=True)
class Port:
    name: str          # the Verilog port
    direction: str     # "in" or "out"
    width: int
    role: str          # the AXI4-Stream signal (TDATA ...), or the port's own role


CLOCK = Port("clk", "in", 1, "CLK")
#: Amaranth's synchronous reset: active high, released with the clock.
RESET = Port("rst", "in", 1, "RST")
#: High for one clock when a frame's framing (tuser/tlast) was not the expected one.
FRAMING_ERROR = Port("framing_error", "out", 1, "framing_error")

#: The two AXI4-Stream interfaces: name and whether the core receives on it.
STREAMS = (("s_axis", True), ("m_axis", False))


def stream_ports(params, interface):
    """The ports of the AXI4-Stream interface ``s_axis`` (input pixels) or ``m_axis``
    (disparities), TDATA first."""
    receives = dict(STREAMS)[interface]
    width = data.Layout.cast(PixelPair).size if receives else output_width(params)
    forward, backward = ("in", "out") if receives else ("out", "in")
    return [Port(f"{interface}_tdata", forward, width, "TDATA"),
            Port(f"{interface}_tvalid", forward, 1, "TVALID"),
            Port(f"{interface}_tready", backward, 1, "TREADY"),
            Port(f"{interface}_tuser", forward, 1, "TUSER"),
            Port(f"{interface}_tlast", forward, 1, "TLAST")]
