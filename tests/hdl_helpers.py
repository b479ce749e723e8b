"""Drive ``npstereo_core`` in Amaranth's simulator: AXI4-Stream beats in, words out.

One testbench coroutine plays both the source and the sink, clock by clock, so that random
valid gaps and random backpressure cost no extra simulator processes.
"""

import random

import numpy as np
from amaranth.hdl import ResetInserter, Signal
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


def run_scenario(params, beats, *, valid_prob=1.0, ready_prob=1.0, seed=0, max_cycles=None):
    """Feed ``beats`` (and RESET markers) through a core; collect every output word.

    The source keeps a beat offered until it is taken (AXI rule) but inserts random gaps
    before offering the next; the sink drops ``tready`` at random.

    Returns
    -------
    dict
        ``words`` (list of (tdata, tuser, tlast)), ``errors`` (framing-error pulses),
        ``frame_starts`` (clock of every output word with tuser), ``cycles`` (clocks until
        the last word came out), ``latency`` (the core's, in positions).
    """
    core = NpStereoCore(params)
    rst = Signal()
    dut = ResetInserter({"sync": rst})(core)
    rng = random.Random(seed)
    words, starts, state = [], [], {"errors": 0, "cycles": 0}
    expected = sum(1 for b in beats if b != RESET)
    slack = 4 * core.latency * params.rounds + 50
    limit = max_cycles or int((expected * params.rounds + slack * 3)
                              / min(valid_prob, ready_prob) + slack)

    async def bench(ctx):
        index, cycle, last_word_cycle, offering = 0, 0, 0, False
        while cycle < limit:
            if index < len(beats) and beats[index] == RESET:
                ctx.set(core.s_axis_tvalid, 0)
                ctx.set(core.m_axis_tready, 0)
                ctx.set(rst, 1)
                await ctx.tick()
                ctx.set(rst, 0)
                index, offering = index + 1, False
                cycle += 1
                continue
            if not offering and index < len(beats):
                offering = rng.random() < valid_prob
            if offering:
                data, user, last = beats[index]
                ctx.set(core.s_axis_tdata, data)
                ctx.set(core.s_axis_tuser, user)
                ctx.set(core.s_axis_tlast, last)
            ctx.set(core.s_axis_tvalid, offering)
            ready = rng.random() < ready_prob
            ctx.set(core.m_axis_tready, ready)
            if offering and ctx.get(core.s_axis_tready):
                index, offering = index + 1, False
            if ready and ctx.get(core.m_axis_tvalid):
                word = (ctx.get(core.m_axis_tdata), ctx.get(core.m_axis_tuser),
                        ctx.get(core.m_axis_tlast))
                words.append(word)
                if word[1]:
                    starts.append(cycle)
                last_word_cycle = cycle
            state["errors"] += ctx.get(core.framing_error)
            await ctx.tick()
            cycle += 1
            if index >= len(beats) and cycle > last_word_cycle + slack:
                break
        state["cycles"] = last_word_cycle + 1

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return {"words": words, "frame_starts": starts, "latency": core.latency, **state}


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
