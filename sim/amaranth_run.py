"""One frame through :class:`~npstereo.hdl.core.NpStereoCore` in Amaranth's own simulator.

No Verilog and no external tool: the reference point when a Verilog simulator disagrees.
Amaranth's Python simulator runs a few thousand cycles per second, so small crops only.
"""

from amaranth.sim import Simulator

from ..hdl.core import NpStereoCore
from ..hdl.stream import WordCodec

__all__ = ["run_amaranth"]


def run_amaranth(params, left, right, progress=None):
    """Stream one frame; return (words, first, last, cycles) of the output beats.

    The words are integers (:class:`~npstereo.hdl.stream.WordCodec`), as the Verilog
    simulators deliver them. ``cycles`` counts from the first input handshake to the last
    output beat; ``progress(n)`` is called with the number of further output pixels received.
    """
    core = NpStereoCore(params)
    sink, source = core.sink, core.source
    words = WordCodec(params).pack_pixels(left, right).tolist()
    width, pixels = params.width, params.width * params.height
    got, first, last = [], [], []
    clock = {"cycle": 0, "first_in": None, "last_out": 0}

    async def feed(ctx):
        for index, word in enumerate(words):
            ctx.set(sink.payload.data.as_value(), word)
            ctx.set(sink.payload.first, index == 0)
            ctx.set(sink.payload.last, index % width == width - 1)
            ctx.set(sink.valid, 1)
            await ctx.tick().until(sink.ready)
            if clock["first_in"] is None:
                clock["first_in"] = clock["cycle"]
        ctx.set(sink.valid, 0)

    async def drain(ctx):
        ctx.set(source.ready, 1)
        # Generous bound: R clocks per pixel plus a few lines of latency, then give up.
        limit = pixels * params.rounds * 2 + 64 * width * params.rounds + 1000
        async for _, _, valid, word, first_flag, last_flag in ctx.tick().sample(
                source.valid, source.payload.data.as_value(), source.payload.first,
                source.payload.last):
            clock["cycle"] += 1
            if valid:
                got.append(word)
                first.append(first_flag)
                last.append(last_flag)
                clock["last_out"] = clock["cycle"]
                if progress is not None and len(got) % width == 0:
                    progress(width)
            if len(got) >= pixels or clock["cycle"] > limit:
                break

    sim = Simulator(core)
    sim.add_clock(1e-8)
    sim.add_testbench(feed, background=True)
    sim.add_testbench(drain)
    sim.run()
    cycles = clock["last_out"] - (clock["first_in"] or 0) + 1
    return got, first, last, cycles
