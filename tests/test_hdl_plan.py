"""``hdl/plan*.py``: the hardware facts, checked against the elaborated hardware.

The cycles per frame against the frame period measured in Amaranth's simulator (frames
back to back), the latency against the flush after a lone frame (and broken variants of
its formula against the same flush); the output word width against the core's port and the
generated Verilog; the size limits of :func:`check_buildable`. (The memory bits are checked
against Yosys in ``tests/test_report.py``, the units' latencies by the stream comparisons
of ``tests/test_hdl_units.py``, which align outputs by them.)
"""

import re

import pytest
from amaranth.hdl import Fragment
from amaranth.sim import Simulator

from npstereo.hdl import plan, plan_structure, plan_timing
from npstereo.hdl.core import NpStereoCore
from npstereo.hdl.verilog import core_verilog
from npstereo.params import ParameterError, StereoParams

from hdl_helpers import frame_beats, run_scenario
from scenes import stereo_pair

#: Every term of the latency: transforms with and without a tree, R = 1 .. 4, A = 1/3/5,
#: the L/R check on and off, block sizes 3/5, semi-global aggregation.
PERIODS = [
    StereoParams(transform="census", block=3, disparities=8, rounds=1, lr_threshold=1),
    StereoParams(transform="census", block=3, disparities=8, rounds=4, lr_threshold=1),
    StereoParams(transform="rank", block=5, disparities=8, rounds=2, lr_threshold=None),
    StereoParams(transform="ext-rank", block=3, disparities=8, rounds=1, aggregation=5,
                 lr_threshold=0),
    StereoParams(transform="census", block=3, disparities=8, rounds=2, aggregation=1,
                 lr_threshold=None),
    StereoParams(transform="ext-census", block=3, disparities=12, rounds=3, lr_threshold=2),
    StereoParams(transform="census", block=3, disparities=8, rounds=8, aggregation="sgm",
                 p1=3, p2=20, lr_threshold=1),
]


def measured_period(params):
    """Clocks between the first output words of back-to-back frames, without stalls."""
    pair = stereo_pair("independent", params.height, params.width, 1)
    starts = run_scenario(params, frame_beats(*pair) * 3)["frame_starts"]
    periods = {b - a for a, b in zip(starts, starts[1:])}
    assert len(starts) == 3 and len(periods) == 1, starts
    return periods.pop()


def measured_flush(params):
    """Clocks from the admission of a frame's last pixel to its last output word entering
    the output queue, for a frame followed by no other (the core flushes)."""
    core = NpStereoCore(params)
    pair = stereo_pair("independent", params.height, params.width, 1)
    beats = frame_beats(*pair)
    events = {"admitted": [], "last_word": None}

    async def bench(ctx):
        index = 0
        for clock in range(len(beats) * params.rounds + 40 * plan_timing.latency(params)
                           * params.rounds):
            offering = index < len(beats)
            if offering:
                pixels, first, last = beats[index]
                ctx.set(core.sink.payload, {"data": pixels, "first": first, "last": last})
            ctx.set(core.sink.valid, offering)
            ctx.set(core.source.ready, 1)
            if offering and ctx.get(core.sink.ready):
                index += 1
            if ctx.get(core.input_stage.admit):
                # The admission's decision (the input stage sees it decision_clocks later):
                # its slot starts in the clock after it.
                events["admitted"].append(clock + 1 - plan_timing.decision_clocks(params.rounds))
            if _last_word(ctx, core, params):
                events["last_word"] = clock
                break
            await ctx.tick()

    sim = Simulator(core)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    last_pixel = events["admitted"][params.width * params.height - 1]
    return events["last_word"] - last_pixel, core.clock_latency


def _last_word(ctx, core, params):
    """The frame's last word leaves the core's last stage (the 3x3 median's, when on, or
    the mirrored rows' turn-round's, with the fifth path)."""
    if core.median is not None:
        return ctx.get(core.median.produce_out) and ctx.get(core.median.frame_end)
    if core.row_turn is not None:
        return ctx.get(core.row_turn.produce_out) and ctx.get(core.row_turn.frame_end)
    lr = core.lr_check
    return (ctx.get(lr.produce) and ctx.get(lr.x) == params.width - 1
            and ctx.get(lr.y) == params.height - 1)


