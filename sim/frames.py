"""Pixel words in and out of the core, and the bit-exact comparison with the golden model.

Numpy and the hardware's word width (:func:`npstereo.hdl.plan.output_width`), shared by
the cocotb test modules (inside the simulator process) and by the command line / pytest
side, so both report mismatches in exactly the same words.
"""

from dataclasses import dataclass

import numpy as np

from ..hdl.plan import output_width

__all__ = ["input_words", "expected_words", "decode_word", "decode_map", "Comparison",
           "compare_frame"]


def input_words(left, right):
    """``s_axis_tdata`` words in raster order: right pixel in bits 15:8, left in 7:0."""
    return (right.astype(np.uint32) << 8 | left.astype(np.uint32)).ravel()


def expected_words(disparity, params):
    """The words the core must emit for a golden map (-1 = invalid: all bits 0)."""
    valid = disparity >= 0
    words = np.where(valid, disparity.astype(np.int64) | (1 << (output_width(params) - 1)), 0)
    return words.astype(np.int64).ravel()


def decode_word(word, params):
    """A readable value for a mismatch report: the disparity, -1 for invalid, "X" for an
    undefined word (negative: how the harness marks x/z), else the raw word in hex."""
    flag = 1 << (output_width(params) - 1)
    word = int(word)
    if word < 0:
        return "X"   # undefined (x/z) bits in the simulator
    if word == 0:
        return -1
    if word & flag and (word & ~flag) < params.disparities:
        return word & ~flag
    return hex(word)


def decode_map(words, params):
    """The hardware's disparity map (int16, -1 invalid) from its output words.

    Missing pixels (fewer words than W*H) and words with the valid flag clear are -1.
    """
    pixels = params.width * params.height
    words = np.asarray(words, dtype=np.int64)[:pixels]
    flag = 1 << (output_width(params) - 1)
    disparity = np.full(pixels, -1, dtype=np.int16)
    valid = (words >= 0) & ((words & flag) != 0)
    disparity[:words.size][valid] = (words[valid] & ((1 << params.disparity_bits) - 1))
    return disparity.reshape(params.height, params.width)


@dataclass
class Comparison:
    """Outcome of one frame: pixels compared, mismatching words, and where the first one is."""

    width: int
    height: int
    pixels: int
    mismatches: int
    first: tuple | None      # (x, y, expected, got) of the first differing pixel
    framing: list            # framing problems (tuser/tlast/count), empty when correct

    @property
    def ok(self):
        return self.mismatches == 0 and not self.framing

    def message(self):
        """One line a test failure or the command line shows."""
        parts = [f"{self.mismatches} of {self.pixels} pixels differ"]
        if self.first is not None:
            x, y, expected, got = self.first
            parts.append(f"first at x={x} y={y}: expected {expected}, got {got}")
        parts.extend(self.framing)
        return "; ".join(parts)

    def to_dict(self):
        return {"width": self.width, "height": self.height, "pixels": self.pixels,
                "mismatches": self.mismatches,
                "first": None if self.first is None else list(self.first),
                "framing": list(self.framing)}

    @classmethod
    def from_dict(cls, data):
        first = data["first"]
        return cls(data["width"], data["height"], data["pixels"], data["mismatches"],
                   None if first is None else tuple(first), list(data["framing"]))


def compare_frame(expected, got, tuser, tlast, params):
    """Compare the output beats of one frame with the expected words.

    Parameters
    ----------
    expected : (W*H,) int array
        From :func:`expected_words`.
    got, tuser, tlast : sequences
        ``m_axis_tdata``/``tuser``/``tlast`` of the received beats, in order; fewer or more
        beats than W*H is a framing error, and missing pixels count as mismatches.
    params : StereoParams
        With width and height.
    """
    width, height = params.width, params.height
    pixels = width * height
    got = np.asarray(got, dtype=np.int64)
    framing = []
    if got.size != pixels:
        framing.append(f"received {got.size} output pixels, expected {pixels}")
    n = min(got.size, pixels)
    differ = np.flatnonzero(got[:n] != expected[:n])
    mismatches = differ.size + (pixels - n)
    first = None
    if differ.size:
        index = int(differ[0])
        first = (index % width, index // width, decode_word(expected[index], params),
                 decode_word(got[index], params))
    elif n < pixels:
        first = (n % width, n // width, decode_word(expected[n], params), "nothing")
    tuser = np.asarray(tuser[:n], dtype=bool)
    tlast = np.asarray(tlast[:n], dtype=bool)
    index = np.arange(n)
    want_user = index == 0
    want_last = index % width == width - 1
    for name, have, want in (("tuser", tuser, want_user), ("tlast", tlast, want_last)):
        bad = np.flatnonzero(have != want)
        if bad.size:
            i = int(bad[0])
            framing.append(f"m_axis_{name} wrong on {bad.size} beats, first at "
                           f"x={i % width} y={i // width} (expected {int(want[i])})")
    return Comparison(width, height, pixels, int(mismatches), first, framing)
