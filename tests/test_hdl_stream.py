"""``StereoStream``: the core behind ``amaranth.lib.stream`` interfaces, in Amaranth's simulator.

The same scenarios as the AXI core's (``hdl_helpers.run_scenario`` with ``stream=True``):
random stalls on both sides, every output beat compared with the golden model, the
``first``/``last`` flags with the frame's. A wrapper that swaps the payload fields must fail.
"""

import pytest

from npstereo.hdl import stream as hdl_stream
from npstereo.params import StereoParams

from hdl_helpers import check_frames, frame_beats
from scenes import stereo_pair


def check_stream(params, seed=5):
    pair = stereo_pair("random", params.height, params.width, seed)
    result = check_frames(params, [pair], frame_beats(*pair), valid_prob=0.65,
                          ready_prob=0.65, seed=seed, stream=True)
    width = params.width
    flags = [(user, last) for _, user, last in result["words"]]
    assert flags == [(i == 0, i % width == width - 1) for i in range(len(flags))], \
        "first/last flags out of place"


@pytest.mark.parametrize("transform,rounds", [("census", 2), ("ext-rank", 1)])
def test_stream_core_matches_golden(transform, rounds):
    check_stream(StereoParams(transform=transform, block=3, disparities=8, rounds=rounds,
                              lr_threshold=1, width=24, height=8))


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
    with pytest.raises(AssertionError, match="pixels differ"):
        check_stream(StereoParams(transform="census", block=3, disparities=8, rounds=2,
                                  lr_threshold=None, width=24, height=8))
