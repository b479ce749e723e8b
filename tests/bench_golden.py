"""Speed of the golden model on one real frame: seconds per frame for each transform.

Usage: ``python tests/bench_golden.py --dataset DIR [--runs N] [--threads N]``, where DIR
holds a Middlebury 2003 pair (``im2.png`` left, ``im6.png`` right), e.g. teddy. Each
configuration runs ``--runs`` times after one warm-up run; the median is printed. Targets
(issue 2, 2-core machine): census 9x9 <= 0.25 s, ext-census 19x19 <= 3 s at D = 100 with the
left/right check on.
"""

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image

from npstereo.params import StereoParams
from npstereo.golden.pipeline import disparity_map

#: (transform, block, target seconds or None), all at D = 100 with the L/R check (T = 3).
CONFIGS = [
    ("census", 9, 0.25),
    ("ext-census", 19, 3.0),
    ("rank", 9, None),
    ("ext-rank", 9, None),
    ("census", 19, None),
]


def load_gray(path):
    """BT.601 integer luma of an 8-bit RGB image, as the semantics page prescribes."""
    rgb = np.asarray(Image.open(path).convert("RGB"), dtype=np.uint32)
    luma = (299 * rgb[..., 0] + 587 * rgb[..., 1] + 114 * rgb[..., 2] + 500) // 1000
    return luma.astype(np.uint8)


def time_config(left, right, params, runs, threads):
    """Median wall-clock and CPU (all threads) seconds of one frame."""
    disparity_map(left, right, params, threads=threads)  # warm-up: page faults, thread pool
    wall, cpu = [], []
    for _ in range(runs):
        start, start_cpu = time.perf_counter(), time.process_time()
        disparity_map(left, right, params, threads=threads)
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return statistics.median(wall), statistics.median(cpu)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", required=True, type=Path,
                        help="Middlebury 2003 folder with im2.png and im6.png (e.g. teddy)")
    parser.add_argument("--runs", type=int, default=5, help="timed runs per configuration")
    parser.add_argument("--threads", type=int, default=None,
                        help="worker threads (default: one per core)")
    args = parser.parse_args(argv)
    paths = [args.dataset / name for name in ("im2.png", "im6.png")]
    for path in paths:
        if not path.is_file():
            print(f"bench_golden: {path} does not exist (--dataset must hold im2.png and "
                  f"im6.png)", file=sys.stderr)
            return 2
    if args.runs < 1:
        print(f"bench_golden: --runs must be >= 1, not {args.runs}", file=sys.stderr)
        return 2
    left, right = (load_gray(p) for p in paths)
    height, width = left.shape
    print(f"golden model, {width}x{height} frame from {args.dataset}, median of {args.runs} "
          f"runs, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    # CPU seconds (summed over threads) are what other jobs on the machine cannot inflate
    # much; wall seconds are the target's measure but need an otherwise idle machine.
    for name, block, target in CONFIGS:
        params = StereoParams(transform=name, block=block, disparities=100, lr_threshold=3)
        wall, cpu = time_config(left, right, params, args.runs, args.threads)
        goal = "" if target is None else f"  (target <= {target:g} s wall: " \
            f"{'ok' if wall <= target else 'MISSED'})"
        print(f"  {params.describe():36s} {wall:7.3f} s/frame wall {cpu:7.3f} s CPU{goal}",
              flush=True)
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
