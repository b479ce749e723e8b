"""Benchmark: the paper's configuration on a whole Middlebury frame under Verilator.

census 9x9, D = 100, R = 10, A = 3, L/R threshold 3 on teddy (450 x 375, about 1.7 M
clock cycles), streamed through the Verilog harness of ``npstereo.sim.harness`` under
cocotb. Prints the build and simulation times, the cycles, and whether the frame was
bit-exact; ``--icarus-crop WxH`` additionally measures Icarus on the central crop
(Icarus on the full frame takes far longer). Goal: Verilator <= 60 s including the build.

Run: ``.venv/bin/python tests/bench_cosim.py --dataset ../shared/datasets/middlebury2003/teddy``
"""

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

from npstereo.golden.data import load_middlebury, to_gray
from npstereo.params import StereoParams, UserError
from npstereo.golden.pipeline import disparity_map
from npstereo.sim.cosim import CosimError, run_frame


def measure(simulator, params, left, right, build_root):
    start = time.perf_counter()
    golden = disparity_map(left, right, params).disparity
    golden_seconds = time.perf_counter() - start
    start = time.perf_counter()
    result = run_frame(simulator, params, left, right, golden=golden, build_root=build_root)
    total = time.perf_counter() - start
    _, comparison = result.frames[0]
    verdict = "bit-exact" if comparison.ok else comparison.message()
    print(f"{simulator:9s} {params.width}x{params.height}: build {result.build_seconds:6.1f} s, "
          f"simulation {result.seconds:6.1f} s, total {total:6.1f} s "
          f"(+ golden {golden_seconds:.1f} s); {result.cycles} cycles "
          f"({result.cycles / max(result.seconds, 1e-9) / 1e3:.0f} k cycles/s); "
          f"{comparison.pixels} pixels, {comparison.mismatches} mismatches: {verdict}")
    return comparison.ok


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset", required=True, help="Middlebury scene folder (teddy)")
    parser.add_argument("--icarus-crop", help="also run Icarus on the central WxH crop")
    parser.add_argument("--keep-build", action="store_true",
                        help="reuse build/cosim instead of a fresh build directory "
                             "(measures the simulation without the build)")
    args = parser.parse_args()
    try:
        pair = load_middlebury(args.dataset)
    except UserError as error:
        print(f"bench_cosim: {error}", file=sys.stderr)
        return 2
    left, right = to_gray(pair.left), to_gray(pair.right)
    params = StereoParams(transform="census", block=9, disparities=100, rounds=10,
                          aggregation=3, lr_threshold=3)
    scratch = None if args.keep_build else Path(tempfile.mkdtemp(prefix="bench-cosim-"))
    ok = True
    try:
        height, width = left.shape
        ok &= measure("verilator", params.with_size(width, height), left, right, scratch)
        if args.icarus_crop:
            w, h = (int(v) for v in args.icarus_crop.lower().split("x"))
            y, x = (height - h) // 2, (width - w) // 2
            crop = (left[y:y + h, x:x + w].copy(), right[y:y + h, x:x + w].copy())
            ok &= measure("icarus", params.with_size(w, h), *crop, scratch)
    except CosimError as error:
        print(f"bench_cosim: {error}", file=sys.stderr)
        return 1
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
