"""The core's stream formats (``hdl/stream.py``) and its ``amaranth.lib.stream`` ports.

The codec against the words docs/semantics.md documents (so a changed layout shows here,
not as a silent change of the Verilog ports), its decoding of reports and harness records;
the core in Amaranth's simulator behind its streams with random stalls on both sides, every
output beat compared with the golden model and the ``first``/``last`` flags with the
frame's. A core whose output slice drops ``last`` must fail.
"""

import numpy as np
import pytest

from npstereo.hdl import core as core_module
from npstereo.hdl.stream import WordCodec
from npstereo.hdl.stream_parts import RegisterSlice
from npstereo.params import StereoParams

from hdl_helpers import check_frames, frame_beats
from scenes import stereo_pair


def codec(disparities):
    return WordCodec(StereoParams(transform="census", block=3, disparities=disparities,
                                  rounds=1, width=disparities + 8, height=4))


def test_pixel_words_are_right_over_left():
    left = np.array([[1, 255]], dtype=np.uint8)
    right = np.array([[2, 0]], dtype=np.uint8)
    assert codec(8).pack_pixels(left, right).tolist() == [0x0201, 0x00FF]
    assert codec(8).pixels.size == 16


@pytest.mark.parametrize("disparities,words", [
    (8, [0, 0x80, 0x87]),            # 3 disparity bits, the valid flag in bit 7
    (100, [0, 0x80, 0x80 | 99]),     # 7 bits: still one byte
    (129, [0, 0x8000, 0x8080]),      # 8 bits and the flag: two bytes
])
def test_disparity_words_are_valid_flag_over_disparity(disparities, words):
    disparity = np.array([-1, 0, disparities - 1])
    packed = codec(disparities).pack_disparity(disparity)
    assert packed.tolist() == words
    assert codec(disparities).unpack_disparity(packed).tolist() == disparity.tolist()


def test_unpack_and_describe():
    words = codec(8)
    # Undefined (negative), invalid, valid; a padding bit set; out of range for D = 8.
    assert words.unpack_disparity([-1, 0, 0x85, 0x25]).tolist() == [-1, -1, 5, -1]
    assert [words.describe(w) for w in (-1, 0, 0x85, 0x95, 0xBF, 0x8F)] == \
        ["X", -1, 5, "0x95", "0xbf", "0x8f"]
    assert codec(12).describe(0x8F) == "0x8f"   # 15 >= D
    assert codec(16).describe(0x8F) == 15


def test_beat_records_are_last_first_word():
    """The Verilog harness stores {last, first, word}; -1 marks an undefined record."""
    records = [0x085, 1 << 8 | 0x80, 1 << 9 | 0x81, -1]
    got, first, last = codec(8).unpack_beats(records)
    assert got.tolist() == [0x85, 0x80, 0x81, -1]
    assert first.tolist() == [0, 1, 0, 0] and last.tolist() == [0, 0, 1, 0]


def check_stream(params, seed=5):
    pair = stereo_pair("random", params.height, params.width, seed)
    result = check_frames(params, [pair], frame_beats(*pair), valid_prob=0.65,
                          ready_prob=0.65, seed=seed)
    width = params.width
    flags = [(first, last) for _, first, last in result["words"]]
    assert flags == [(i == 0, i % width == width - 1) for i in range(len(flags))], \
        "first/last flags out of place"


@pytest.mark.parametrize("transform,rounds", [("census", 2), ("ext-rank", 1)])
def test_core_streams_match_golden(transform, rounds):
    check_stream(StereoParams(transform=transform, block=3, disparities=8, rounds=rounds,
                              lr_threshold=1, width=24, height=8))


class LastDroppingSlice(RegisterSlice):
    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.source.payload.last.eq(0)
        return m


def test_dropped_last_flags_are_caught(monkeypatch):
    monkeypatch.setattr(core_module, "RegisterSlice", LastDroppingSlice)
    with pytest.raises(AssertionError, match="flags out of place"):
        check_stream(StereoParams(transform="census", block=3, disparities=8, rounds=2,
                                  lr_threshold=None, width=24, height=8))