@pytest.mark.parametrize("params", PERIODS, ids=lambda p: p.describe().replace(" ", "_"))
def test_cycles_per_frame_is_the_measured_period(params):
    """Frames back to back: W x H x R clocks each, no flush between them."""
    params = params.with_size(24, 6)
    assert measured_period(params) == plan_timing.cycles_per_frame(params) == \
        24 * 6 * params.rounds


@pytest.mark.parametrize("params", PERIODS, ids=lambda p: p.describe().replace(" ", "_"))
def test_latency_is_the_measured_flush(params):
    """After a frame's last pixel the flush admits a dummy position every R clocks; the
    last word leaves ``latency`` positions and the output offset later."""
    params = params.with_size(24, 6)
    flush, output = measured_flush(params)
    assert flush == planned_flush(params, output)


def planned_flush(params, output):
    """The flush in clocks that ``plan_timing.latency`` says: a position every R clocks."""
    return plan_timing.latency(params) * params.rounds + output


#: Broken variants of ``plan_timing.latency``, each wrong in one term: a row of W
#: positions instead of W + 1 (the window's column lag left out), the aggregation's lag
#: left out, the L/R check's D positions left out.
BROKEN_LATENCIES = {
    "rows of W": lambda p: (p.radius + p.agg_radius) * p.width + p.disparities,
    "no aggregation lag": lambda p: p.radius * (p.width + 1) + p.disparities,
    "no L/R wait": lambda p: (p.radius + p.agg_radius) * (p.width + 1),
}


def test_a_broken_latency_fails_the_flush_check(monkeypatch):
    """The check of the flush fails for each broken variant of the formula."""
    params = PERIODS[1].with_size(24, 6)
    flush, output = measured_flush(params)
    for broken in BROKEN_LATENCIES.values():
        with monkeypatch.context() as patch:
            patch.setattr(plan_timing, "latency", broken)
            assert flush != planned_flush(params, output)


@pytest.mark.parametrize("disparities,width", [(2, 8), (128, 8), (129, 16), (256, 16)])
def test_output_width_is_the_port_width(disparities, width):
    # R = D: one cost unit, so that even D = 256 elaborates in a moment.
    params = StereoParams(transform="rank", block=3, disparities=disparities,
                          rounds=disparities, lr_threshold=None, width=disparities + 2,
                          height=2)
    assert plan_structure.output_width(params) == width
    core = NpStereoCore(params)
    Fragment.get(core, None)
    assert len(core.source.payload.data.as_value()) == width
    if disparities == 2:  # the smallest core generates in well under a second
        assert re.search(rf"output \[{width - 1}:0\] m_axis_tdata", core_verilog(params))


@pytest.mark.parametrize("changes,message", [
    ({"width": None, "height": None}, "the hardware needs the image size"),
    ({"width": plan.MAX_WIDTH + 1}, f"image width must be <= {plan.MAX_WIDTH}"),
    ({"block": plan.MAX_BLOCK + 2}, f"block size must be <= {plan.MAX_BLOCK}"),
    ({"disparities": plan.MAX_DISPARITIES + 1, "width": 400},
     f"disparities must be <= {plan.MAX_DISPARITIES}"),
])
def test_check_buildable_refuses(changes, message):
    params = StereoParams(transform="census", block=3, disparities=8, width=64,
                          height=4).replace(**changes)
    with pytest.raises(ParameterError, match=message):
        plan.check_buildable(params)
    with pytest.raises(ParameterError, match=message):
        NpStereoCore(params)


def test_check_buildable_accepts_the_limits():
    plan.check_buildable(StereoParams(transform="census", block=plan.MAX_BLOCK,
                                      disparities=plan.MAX_DISPARITIES,
                                      width=plan.MAX_WIDTH, height=1))
