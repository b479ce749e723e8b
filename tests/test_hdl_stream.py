"""``StereoStream``: the core behind ``amaranth.lib.stream`` interfaces, in Amaranth's simulator.

A producer and a consumer testbench (``stream_put`` / ``stream_get``, each with random
stalls) run side by side, as Amaranth users would drive the core; every output beat is
compared with the golden model. A wrapper that swaps the payload fields must fail.
"""

import random

import numpy as np
import pytest
from amaranth.sim import Simulator

from npstereo.golden.lr_check import INVALID
from npstereo.golden.params import StereoParams
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import stream as hdl_stream
from npstereo.hdl.stream import StereoStream

from hdl_helpers import first_mismatch


async def stream_put(ctx, stream, payload):
    ctx.set(stream.valid, 1)
    ctx.set(stream.payload, payload)
    await ctx.tick().until(stream.ready)
    ctx.set(stream.valid, 0)


async def stream_get(ctx, stream):
    ctx.set(stream.ready, 1)
    payload, = await ctx.tick().sample(stream.payload).until(stream.valid)
    ctx.set(stream.ready, 0)
    return payload


async def stall(ctx, rng, probability):
    while rng.random() < probability:
        await ctx.tick()


def run_scenario(params, left, right, *, stalls=0.35, seed=0):
    """Stream one frame through a ``StereoStream``; the output map (INVALID where invalid)."""
    dut = StereoStream(params)
    height, width = left.shape
    got = np.full((height, width), INVALID - 1, dtype=np.int16)   # -2: never written
    framing = []

    async def producer(ctx):
        rng = random.Random(seed)
        for y in range(height):
            for x in range(width):
                await stall(ctx, rng, stalls)
                await stream_put(ctx, dut.sink, {
                    "left": int(left[y, x]), "right": int(right[y, x]),
                    "first": x == 0 and y == 0, "last": x == width - 1})

    async def consumer(ctx):
        rng = random.Random(seed + 1)
        for y in range(height):
            for x in range(width):
                await stall(ctx, rng, stalls)
                beat = await stream_get(ctx, dut.source)
                framing.append((beat.first, beat.last) == (x == 0 and y == 0, x == width - 1))
                got[y, x] = beat.disparity if beat.valid else INVALID

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(producer)
    sim.add_testbench(consumer)
    sim.run()
    assert all(framing), "first/last flags out of place"
    return got


def scene(params, seed):
    rng = np.random.default_rng(seed)
    texture = rng.integers(0, 256, (params.height, params.width + 4), dtype=np.uint8)
    return texture[:, 3:3 + params.width], texture[:, :params.width]   # disparity 3


@pytest.mark.parametrize("transform,rounds", [("census", 2), ("ext-rank", 1)])
def test_stream_core_matches_golden(transform, rounds):
    params = StereoParams(transform=transform, block=3, disparities=8, rounds=rounds,
                          lr_threshold=1, width=24, height=8)
    left, right = scene(params, 5)
    expected = disparity_map(left, right, params).disparity
    assert first_mismatch(expected, run_scenario(params, left, right)) is None


def test_swapped_payload_fields_are_caught(monkeypatch):
    """A wrapper that feeds the right image as the left one must fail the comparison."""
    original = hdl_stream.StereoStream.elaborate

    def swapped(self, platform):
        m = original(self, platform)
        from amaranth.hdl import Cat
        m.d.comb += self.core.s_axis_tdata.eq(Cat(self.sink.payload.right,
                                                  self.sink.payload.left))
        return m

    monkeypatch.setattr(hdl_stream.StereoStream, "elaborate", swapped)
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2,
                          lr_threshold=None, width=24, height=8)
    left, right = scene(params, 5)
    expected = disparity_map(left, right, params).disparity
    assert first_mismatch(expected, run_scenario(params, left, right)) is not None
