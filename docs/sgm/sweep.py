"""The measurements behind the SGM defaults (docs/sgm.md, "Choosing the defaults").

Usage::

    .venv/bin/python docs/sgm/sweep.py --dataset ../shared/datasets/middlebury2003/teddy \
        --out docs/sgm/sweep.json

For each configuration of the grids below it scores the golden SGM map with the project's
metric (golden/quality.py: |d - gt| <= 1 over known ground truth at x >= D, invalid counts
as wrong), with the L/R check at T = 3 and without it:

- teddy, D = 100: census 5x5 over P1 x P2 x adaptive-P2 exponent, and the other transforms
  and block sizes at penalties scaled to their maximum cost;
- the synthetic scenes of golden/synthetic.py (3 seeds, 320 x 240, D = 64) at gaussian
  noise variances 0, 2e-4 and 2e-3 (golden/degrade.py), census 5x5 over a coarser grid,
  so that the choice is not tuned to teddy alone.

The cost volume of each scene is computed once; only the aggregation is repeated.
"""

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np

from npstereo.golden import sgm
from npstereo.golden.data import load_middlebury
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.golden.params import StereoParams
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair

TEDDY_GRID = dict(p1=(4, 6, 8, 10, 12, 16, 20, 24), p2=(16, 24, 32, 48, 64, 80, 96),
                  adapt=(None, 2, 3, 4, 5, 6))
SYNTH_GRID = dict(p1=(4, 8, 12, 16), p2=(32, 48, 64, 96), adapt=(None, 3, 4, 5))
#: Other transforms on teddy: (name, block), penalties as fractions of Cmax.
OTHER = [("census", 3), ("census", 7), ("census", 9), ("rank", 5), ("rank", 9),
         ("ext-census", 5), ("ext-rank", 5)]
OTHER_FRACTIONS = [(1 / 4, 4 / 3), (1 / 2, 4 / 3), (1 / 2, 8 / 3), (1 / 2, 4)]
NOISE = (0.0, 2e-4, 2e-3)
SEEDS = (0, 1, 2)


def grid(spec, max_cost):
    limit = sgm.max_path_penalty(max_cost)
    for p1, p2, adapt in itertools.product(spec["p1"], spec["p2"], spec["adapt"]):
        if p1 <= p2 <= limit:
            yield p1, p2, adapt


def score(volume, left, truth, disparities, max_cost, p1, p2, adapt):
    summed = sgm.aggregate(volume, p1, p2, guide=left, adapt=adapt, max_cost=max_cost,
                           threads=2)
    return {f"lr{t}" if t is not None else "nolr":
            round(evaluate(sgm.disparity_from_summed(summed, t).disparity, truth,
                           disparities).correct, 3) for t in (3, None)}


def run(left, right, truth, transform, block, disparities, configs, label, rows, out):
    params = StereoParams(transform=transform, block=block, disparities=disparities)
    volume = sgm.cost_volume(left, right, params)
    for p1, p2, adapt in configs:
        start = time.perf_counter()
        result = score(volume, left, truth, disparities, params.max_cost, p1, p2, adapt)
        rows.append(dict(scene=label, transform=transform, block=block, p1=p1, p2=p2,
                         adapt=adapt, **result))
        print(f"{label:28s} {transform} {block}x{block} P1={p1:3d} P2={p2:4d} "
              f"adapt={adapt} LR {result['lr3']:6.2f} noLR {result['nolr']:6.2f} "
              f"({time.perf_counter() - start:.1f} s)", flush=True)
    # Written after every scene, so that an interrupted sweep keeps what it measured.
    out.write_text(json.dumps({"rows": rows}, indent=0) + "\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--only", choices=("teddy", "other", "synthetic"), nargs="*",
                        default=("teddy", "other", "synthetic"))
    args = parser.parse_args(argv)
    rows = []
    pair = load_middlebury(args.dataset)
    left, right = pair.gray()
    if "teddy" in args.only:
        run(left, right, pair.ground_truth, "census", 5, 100,
            list(grid(TEDDY_GRID, 24)), pair.name, rows, args.out)
    if "other" in args.only:
        for transform, block in OTHER:
            cmax = StereoParams(transform=transform, block=block).max_cost
            limit = sgm.max_path_penalty(cmax)
            configs = sorted({(max(1, round(f1 * cmax)), min(limit, round(f2 * cmax)), adapt)
                              for f1, f2 in OTHER_FRACTIONS for adapt in (None, 4)})
            run(left, right, pair.ground_truth, transform, block, 100, configs, pair.name,
                rows, args.out)
    if "synthetic" in args.only:
        for seed, noise in itertools.product(SEEDS, NOISE):
            scene = synthetic_pair(320, 240, 64, seed=seed)
            sl, sr = scene.gray()
            if noise:
                sl, sr = gaussian_noise_pair(sl, sr, noise, seed=seed)
            run(sl, sr, scene.ground_truth, "census", 5, 64, list(grid(SYNTH_GRID, 24)),
                f"synthetic s{seed} noise {noise:g}", rows, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
