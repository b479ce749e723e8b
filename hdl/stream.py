"""The formats of the core's streams, described once for the hardware and for numpy.

:class:`PixelPair` is the input word (both images' pixels at one position),
:func:`disparity_word` the output word (a disparity and its valid flag); :func:`framed`
adds the framing flags a stream payload carries beside its word. The core's ports
(:class:`~.core.NpStereoCore`) are :class:`amaranth.lib.stream.Signature` streams of these
payloads, the Verilog top level (:mod:`.verilog`) maps the word to ``tdata`` and the flags
to ``tuser``/``tlast``, and :class:`WordCodec` packs and unpacks numpy frames with the
offsets and widths it reads from the same layouts: the co-simulation, the harness and the
tests have no bit position of their own.
"""

import numpy as np
from amaranth.hdl import unsigned
from amaranth.lib import data

from .plan_structure import output_width

__all__ = ["PixelPair", "disparity_word", "framed", "WordCodec"]


class PixelPair(data.Struct):
    """One input word: the left and the right image's pixel at the same position."""
    left: unsigned(8)
    right: unsigned(8)


def disparity_word(params):
    """One output word: the disparity (0 where invalid; with F > 0 fractional bits scaled
    by 2^F, docs/semantics.md "Sub-pixel disparity") from bit 0, the valid flag in the
    top bit of :func:`~.plan_structure.output_width` (whole bytes, as video IP expects); the bits
    between are 0."""
    size = output_width(params)
    return data.FlexibleLayout(size, {
        "disparity": data.Field(unsigned(params.output_disparity_bits), 0),
        "valid": data.Field(unsigned(1), size - 1)})


def framed(word):
    """A stream payload: ``data`` (the word), ``first`` on a frame's first pixel (0, 0),
    ``last`` on every line's last pixel (W-1, y)."""
    return data.StructLayout({"data": word, "first": 1, "last": 1})


def _mask(field):
    return (1 << field.width) - 1


def _get(words, field):
    return (words >> field.offset) & _mask(field)


def _put(values, field):
    return (np.asarray(values, dtype=np.int64) & _mask(field)) << field.offset


class WordCodec:
    """The words of one configuration's streams as integers, for numpy frames.

    Words are int64 arrays; a negative word is one the simulator left undefined (x/z).
    """

    def __init__(self, params):
        self.params = params
        self.pixels = data.Layout.cast(PixelPair)
        self.disparity = disparity_word(params)
        #: An output beat with its flags: the records of the Verilog harness's response.
        self.beat = framed(self.disparity)

    def pack_pixels(self, left, right):
        """Input words in raster order from two (H, W) uint8 images."""
        return (_put(left, self.pixels["left"])
                | _put(right, self.pixels["right"])).ravel()

    def pack_disparity(self, disparity):
        """The output words for a disparity map (-1 invalid: the word 0), raster order."""
        disparity = np.asarray(disparity, dtype=np.int64).ravel()
        valid = disparity >= 0
        return np.where(valid, _put(disparity, self.disparity["disparity"])
                        | _put(1, self.disparity["valid"]), 0)

    def unpack_disparity(self, words):
        """int16 disparities of output words: -1 where the valid flag is clear or the word
        undefined."""
        words = np.asarray(words, dtype=np.int64)
        valid = (words >= 0) & (_get(words, self.disparity["valid"]) == 1)
        return np.where(valid, _get(words, self.disparity["disparity"]), -1).astype(np.int16)

    def unpack_beats(self, records):
        """``(words, first, last)`` of records laid out as :attr:`beat`; an undefined
        record (negative) gives the word -1 and clear flags."""
        records = np.asarray(records, dtype=np.int64)
        defined = records >= 0
        return tuple(np.where(defined, _get(records, self.beat[name]), default)
                     for name, default in (("data", -1), ("first", 0), ("last", 0)))

    def describe(self, word):
        """A readable value of one output word for a mismatch report: the disparity, -1
        for the invalid word, "X" for an undefined word, else the raw word in hex (a
        disparity out of range, a padding bit set)."""
        word = int(word)
        if word < 0:
            return "X"
        if word == 0:
            return -1
        disparity = int(self.unpack_disparity(word))
        if disparity >= 0 and int(self.pack_disparity(disparity)[0]) == word \
                and disparity <= (self.params.disparities - 1) << self.params.subpixel_bits:
            return disparity
        return hex(word)
