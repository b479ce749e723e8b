"""Benchmark: Verilog generation time and the lint sweep of ``npstereo verilog``.

1. Generation time of the paper's largest configuration (census 19x19, D = 100, R = 10,
   450 x 375; goal <= 20 s), ext-census 19x19 and census 9x9 at the same size.
2. ``verilator --lint-only -Wall`` of 25 configurations (every transform, block sizes
   3..19, D in {16, 64, 100}, R in {1, 2, 4, 10}) at a small frame size (the lint does not
   depend on it); every one must be clean.

``--dataset`` (the Middlebury scene folder) only sets the frame size of part 1 from its
left image; without it 450 x 375 is used. Prints one line per configuration.

Run: ``.venv/bin/python tests/bench_hdl.py [--dataset DIR] [--skip-sweep]``
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path

from tqdm import tqdm

from npstereo.hdl.verilog import core_verilog
from npstereo.params import StereoParams, UserError
from npstereo.sim.lint import lint

TIMED = [("census", 19), ("ext-census", 19), ("census", 9)]

SWEEP = [
    ("rank", 3, 16, 1), ("census", 3, 16, 2), ("ext-rank", 3, 16, 4), ("ext-census", 3, 16, 1),
    ("rank", 5, 64, 4), ("census", 5, 16, 4), ("ext-rank", 5, 64, 2), ("ext-census", 5, 16, 2),
    ("rank", 7, 100, 10), ("census", 7, 64, 4), ("ext-rank", 7, 16, 1),
    ("ext-census", 7, 64, 4), ("rank", 9, 100, 4), ("census", 9, 100, 10),
    ("ext-rank", 9, 64, 4), ("ext-census", 9, 16, 4), ("rank", 11, 64, 2),
    ("census", 11, 100, 10), ("ext-rank", 13, 100, 10), ("ext-census", 13, 100, 10),
    ("rank", 15, 16, 1), ("census", 15, 64, 4), ("ext-rank", 17, 100, 10),
    ("census", 19, 100, 10), ("ext-census", 19, 100, 10),
]


def frame_size(dataset):
    if dataset is None:
        return 450, 375
    from npstereo.golden.data import load_middlebury
    height, width = load_middlebury(dataset).left.shape[:2]
    return width, height


def timed_generation(width, height):
    for transform, block in TIMED:
        params = StereoParams(transform=transform, block=block, disparities=100, rounds=10,
                              width=width, height=height)
        start = time.perf_counter()
        text = core_verilog(params)
        seconds = time.perf_counter() - start
        print(f"generate {params.describe():45s} {seconds:7.1f} s  "
              f"{len(text) / 1e6:6.1f} MB Verilog", flush=True)


def lint_sweep():
    failures = 0
    with tempfile.TemporaryDirectory(prefix="bench-hdl-") as scratch:
        for transform, block, disparities, rounds in tqdm(SWEEP, desc="lint", file=sys.stderr):
            params = StereoParams(transform=transform, block=block, disparities=disparities,
                                  rounds=rounds, width=disparities + 24, height=6)
            path = Path(scratch) / "core.v"
            start = time.perf_counter()
            path.write_text(core_verilog(params))
            generated = time.perf_counter() - start
            ok, messages = lint(path)
            failures += not ok
            verdict = "lint clean" if ok else "LINT FAILED: " + messages.splitlines()[0]
            tqdm.write(f"{params.describe():45s} generate {generated:6.1f} s, "
                       f"lint {time.perf_counter() - start - generated:5.1f} s: {verdict}",
                       file=sys.stdout)
    print(f"lint sweep: {len(SWEEP) - failures}/{len(SWEEP)} configurations clean")
    return failures == 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset", help="Middlebury scene folder (sets the frame size)")
    parser.add_argument("--skip-sweep", action="store_true", help="only the timed generation")
    parser.add_argument("--skip-timed", action="store_true", help="only the lint sweep")
    args = parser.parse_args()
    try:
        width, height = frame_size(args.dataset)
    except UserError as error:
        print(f"bench_hdl: {error}", file=sys.stderr)
        return 2
    if not args.skip_timed:
        timed_generation(width, height)
    ok = True if args.skip_sweep else lint_sweep()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
