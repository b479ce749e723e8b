"""The measurements behind the SGM defaults (docs/sgm.md, "Choosing the defaults").

Usage::

    .venv/bin/python docs/sgm/sweep.py --dataset ../shared/datasets/middlebury2003/teddy \
        --out docs/sgm/sweep.json

For each configuration of the grids below it scores the golden SGM map with the project's
metric (golden/quality.py: |d - gt| <= 1 over known ground truth at x >= D, invalid counts
as wrong), with the L/R check at T = 3 and without it:

- teddy, D = 100: census 5x5 over P1 x P2 x adaptive-P2 exponent, and the other transforms
  and block sizes at penalties scaled to their maximum cost;
- teddy's other view as the reference (the pair mirrored, ground truth disp6.pgm), over the
  synthetic grid;
- the synthetic scenes of golden/synthetic.py (3 seeds, 256 x 192, D = 48) at gaussian
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
from npstereo.golden.data import load_middlebury, read_image
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.golden.params import StereoParams
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair

TEDDY_GRID = dict(p1=(4, 8, 12, 16, 20, 24, 32), p2=(24, 32, 48, 64, 96, 103),
                  adapt=(None, 3, 4, 5))
SYNTH_GRID = dict(p1=(8, 12, 16, 20, 24), p2=(32, 64, 96), adapt=(None, 3, 4, 5))
#: Other transforms on teddy: (name, block), penalties as fractions of Cmax.
OTHER = [("census", 3), ("census", 7), ("census", 9), ("rank", 5), ("ext-census", 5)]
OTHER_FRACTIONS = [(1 / 2, 4 / 3), (1 / 2, 8 / 3)]
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
    done = {(r["p1"], r["p2"], r["adapt"]) for r in rows
            if (r["scene"], r["transform"], r["block"]) == (label, transform, block)}
    configs = [c for c in configs if c not in done]
    if not configs:
        return
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
        # Written after every configuration: an interrupted sweep keeps what it measured.
        out.write_text(json.dumps({"rows": rows}, indent=0) + "\n")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--only", choices=("teddy", "other", "synthetic", "mirrored"),
                        nargs="*", default=("teddy", "other", "synthetic", "mirrored"))
    parser.add_argument("--report", choices=("lr3", "nolr"),
                        help="print the tables of an existing --out instead of measuring")
    args = parser.parse_args(argv)
    if args.report:
        print(report(json.loads(args.out.read_text())["rows"], args.report))
        return 0
    # An existing output is extended: configurations it holds are not measured again.
    rows = json.loads(args.out.read_text())["rows"] if args.out.exists() else []
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
                              for f1, f2 in OTHER_FRACTIONS for adapt in (None, 4)},
                             key=lambda c: (c[0], c[1], c[2] or 0))
            run(left, right, pair.ground_truth, transform, block, 100, configs, pair.name,
                rows, args.out)
    if "synthetic" in args.only:
        for seed, noise in itertools.product(SEEDS, NOISE):
            scene = synthetic_pair(256, 192, 48, seed=seed)
            sl, sr = scene.gray()
            if noise:
                sl, sr = gaussian_noise_pair(sl, sr, noise, seed=seed)
            run(sl, sr, scene.ground_truth, "census", 5, 48, list(grid(SYNTH_GRID, 24)),
                f"synthetic s{seed} noise {noise:g}", rows, args.out)
    if "mirrored" in args.only:
        # The other view of the same scene as the reference (its own ground truth,
        # disp6.pgm, its own occlusions): the pair mirrored left to right.
        truth = read_image(args.dataset / "disp6.pgm", "ground truth").astype(np.float64)
        truth = np.where(truth == 0, np.nan, truth / 4)[:, ::-1]
        run(np.ascontiguousarray(right[:, ::-1]), np.ascontiguousarray(left[:, ::-1]),
            np.ascontiguousarray(truth), "census", 5, 100, list(grid(SYNTH_GRID, 24)),
            f"{pair.name} mirrored", rows, args.out)
    return 0



# Report ------------------------------------------------------------------------------------


def _key(row):
    return (row["p1"], row["p2"], row["adapt"])


def _adapt_text(adapt):
    return "off" if adapt is None else f"t={adapt}"


def report(rows, check="lr3"):
    """Markdown tables of a sweep (``check``: "lr3" or "nolr") and the chosen defaults."""
    lines = []
    teddy = {(r["scene"], r["transform"], r["block"]): {} for r in rows}
    for r in rows:
        teddy[(r["scene"], r["transform"], r["block"])][_key(r)] = r[check]
    main = teddy[("teddy", "census", 5)]
    p1s = sorted({k[0] for k in main})
    p2s = sorted({k[1] for k in main})
    for adapt in sorted({k[2] for k in main}, key=lambda a: a or 0):
        lines.append(f"\nteddy, census 5x5, adaptive P2 {_adapt_text(adapt)}: correct (%), "
                     f"rows P1, columns P2\n")
        lines.append("| P1 \\ P2 | " + " | ".join(str(p) for p in p2s) + " |")
        lines.append("|---:|" + "---:|" * len(p2s))
        for p1 in p1s:
            cells = [f"{main[(p1, p2, adapt)]:.2f}" if (p1, p2, adapt) in main else ""
                     for p2 in p2s]
            lines.append(f"| {p1} | " + " | ".join(cells) + " |")
    # Conditions: teddy and the synthetic scenes averaged over seeds per noise level.
    conditions = {"teddy": main}
    for (scene, transform, block), values in teddy.items():
        if scene.endswith("mirrored") and (transform, block) == ("census", 5):
            conditions[scene] = values
    for noise in NOISE:
        scenes = [v for (scene, t, b), v in teddy.items()
                  if scene.startswith("synthetic") and scene.endswith(f"noise {noise:g}")]
        if scenes:
            common = set.intersection(*(set(s) for s in scenes))
            conditions[f"synthetic noise {noise:g}"] = {
                k: sum(s[k] for s in scenes) / len(scenes) for k in common}
    common = set.intersection(*(set(v) for v in conditions.values()))
    best = {name: max(values[k] for k in common) for name, values in conditions.items()}
    regret = {k: max(best[n] - conditions[n][k] for n in conditions) for k in common}
    ranked = sorted(common, key=lambda k: (regret[k], -conditions["teddy"][k]))
    lines.append(f"\nConfigurations measured in every condition, by their largest shortfall "
                 f"to the best of each condition (the selection rule), top 15:\n")
    lines.append("| P1 | P2 | adaptive | " + " | ".join(conditions) + " | largest shortfall |")
    lines.append("|---:|---:|---|" + "---:|" * (len(conditions) + 1))
    for k in ranked[:15]:
        lines.append(f"| {k[0]} | {k[1]} | {_adapt_text(k[2])} | "
                     + " | ".join(f"{conditions[n][k]:.2f}" for n in conditions)
                     + f" | {regret[k]:.2f} |")
    lines.append("| best of each | | | " + " | ".join(f"{best[n]:.2f}" for n in conditions)
                 + " | |")
    others = [(key, v) for key, v in teddy.items()
              if key[0] == "teddy" and key != ("teddy", "census", 5)]
    if others:
        lines.append("\nOther transforms on teddy (penalties scaled to Cmax):\n")
        lines.append("| transform | P1 | P2 | adaptive | correct (%) |")
        lines.append("|---|---:|---:|---|---:|")
        for (scene, transform, block), values in sorted(others):
            for k in sorted(values, key=lambda k: (k[0], k[1], k[2] or 0)):
                lines.append(f"| {transform} {block}x{block} | {k[0]} | {k[1]} | "
                             f"{_adapt_text(k[2])} | {values[k]:.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
