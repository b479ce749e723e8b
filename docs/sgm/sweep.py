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
  so that the choice is not tuned to teddy alone;
- census 7x7 in all of these conditions, with P2 <= 79 (7-bit path costs).

The cost volume of each scene is computed once; only the aggregation is repeated. An
existing ``--out`` is extended (configurations already in it are skipped);
``--report lr3`` or ``--report nolr`` prints the tables of docs/sgm/sweep.md and the
ranking of the selection rule from it.
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
from npstereo.params import StereoParams, max_path_penalty
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair

TEDDY_GRID = dict(p1=(4, 8, 12, 16, 20, 24, 32), p2=(24, 32, 48, 64, 96, 103),
                  adapt=(None, 3, 4, 5))
SYNTH_GRID = dict(p1=(8, 12, 16, 20, 24), p2=(32, 64, 96), adapt=(None, 3, 4, 5))
#: Other transforms on teddy: (name, block), penalties as fractions of Cmax.
OTHER = [("census", 3), ("census", 7), ("census", 9), ("rank", 5), ("ext-census", 5)]
OTHER_FRACTIONS = [(1 / 2, 4 / 3), (1 / 2, 8 / 3)]
#: Census 7x7 in every condition, P2 <= 79 so that its path cost stays at 7 bits as well.
CENSUS7_GRID = dict(p1=(16, 24, 32), p2=(48, 64, 79), adapt=(None, 4, 5))
NOISE = (0.0, 2e-4, 2e-3)
SEEDS = (0, 1, 2)


def grid(spec, max_cost):
    limit = max_path_penalty(max_cost)
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


def synthetic(seed, noise):
    """(left, right, ground truth) of a synthetic scene with noise of this variance."""
    scene = synthetic_pair(256, 192, 48, seed=seed)
    left, right = scene.gray()
    if noise:
        left, right = gaussian_noise_pair(left, right, noise, seed=seed)
    return left, right, scene.ground_truth


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--only", choices=("teddy", "other", "synthetic", "mirrored",
                                           "census7"),
                        nargs="*", default=("teddy", "other", "synthetic", "mirrored",
                                            "census7"))
    parser.add_argument("--report", choices=("lr3", "nolr"),
                        help="print the tables of an existing --out instead of measuring")
    args = parser.parse_args(argv)
    if args.report:
        print(report(json.loads(args.out.read_text())["rows"], args.report))
        return 0
    if args.dataset is None:
        parser.error("--dataset is needed to measure (teddy: Middlebury 2003 with disp6.pgm)")
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
            limit = max_path_penalty(cmax)
            configs = sorted({(max(1, round(f1 * cmax)), min(limit, round(f2 * cmax)), adapt)
                              for f1, f2 in OTHER_FRACTIONS for adapt in (None, 4)},
                             key=lambda c: (c[0], c[1], c[2] or 0))
            run(left, right, pair.ground_truth, transform, block, 100, configs, pair.name,
                rows, args.out)
    if "synthetic" in args.only:
        for seed, noise in itertools.product(SEEDS, NOISE):
            sl, sr, truth = synthetic(seed, noise)
            run(sl, sr, truth, "census", 5, 48, list(grid(SYNTH_GRID, 24)),
                f"synthetic s{seed} noise {noise:g}", rows, args.out)
    # The other view of the same scene as the reference (its own ground truth, disp6.pgm,
    # its own occlusions): the pair mirrored left to right.
    truth = read_image(args.dataset / "disp6.pgm", "ground truth").astype(np.float64)
    mirrored = (np.ascontiguousarray(right[:, ::-1]), np.ascontiguousarray(left[:, ::-1]),
                np.ascontiguousarray(np.where(truth == 0, np.nan, truth / 4)[:, ::-1]))
    if "mirrored" in args.only:
        run(*mirrored, "census", 5, 100, list(grid(SYNTH_GRID, 24)), f"{pair.name} mirrored",
            rows, args.out)
    if "census7" in args.only:
        configs = list(grid(CENSUS7_GRID, 48))
        run(left, right, pair.ground_truth, "census", 7, 100, configs, pair.name, rows,
            args.out)
        run(*mirrored, "census", 7, 100, configs, f"{pair.name} mirrored", rows, args.out)
        for seed, noise in itertools.product(SEEDS, NOISE):
            sl, sr, truth = synthetic(seed, noise)
            run(sl, sr, truth, "census", 7, 48, configs, f"synthetic s{seed} noise {noise:g}",
                rows, args.out)
    return 0



