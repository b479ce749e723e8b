"""hdl.common.delay_line: a free-running delay of any length, registers or rings of LUT RAM,
in Amaranth's simulator against the input stream shifted by the delay."""

import random

import pytest
from amaranth.hdl import Module, Signal
from amaranth.sim import Simulator

from npstereo.hdl import common
from npstereo.hdl.common import DELAY_LINE_BITS, DELAY_LINE_MIN, delay_line, delay_line_rings


def delayed_stream(width, steps, clocks=60, seed=0):
    """(inputs, outputs) of a delay line of ``width`` bits by ``steps`` over random input."""
    m = Module()
    value = Signal(width)
    out = delay_line(m, value, steps, "probe")
    stream = random.Random(seed)
    inputs = [stream.randrange(1 << width) for _ in range(clocks)]
    outputs = []

    async def testbench(ctx):
        for word in inputs:
            ctx.set(value, word)
            outputs.append(ctx.get(out))
            await ctx.tick()

    sim = Simulator(m)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    return inputs, outputs


@pytest.mark.parametrize("width, steps", [(5, 1), (5, 3), (5, DELAY_LINE_MIN), (9, 7),
                                          (12, 16), (3, 17), (2 * DELAY_LINE_BITS + 3, 14)])
def test_output_is_the_input_steps_clocks_ago(width, steps):
    inputs, outputs = delayed_stream(width, steps)
    assert outputs[steps:] == inputs[:-steps]


def test_rings_from_the_threshold_on():
    """Registers below DELAY_LINE_MIN clocks; from it a ring per DELAY_LINE_BITS bits, as
    deep as the next power of two."""
    assert delay_line_rings(40, DELAY_LINE_MIN - 1) == []
    assert delay_line_rings(2 * DELAY_LINE_BITS + 3, 14) == \
        [(DELAY_LINE_BITS, 16), (DELAY_LINE_BITS, 16), (3, 16)]
    assert delay_line_rings(8, 17) == [(8, 32)]


def test_broken_ring_distance_is_caught(monkeypatch):
    """The read pointer one word too far behind: one clock too late."""
    monkeypatch.setattr(common, "_ring_distance", lambda steps: steps)
    inputs, outputs = delayed_stream(9, 7)
    assert outputs[7:] != inputs[:-7]
