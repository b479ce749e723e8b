"""``hdl/plan.py``: the hardware facts, checked against the elaborated hardware.

The latency and the cycles per frame against the frame period measured in Amaranth's
simulator; the output word width against the core's port and the generated Verilog; the
size limits of :func:`check_buildable`. (The memory bits are checked against Yosys in
``tests/test_report.py``, the units' latencies by the stream comparisons of
``tests/test_hdl_units.py``, which align outputs by them.)
"""

import re

import pytest
from amaranth.hdl import Fragment

from npstereo.hdl import plan
from npstereo.hdl.core import NpStereoCore
from npstereo.hdl.verilog import core_verilog
from npstereo.params import ParameterError, StereoParams

from hdl_helpers import frame_beats, run_scenario
from scenes import stereo_pair

#: Every term of the latency: transforms with and without a tree, R = 1 .. 4, A = 1/3/5,
#: the L/R check on and off, block sizes 3/5.
PERIODS = [
    StereoParams(transform="census", block=3, disparities=8, rounds=1, lr_threshold=1),
    StereoParams(transform="census", block=3, disparities=8, rounds=4, lr_threshold=1),
    StereoParams(transform="rank", block=5, disparities=8, rounds=2, lr_threshold=None),
    StereoParams(transform="ext-rank", block=3, disparities=8, rounds=1, aggregation=5,
                 lr_threshold=0),
    StereoParams(transform="census", block=3, disparities=8, rounds=2, aggregation=1,
                 lr_threshold=None),
    StereoParams(transform="ext-census", block=3, disparities=12, rounds=3, lr_threshold=2),
]


def measured_period(params):
    """Clocks between the first output words of back-to-back frames, without stalls."""
    pair = stereo_pair("independent", params.height, params.width, 1)
    starts = run_scenario(params, frame_beats(*pair) * 3)["frame_starts"]
    periods = {b - a for a, b in zip(starts, starts[1:])}
    assert len(starts) == 3 and len(periods) == 1, starts
    return periods.pop()


@pytest.mark.parametrize("params", PERIODS, ids=lambda p: p.describe().replace(" ", "_"))
def test_cycles_per_frame_is_the_measured_period(params):
    params = params.with_size(24, 6)
    assert measured_period(params) == plan.cycles_per_frame(params) == (
        (24 * 6 + plan.latency(params)) * params.rounds)


def test_a_wrong_latency_fails_the_period_check():
    """Broken variant: the flush one position shorter (or longer) is not the period."""
    params = PERIODS[1].with_size(24, 6)
    period = measured_period(params)
    for wrong in (plan.latency(params) - 1, plan.latency(params) + 1):
        assert period != (24 * 6 + wrong) * params.rounds


@pytest.mark.parametrize("disparities,width", [(2, 8), (128, 8), (129, 16), (256, 16)])
def test_output_width_is_the_port_width(disparities, width):
    # R = D: one cost unit, so that even D = 256 elaborates in a moment.
    params = StereoParams(transform="rank", block=3, disparities=disparities,
                          rounds=disparities, lr_threshold=None, width=disparities + 2,
                          height=2)
    assert plan.output_width(params) == width
    core = NpStereoCore(params)
    Fragment.get(core, None)
    assert len(core.m_axis_tdata) == width
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
