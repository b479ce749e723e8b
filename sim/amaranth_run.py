"""One frame through :class:`~npstereo.hdl.core.NpStereoCore` in Amaranth's own simulator.

No Verilog and no external tool: the reference point when a Verilog simulator disagrees.
Amaranth's Python simulator runs a few thousand cycles per second, so small crops only.
"""

from amaranth.sim import Simulator

from ..hdl.core import NpStereoCore
from .frames import input_words

__all__ = ["run_amaranth"]


def run_amaranth(params, left, right, progress=None):
    """Stream one frame; return (data, tuser, tlast, cycles) of the output beats.

    ``cycles`` counts from the first input handshake to the last output beat.
    ``progress(n)`` is called with the number of further output pixels received.
    """
    core = NpStereoCore(params)
    words = input_words(left, right).tolist()
    width, pixels = params.width, params.width * params.height
    data, tuser, tlast = [], [], []
    clock = {"cycle": 0, "first_in": None, "last_out": 0}

    async def source(ctx):
        for index, word in enumerate(words):
            ctx.set(core.s_axis_tdata, word)
            ctx.set(core.s_axis_tuser, index == 0)
            ctx.set(core.s_axis_tlast, index % width == width - 1)
            ctx.set(core.s_axis_tvalid, 1)
            await ctx.tick().until(core.s_axis_tready)
            if clock["first_in"] is None:
                clock["first_in"] = clock["cycle"]
        ctx.set(core.s_axis_tvalid, 0)

    async def sink(ctx):
        ctx.set(core.m_axis_tready, 1)
        # Generous bound: R clocks per pixel plus a few lines of latency, then give up.
        limit = pixels * params.rounds * 2 + 64 * width * params.rounds + 1000
        async for _, _, valid, word, user, last in ctx.tick().sample(
                core.m_axis_tvalid, core.m_axis_tdata, core.m_axis_tuser, core.m_axis_tlast):
            clock["cycle"] += 1
            if valid:
                data.append(word)
                tuser.append(user)
                tlast.append(last)
                clock["last_out"] = clock["cycle"]
                if progress is not None and len(data) % width == 0:
                    progress(width)
            if len(data) >= pixels or clock["cycle"] > limit:
                break

    sim = Simulator(core)
    sim.add_clock(1e-8)
    sim.add_testbench(source, background=True)
    sim.add_testbench(sink)
    sim.run()
    cycles = clock["last_out"] - (clock["first_in"] or 0) + 1
    return data, tuser, tlast, cycles
