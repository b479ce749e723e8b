"""hdl.banks.line_memory: line buffers deeper than one block RAM cut into slices as wide as a
block RAM is at their depth, so that no cascade's multiplexer stands between a block RAM
and its read register (docs/hardware.md, "Memories")."""

import pytest

from npstereo.hdl import banks
from npstereo.params import StereoParams

from hdl_helpers import check_frames, frame_beats
from scenes import stereo_pair


@pytest.mark.parametrize("width, depth, slices", [
    (32, 450, [32]), (32, 512, [32]), (32, 1280, [9, 9, 9, 5]), (21, 1920, [9, 9, 3]),
    (140, 4500, [2] * 70), (3, 20000, [1, 1, 1])])
def test_slice_widths(width, depth, slices):
    assert banks.slice_widths(width, depth) == slices


#: Block RAM shapes scaled down so that the small frames below are "deep": 20 words in
#: slices of 9 bits (a 1280-word buffer's shape at full size).
SMALL_MODES = ((8, 36), (16, 18), (32, 9), (64, 4), (128, 2), (256, 1))


@pytest.mark.parametrize("params", [
    StereoParams(transform="census", block=3, disparities=4, rounds=1, width=20, height=6),
    StereoParams(transform="census", block=3, disparities=4, rounds=2, width=20, height=6,
                 line_buffer="transforms"),
    StereoParams(transform="census", block=3, disparities=4, rounds=2, aggregation="sgm",
                 p1=3, p2=20, width=20, height=6, median=True),
], ids=lambda p: p.describe().replace(" ", "_"))
def test_sliced_line_buffers_match_golden(monkeypatch, params):
    """Input lines, transform lines, SGM minima and the median's lines in 9-bit slices: the
    core still matches the golden model, with gaps and stalls."""
    monkeypatch.setattr(banks, "BLOCK_RAM_MODES", SMALL_MODES)
    assert len(banks.slice_widths(8 * 2, params.width)) == 2
    pair = stereo_pair("layers", params.height, params.width, 5)
    result = check_frames(params, [pair], frame_beats(*pair), valid_prob=0.8, ready_prob=0.8,
                          seed=1)
    assert result["errors"] == 0


def test_slices_out_of_order_are_caught(monkeypatch):
    """Broken variant: the slices' read data put together in the wrong order."""
    monkeypatch.setattr(banks, "BLOCK_RAM_MODES", SMALL_MODES)
    real_cat = banks.Cat
    monkeypatch.setattr(banks, "Cat", lambda *parts: real_cat(*reversed(parts)))
    params = StereoParams(transform="census", block=3, disparities=4, rounds=1, width=20,
                          height=6)
    pair = stereo_pair("layers", params.height, params.width, 5)
    with pytest.raises(AssertionError, match="differ"):
        check_frames(params, [pair], frame_beats(*pair), seed=1)