# Report ------------------------------------------------------------------------------------

#: Candidate transforms of the selection: measured in every condition.
CANDIDATES = (("census", 5), ("census", 7))


def _adapt_text(adapt):
    return "off" if adapt is None else f"t={adapt}"


def _condition(scene):
    """Teddy views by name; synthetic scenes pooled over seeds per noise level."""
    return f"synthetic noise {scene.split()[-1]}" if scene.startswith("synthetic") else scene


def report(rows, check="lr3"):
    """Markdown tables of a sweep (``check``: "lr3" or "nolr") and the selection.

    The selection rule: among the configurations measured in every condition (teddy,
    teddy mirrored, synthetic at each noise level, the mean over the seeds), the one whose
    largest shortfall to the best configuration of a condition is smallest.
    """
    lines = []
    values = {}
    for r in rows:
        values.setdefault((r["scene"], r["transform"], r["block"]), {})[
            (r["p1"], r["p2"], r["adapt"])] = r[check]
    for transform, block in CANDIDATES:
        main = values.get(("teddy", transform, block), {})
        p1s, p2s = sorted({k[0] for k in main}), sorted({k[1] for k in main})
        for adapt in sorted({k[2] for k in main}, key=lambda a: a or 0):
            lines.append(f"\nteddy, {transform} {block}x{block}, adaptive P2 "
                         f"{_adapt_text(adapt)}: correct (%), rows P1, columns P2\n")
            lines.append("| P1 \\ P2 | " + " | ".join(str(p) for p in p2s) + " |")
            lines.append("|---:|" + "---:|" * len(p2s))
            for p1 in p1s:
                cells = [f"{main[(p1, p2, adapt)]:.2f}" if (p1, p2, adapt) in main else ""
                         for p2 in p2s]
                lines.append(f"| {p1} | " + " | ".join(cells) + " |")
    # condition -> candidate (transform, block, p1, p2, adapt) -> list of scores
    pooled = {}
    for (scene, transform, block), scores in values.items():
        if (transform, block) not in CANDIDATES:
            continue
        condition = pooled.setdefault(_condition(scene), {})
        for k, v in scores.items():
            condition.setdefault((transform, block) + k, []).append(v)
    names = sorted(pooled, key=lambda c: (not c.startswith("teddy"), c))
    means = {c: {k: sum(v) / len(v) for k, v in pooled[c].items()} for c in names}
    common = set.intersection(*(set(means[c]) for c in names))
    best = {c: max(means[c][k] for k in common) for c in names}
    shortfall = {k: max(best[c] - means[c][k] for c in names) for k in common}
    ranked = sorted(common, key=lambda k: (shortfall[k], -means["teddy"][k]))
    lines.append("\nConfigurations measured in every condition, by their largest shortfall to "
                 "the best of each condition (the selection rule), top 12:\n")
    lines.append("| transform | P1 | P2 | adaptive | " + " | ".join(names)
                 + " | largest shortfall |")
    lines.append("|---|---:|---:|---|" + "---:|" * (len(names) + 1))
    for k in ranked[:12]:
        lines.append(f"| {k[0]} {k[1]}x{k[1]} | {k[2]} | {k[3]} | {_adapt_text(k[4])} | "
                     + " | ".join(f"{means[c][k]:.2f}" for c in names)
                     + f" | {shortfall[k]:.2f} |")
    lines.append("| best of each | | | | " + " | ".join(f"{best[c]:.2f}" for c in names)
                 + " | |")
    others = [(key, v) for key, v in values.items()
              if key[0] == "teddy" and key[1:] not in CANDIDATES]
    if others:
        lines.append("\nOther transforms on teddy (penalties scaled to Cmax):\n")
        lines.append("| transform | P1 | P2 | adaptive | correct (%) |")
        lines.append("|---|---:|---:|---|---:|")
        for (_, transform, block), scores in sorted(others):
            for k in sorted(scores, key=lambda k: (k[0], k[1], k[2] or 0)):
                lines.append(f"| {transform} {block}x{block} | {k[0]} | {k[1]} | "
                             f"{_adapt_text(k[2])} | {scores[k]:.2f} |")
    return "\n".join(lines)

if __name__ == "__main__":
    sys.exit(main())
