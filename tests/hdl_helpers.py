"""Drive ``npstereo_core`` in Amaranth's simulator: AXI4-Stream beats in, words out.

One testbench coroutine plays both the source and the sink, clock by clock, so that random
valid gaps and random backpressure cost no extra simulator processes.
"""

import random

import numpy as np
from amaranth.sim import Simulator

from npstereo.golden.lr_check import INVALID
from npstereo.hdl.core import NpStereoCore

__all__ = ["frame_beats", "run_scenario", "decode_frames", "first_mismatch", "RESET"]

#: A marker in the beat list: assert ``rst`` for one clock at this point of the input.
RESET = "reset"


def frame_beats(left, right, *, drop_last_at=None):
    """AXI beats (tdata, tuser, tlast) of one frame; optionally a missing ``tlast``.

    ``drop_last_at`` is a row whose end-of-line flag is left out (a line that seems too long).
    """
    height, width = left.shape
    beats = []
    for y in range(height):
        for x in range(width):
            last = x == width - 1 and y != drop_last_at
            beats.append((int(left[y, x]) | int(right[y, x]) << 8, x == 0 and y == 0, last))
    return beats


def run_scenario(params, beats, *, valid_prob=1.0, ready_prob=1.0, seed=0, max_cycles=None,
                 core=None):
    """Feed ``beats`` (and RESET markers) through a core; collect every output word.

    Returns
    -------
    dict
        ``words`` (list of (tdata, tuser, tlast)), ``errors`` (framing-error pulses),
        ``cycles`` (clocks until the last word came out).
    """
    core = core or NpStereoCore(params)
    rng = random.Random(seed)
    words, state = [], {"errors": 0, "cycles": 0}
    expected = sum(1 for b in beats if b != RESET)
    limit = max_cycles or int(50 * (len(beats) + core.latency * 4) * params.rounds
                              / min(valid_prob, ready_prob))

    async def bench(ctx):
        index, cycle, last_word_cycle = 0, 0, 0
        while cycle < limit:
            if index < len(beats) and beats[index] == RESET:
                ctx.set(core.s_axis_tvalid, 0)
                await ctx.tick()  # let the sink see nothing new; then reset
                index += 1
                ctx.set(core.m_axis_tready, 0)
                await reset(ctx)
                continue
            offering = index < len(beats) and rng.random() < valid_prob
            if offering:
                data, user, last = beats[index]
                ctx.set(core.s_axis_tdata, data)
                ctx.set(core.s_axis_tuser, user)
                ctx.set(core.s_axis_tlast, last)
            ctx.set(core.s_axis_tvalid, offering)
            ready = rng.random() < ready_prob
            ctx.set(core.m_axis_tready, ready)
            if offering and ctx.get(core.s_axis_tready):
                index += 1
            if ready and ctx.get(core.m_axis_tvalid):
                words.append((ctx.get(core.m_axis_tdata), ctx.get(core.m_axis_tuser),
                              ctx.get(core.m_axis_tlast)))
                last_word_cycle = cycle
            state["errors"] += ctx.get(core.framing_error)
            await ctx.tick()
            cycle += 1
            if index >= len(beats) and len(words) >= expected and cycle > last_word_cycle + 4 \
                    * core.latency * params.rounds:
                break
        state["cycles"] = last_word_cycle + 1

    async def reset(ctx):
        ctx.set(sim_reset, 1)
        await ctx.tick()
        ctx.set(sim_reset, 0)

    sim = Simulator(core)
    sim.add_clock(1e-8)
    sim_reset = _reset_signal(core)
    sim.add_testbench(bench)
    sim.run()
    return {"words": words, **state}


def _reset_signal(core):
    """The sync domain's reset, created the way ``convert`` would create it."""
    from amaranth.hdl import ResetSignal
    return ResetSignal("sync")


def decode_frames(words, params):
    """Split output words at ``tuser`` into H x W int16 maps (INVALID where not valid)."""
    width, height = params.width, params.height
    n_bits = params.disparity_bits
    top = 8 * -(-(n_bits + 1) // 8) - 1
    frames, current = [], None
    for data, user, _ in words:
        if user:
            current = []
            frames.append(current)
        if current is not None:
            current.append(data)
    maps = []
    for values in frames:
        out = np.full(width * height, INVALID - 1, dtype=np.int16)  # -2: missing
        for i, data in enumerate(values[:width * height]):
            out[i] = data & ((1 << n_bits) - 1) if data >> top & 1 else INVALID
        maps.append(out.reshape(height, width))
    return maps


def first_mismatch(expected, got):
    """None, or a message with the first differing pixel (raster order)."""
    diff = np.argwhere(expected != got)
    if len(diff) == 0:
        return None
    y, x = diff[0]
    return (f"{len(diff)} pixels differ; first at x={x}, y={y}: expected "
            f"{expected[y, x]}, got {got[y, x]}")
