"""Whole frames of output words, and the bit-exact comparison with the golden model.

The words themselves are :class:`npstereo.hdl.stream.WordCodec`'s; this module is shared by
the cocotb test modules (inside the simulator process) and by the command line / pytest
side, so both report mismatches in exactly the same words.
"""

from dataclasses import dataclass

import numpy as np

from ..hdl.stream import WordCodec

__all__ = ["decode_map", "Comparison", "compare_frame"]


def decode_map(words, params, missing=-1):
    """The hardware's disparity map (int16, -1 invalid) from its output words.

    Words with the valid flag clear are -1, missing pixels (fewer words than W*H)
    ``missing``.
    """
    pixels = params.width * params.height
    decoded = WordCodec(params).unpack_disparity(np.asarray(words, dtype=np.int64)[:pixels])
    disparity = np.full(pixels, missing, dtype=np.int16)
    disparity[:decoded.size] = decoded
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
        From :meth:`~npstereo.hdl.stream.WordCodec.pack_disparity`.
    got, tuser, tlast : sequences
        ``m_axis_tdata``/``tuser``/``tlast`` of the received beats, in order; fewer or more
        beats than W*H is a framing error, and missing pixels count as mismatches.
    params : StereoParams
        With width and height.
    """
    width, height = params.width, params.height
    pixels = width * height
    describe = WordCodec(params).describe
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
        first = (index % width, index // width, describe(expected[index]),
                 describe(got[index]))
    elif n < pixels:
        first = (n % width, n // width, describe(expected[n]), "nothing")
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
