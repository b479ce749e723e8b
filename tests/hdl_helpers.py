"""Drive the core in Amaranth's simulator: input beats in, output words out.

One testbench coroutine plays both the source and the sink, clock by clock, so that random
valid gaps and random backpressure cost no extra simulator processes. It drives either
:class:`~npstereo.hdl.core.NpStereoCore` (AXI4-Stream ports) or
:class:`~npstereo.hdl.stream.StereoStream` (``amaranth.lib.stream`` ports) through the same
handshakes, so both are checked by the same scenarios.
"""

import random

import numpy as np
from amaranth.hdl import ResetInserter, Signal
from amaranth.sim import Simulator

from npstereo.golden.lr_check import INVALID
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl.core import NpStereoCore
from npstereo.hdl.plan import output_width
from npstereo.hdl.stream import StereoStream

__all__ = ["frame_beats", "run_scenario", "decode_frames", "first_mismatch", "check_frames",
           "RESET"]

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


class _AxiPorts:
    """The core's own ports."""

    def __init__(self, core):
        self.core = core
        self.in_valid, self.in_ready = core.s_axis_tvalid, core.s_axis_tready
        self.out_valid, self.out_ready = core.m_axis_tvalid, core.m_axis_tready

    def offer(self, ctx, beat):
        data, user, last = beat
        ctx.set(self.core.s_axis_tdata, data)
        ctx.set(self.core.s_axis_tuser, user)
        ctx.set(self.core.s_axis_tlast, last)

    def word(self, ctx):
        return (ctx.get(self.core.m_axis_tdata), ctx.get(self.core.m_axis_tuser),
                ctx.get(self.core.m_axis_tlast))


class _StreamPorts:
    """``StereoStream``'s sink and source, beats translated to and from the core's words."""

    def __init__(self, stream):
        self.stream = stream
        self.in_valid, self.in_ready = stream.sink.valid, stream.sink.ready
        self.out_valid, self.out_ready = stream.source.valid, stream.source.ready
        self.flag = 1 << (output_width(stream.params) - 1)

    def offer(self, ctx, beat):
        data, user, last = beat
        ctx.set(self.stream.sink.payload, {"left": data & 0xFF, "right": data >> 8,
                                           "first": user, "last": last})

    def word(self, ctx):
        beat = ctx.get(self.stream.source.payload)
        data = (beat.disparity | self.flag) if beat.valid else beat.disparity
        return data, beat.first, beat.last


def run_scenario(params, beats, *, valid_prob=1.0, ready_prob=1.0, seed=0, max_cycles=None,
                 stream=False, before_start=None):
    """Feed ``beats`` (RESET markers: a reset; an int n: n idle clocks) through a core;
    collect every output word.

    The source keeps a beat offered until it is taken (AXI rule) but inserts random gaps
    before offering the next; the sink drops ``tready`` at random. ``before_start(ctx)``
    runs in the testbench before the first clock. With ``stream`` the
    core is a :class:`StereoStream`, driven through its sink and source.

    Returns
    -------
    dict
        ``words`` (list of (tdata, tuser, tlast)), ``errors`` (framing-error pulses),
        ``frame_starts`` (clock of every output word with tuser), ``cycles`` (clocks until
        the last word came out), ``last_input`` (the clock the last beat was taken),
        ``latency`` (the core's, in positions).
    """
    dut = StereoStream(params) if stream else NpStereoCore(params)
    ports = _StreamPorts(dut) if stream else _AxiPorts(dut)
    rst = Signal()
    top = ResetInserter({"sync": rst})(dut)
    rng = random.Random(seed)
    words, starts, state = [], [], {"errors": 0, "cycles": 0}
    beats = list(beats)
    expected = sum(1 for b in beats if b != RESET and not isinstance(b, int))
    slack = 4 * dut.latency * params.rounds + 50
    limit = max_cycles or int((expected * params.rounds + slack * 3)
                              / min(valid_prob, ready_prob) + slack)

    async def bench(ctx):
        if before_start is not None:
            before_start(ctx)
        index, cycle, last_word_cycle, offering = 0, 0, 0, False
        state["last_input"] = None
        while cycle < limit:
            if index < len(beats) and beats[index] == RESET:
                ctx.set(ports.in_valid, 0)
                ctx.set(ports.out_ready, 0)
                ctx.set(rst, 1)
                await ctx.tick()
                ctx.set(rst, 0)
                index, offering = index + 1, False
                cycle += 1
                continue
            if index < len(beats) and isinstance(beats[index], int) and beats[index] > 0:
                # An idle gap: no beat offered for that many clocks.
                beats[index] -= 1
                if not beats[index]:
                    index += 1
                offering = False
            elif not offering and index < len(beats):
                offering = rng.random() < valid_prob
            if offering:
                ports.offer(ctx, beats[index])
            ctx.set(ports.in_valid, offering)
            ready = rng.random() < ready_prob
            ctx.set(ports.out_ready, ready)
            if offering and ctx.get(ports.in_ready):
                index, offering = index + 1, False
                state["last_input"] = cycle
            if ready and ctx.get(ports.out_valid):
                word = ports.word(ctx)
                words.append(word)
                if word[1]:
                    starts.append(cycle)
                last_word_cycle = cycle
            state["errors"] += ctx.get(dut.framing_error)
            await ctx.tick()
            cycle += 1
            if index >= len(beats) and cycle > last_word_cycle + slack:
                break
        state["cycles"] = last_word_cycle + 1

    sim = Simulator(top)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return {"words": words, "frame_starts": starts, "latency": dut.latency, **state}


def check_frames(params, pairs, beats, **kwargs):
    """Run ``beats``; compare the last len(pairs) output frames with the golden maps.

    Fails (AssertionError) with "... pixels differ ..." naming the first differing pixel,
    or with "only N output frames".
    """
    result = run_scenario(params, beats, **kwargs)
    frames = decode_frames(result["words"], params)
    assert len(frames) >= len(pairs), f"only {len(frames)} output frames"
    for n, ((left, right), got) in enumerate(zip(pairs, frames[-len(pairs):])):
        expected = disparity_map(left, right, params).disparity
        mismatch = first_mismatch(expected, got)
        assert mismatch is None, f"frame {n} of {params.describe()}: {mismatch}"
    return result


def decode_frames(words, params):
    """Split output words at ``tuser`` into H x W int16 maps (INVALID where not valid)."""
    width, height = params.width, params.height
    n_bits = params.disparity_bits
    top = output_width(params) - 1
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
