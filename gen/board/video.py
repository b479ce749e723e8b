"""The picture a board shows: video timings, where the disparity map sits on the screen and
the frame the golden model says the display receives.

The map is scaled by the largest whole factor that fits the active area and centred; the
rest of the screen is black. With F > 0 fractional bits (``--subpixel-bits``) the fraction
is scaled into the colour: the table has an entry for every output value 0 ..
(D - 1) 2^F, the colour of value / 2^F levels, so a whole level keeps the colour it has
with F = 0. Colours are :func:`~npstereo.gen.images.colour_disparity`'s,
the table the hardware holds (:func:`colour_table`), so the PNG a build writes is the frame
the board sends, bit for bit (the board-top simulation compares the two).
"""

from dataclasses import dataclass

import numpy as np

from ..images import colour_disparity

__all__ = ["VideoTiming", "VGA_640X480", "Placement", "placement", "colour_table",
           "expected_frame"]


@dataclass(frozen=True)
class VideoTiming:
    """One video mode: active pixels, front porch, sync and back porch, per line and per
    frame, in pixel clocks and lines; the syncs are active low when ``negative``."""

    h_active: int
    h_front: int
    h_sync: int
    h_back: int
    v_active: int
    v_front: int
    v_sync: int
    v_back: int
    negative: bool = True

    @property
    def h_total(self):
        return self.h_active + self.h_front + self.h_sync + self.h_back

    @property
    def v_total(self):
        return self.v_active + self.v_front + self.v_sync + self.v_back

    @property
    def clocks(self):
        """Pixel clocks per frame."""
        return self.h_total * self.v_total


#: VESA/CEA 640x480 at 60 Hz: a 25.175 MHz pixel clock, which monitors take at 25 MHz.
VGA_640X480 = VideoTiming(640, 16, 96, 48, 480, 10, 2, 33)


@dataclass(frozen=True)
class Placement:
    """A ``width`` x ``height`` map on the screen: ``scale`` screen pixels a map pixel in
    each direction, its top-left corner at (``x0``, ``y0``)."""

    width: int
    height: int
    scale: int
    x0: int
    y0: int


def placement(width, height, timing):
    """The map scaled by the largest whole factor that fits the active area, centred.

    The caller checks that the map fits at scale 1 (:func:`npstereo.gen.board.fit`)."""
    scale = max(1, min(timing.h_active // width, timing.v_active // height))
    return Placement(width, height, scale, (timing.h_active - scale * width) // 2,
                     (timing.v_active - scale * height) // 2)


def colour_table(disparities, bits=0):
    """The colour of every output value 0 .. (D-1) 2^F as ((D-1) 2^F + 1, 3) uint8 (with
    F = 0 of every disparity 0 .. D-1): the hardware's colour ROM."""
    top = (disparities - 1) << bits
    return colour_disparity(np.arange(top + 1), top)


def expected_frame(disparity, disparities, timing, colours=None, bits=0):
    """The active picture (v_active, h_active, 3) uint8 the board shows for a map
    (-1 invalid, black; with F = ``bits`` > 0 the output values, scaled by 2^F):
    ``colours`` (default :func:`colour_table`) indexed by the value, each map pixel a
    ``scale`` x ``scale`` square, black around the map."""
    colours = colour_table(disparities, bits) if colours is None else np.asarray(colours)
    disparity = np.asarray(disparity)
    height, width = disparity.shape
    where = placement(width, height, timing)
    rgb = colours[np.clip(disparity, 0, None)]
    rgb[disparity < 0] = 0
    big = np.repeat(np.repeat(rgb, where.scale, axis=0), where.scale, axis=1)
    frame = np.zeros((timing.v_active, timing.h_active, 3), np.uint8)
    frame[where.y0:where.y0 + big.shape[0], where.x0:where.x0 + big.shape[1]] = big
    return frame
