"""The core for Amaranth designs: ``amaranth.lib.stream`` in and out.

:class:`~.core.NpStereoCore` is the Verilog top level, with AXI4-Stream video port names
so that it drops into vendor video pipelines. An Amaranth design wants streams instead:
:class:`StereoStream` wraps the same core (no logic of its own, so the generated core
and everything proved about it stay the same) behind a ``sink`` of pixel pairs and a
``source`` of disparities, each a :class:`amaranth.lib.stream.Signature` with
valid/ready handshaking.
"""

from amaranth.hdl import Cat, Module, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from .core import NpStereoCore

__all__ = ["PixelPair", "disparity_layout", "StereoStream"]


class PixelPair(data.Struct):
    """One input beat: both images' pixels at the same position, with framing flags."""
    left: unsigned(8)
    right: unsigned(8)
    first: unsigned(1)   # start of frame (AXI ``tuser``): pixel (0, 0)
    last: unsigned(1)    # end of line (AXI ``tlast``): pixel (W-1, y)


def disparity_layout(params):
    """One output beat: the disparity of a position, its valid flag and framing flags."""
    return data.StructLayout({"disparity": unsigned(params.disparity_bits),
                              "valid": unsigned(1), "first": unsigned(1),
                              "last": unsigned(1)})


class StereoStream(wiring.Component):
    """Streaming stereo core with ``amaranth.lib.stream`` interfaces.

    Parameters
    ----------
    params : StereoParams
        With ``width`` and ``height``.

    Members
    -------
    sink : In(stream.Signature(PixelPair))
        Pixel pairs in raster order; ``first`` on (0, 0), ``last`` on every line's end.
    source : Out(stream.Signature(disparity_layout(params)))
        One beat per input pixel in raster order; ``disparity`` is 0 where ``valid`` is 0.
    framing_error : Out(1)
        One-clock pulse per framing error (docs/semantics.md, "Hardware").
    """

    def __init__(self, params):
        self.params = params
        self.core = NpStereoCore(params)
        super().__init__({
            "sink": In(stream.Signature(PixelPair)),
            "source": Out(stream.Signature(disparity_layout(params))),
            "framing_error": Out(1),
        })

    @property
    def latency(self):
        """Positions from a pixel's entry to its output beat (without stalls)."""
        return self.core.latency

    def elaborate(self, platform):
        m = Module()
        m.submodules.core = core = self.core
        bits = self.params.disparity_bits
        m.d.comb += [
            core.s_axis_tdata.eq(Cat(self.sink.payload.left, self.sink.payload.right)),
            core.s_axis_tuser.eq(self.sink.payload.first),
            core.s_axis_tlast.eq(self.sink.payload.last),
            core.s_axis_tvalid.eq(self.sink.valid),
            self.sink.ready.eq(core.s_axis_tready),
            self.source.payload.disparity.eq(core.m_axis_tdata[:bits]),
            self.source.payload.valid.eq(core.m_axis_tdata[-1]),
            self.source.payload.first.eq(core.m_axis_tuser),
            self.source.payload.last.eq(core.m_axis_tlast),
            self.source.valid.eq(core.m_axis_tvalid),
            core.m_axis_tready.eq(self.source.ready),
            self.framing_error.eq(core.framing_error),
        ]
        return m
