"""Benchmark: the ULX3S board top for one whole 640x480 frame under Verilator.

The default board design of ``npstereo board ulx3s-85f`` (census 9x9, D = 32, R = 4, the
synthetic scene, 160 x 120 shown 4x) from reset through the first disparity map to the end
of the first whole video frame after it (812,000 pixel clocks), compared pixel for
pixel with the golden model's colour-mapped map; then the broken variant (the colour ROM
shifted by one disparity), which must fail. Then the same design with the 3x3 median and
F = 4 fractional bits (the fraction scaled into the colour, docs/board.md) and its broken
variant, the colour ROM shifted by one 1/16 step. Prints build and simulation times. The
bitstream itself is ``make board`` (place and route takes minutes).

``--dataset`` is accepted for ``make bench`` and not used: a Middlebury frame does not fit
the board's block RAM beside its frame buffer.

Run: ``.venv/bin/python tests/bench_board.py``
"""

import argparse
import sys
import time

import numpy as np

from npstereo.gen.board.display import DepthDisplay
from npstereo.gen.board.verify import capture_verilator, compare
from npstereo.gen.board.video import VGA_640X480, colour_table, expected_frame
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.synthetic import DEFAULT_DISPARITIES, synthetic_pair
from npstereo.params import StereoParams


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", help="not used (see the module docstring)")
    parser.parse_args()
    left, right = synthetic_pair().gray()
    height, width = left.shape
    default = StereoParams(transform="census", block=9, disparities=DEFAULT_DISPARITIES,
                           rounds=4, width=width, height=height)
    timing = VGA_640X480
    failed = False
    for params in (default, default.replace(median=True, subpixel_bits=4)):
        bits = params.subpixel_bits
        expected = expected_frame(disparity_map(left, right, params).disparity,
                                  params.disparities, timing, bits=bits)
        verdicts = []
        step = "one disparity" if not bits else f"one 1/{1 << bits} step"
        for label, colours in (("board top", None),
                               (f"broken variant (colour ROM off by {step})",
                                np.roll(colour_table(params.disparities, bits), 1, axis=0))):
            start = time.perf_counter()
            capture, build_seconds = capture_verilator(
                DepthDisplay(params, left, right, timing, colours), timing)
            check = compare(expected, capture, timing)
            print(f"{label}: {params.describe()} on {timing.h_active}x"
                  f"{timing.v_active}: build {build_seconds:.1f} s, simulation "
                  f"{capture.seconds:.1f} s, total {time.perf_counter() - start:.1f} s; "
                  f"{check.message()}")
            verdicts.append(check.ok)
        good, broken = verdicts
        if broken:
            print("the broken variant was not caught")
        failed = failed or not good or broken
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
