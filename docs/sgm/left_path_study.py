"""Issue 27's first question: which left-path recurrence can close at one position per clock?

Usage: ``python docs/sgm/left_path_study.py --dataset DIR --out docs/sgm/left_path_study.json``
(DIR: the Middlebury 2003 teddy folder, with disp6.pgm for the mirrored view), then
``--report`` to print the table of an existing ``--out``.

The left path's loop is the only one of the four that closes within a row: L(x, .) needs
m(x - 1) = min_d L(x - 1, d), a minimum over all D values of the position just before.
Each variant below keeps the unnormalised path cost Lu of one row exact in integers,

    Lu(x, d) = C(x, d) + min(Lu(x - s, d), Lu(x - s, d +- 1) + P1, ref(x) + P2(x)),

with Lu = C for the first s columns, and differs only in the step s and in ref(x), the
reference the large step is taken from (exact SGM: s = 1, ref(x) = min_d Lu(x - 1, d)):

- ``exact``: ref(x) = min_d Lu(x - s, d) (s = 1 was golden/sgm.py bit for bit before the
  tracked reference became the semantics; ``track 4 16`` was until the ninth session,
  ``track 8 32, P1 into odd columns`` is now, checked);
- ``stale K``: ref(x) = min_d Lu(x - K s, d), the minimum of an older position;
- ``comp K``: the stale minimum plus the smallest costs Cmin of the positions in between, a
  lower bound of the exact minimum;
- ``track J K``: the path cost of the disparity d* that was best K steps back, carried
  forward: ref(x) = Lu(x - J s, d*) + sum of C(i, d*) over the J - 1 positions i in
  between, with d* = argmin_d Lu(x - K s, d) (ties to the lowest d). An upper bound of the
  exact minimum (Lu(i, d) <= C(i, d) + Lu(i - s, d)), exact while the best disparity
  stays. In hardware it is a multiplexer of J registered steps and an argmin K steps
  old: no minimum over D inside the loop.

The output normalisation is exact SGM's, L(x, d) = Lu(x, d) - min_d Lu(x - s, d) (0 for the
first s columns), computed outside the loop. The three paths from the row above are
golden/sgm.py's. Scored with the project's metric, L/R check at 3, on teddy, teddy
mirrored and the synthetic scenes (seeds 0-2) at noise 0, 2e-4 and 2e-3.
"""

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np

from npstereo.golden import sgm
from npstereo.golden.data import load_middlebury, read_image
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair
from npstereo.params import (SGM_LEFT_P1_PARITY, SGM_ROW_PATHS, SGM_TRACK_AGE, SGM_TRACK_STEPS,
                             StereoParams)

#: (name, step s, kind, J, K[, (period, phase)]) of every variant measured; with a period,
#: only the steps into the columns x with x % period == phase take the P1 transitions (the
#: others stay or take the large step): with period 2 the loop closes over two positions
#: (docs/sgm.md, "Two clocks at R = 1").
VARIANTS = [("exact", 1, "exact", 0, 0),
            ("stale 8", 1, "stale", 0, 8), ("stale 12", 1, "stale", 0, 12),
            ("comp 2", 1, "comp", 0, 2), ("comp 4", 1, "comp", 0, 4),
            ("comp 8", 1, "comp", 0, 8),
            ("track 1 4", 1, "track", 1, 4), ("track 2 8", 1, "track", 2, 8),
            ("track 3 12", 1, "track", 3, 12), ("track 4 16", 1, "track", 4, 16),
            ("step 2, exact", 2, "exact", 0, 0), ("step 2, track 2 6", 2, "track", 2, 6),
            ("step 3, exact", 3, "exact", 0, 0),
            ("track 4 16, P1 into odd columns", 1, "track", 4, 16, (2, 1)),
            ("track 4 16, P1 into even columns", 1, "track", 4, 16, (2, 0)),
            ("track 8 32, P1 into odd columns", 1, "track", 8, 32, (2, 1))]
#: (transform, block, P1, P2, adaptive-P2 exponent): the default and census 5x5's best.
CONFIGS = [("census", 7, 24, 79, 5), ("census", 5, 16, 96, 4)]
NOISE = (0.0, 2e-4, 2e-3)
SEEDS = (0, 1, 2)


def left_path(volume, p1, p2_map, step, kind, j, k, p1_columns=None):
    """(L of the left path (H, W, D) int64, largest Lu(x, d) - min_d Lu(x, d))."""
    costs = volume.astype(np.int64).transpose(1, 0, 2)          # (W, H, D)
    width, height, _ = costs.shape
    p2 = p2_map.T.astype(np.int64)
    path = np.empty_like(costs)
    path[:step] = costs[:step]
    minima = path.min(axis=2)                                   # filled as x advances
    best = path.argmin(axis=2)
    cmin = costs.min(axis=2)
    rows = np.arange(height)
    spread = 0
    for x in range(step, width):
        previous = path[x - step]
        candidates = previous.copy()
        if p1_columns is None or x % p1_columns[0] == p1_columns[1]:
            candidates[:, 1:] = np.minimum(candidates[:, 1:], previous[:, :-1] + p1)
            candidates[:, :-1] = np.minimum(candidates[:, :-1], previous[:, 1:] + p1)
        first = x % step                                        # this step's first column
        if kind == "exact":
            ref = minima[x - step]
        elif kind in ("stale", "comp"):
            older = x - k * step
            ref = minima[max(older, first)]
            if kind == "comp" or older < first:
                ref = ref + sum(cmin[i] for i in range(max(older, first) + step, x, step))
        else:
            chosen = best[max(x - k * step, first)]
            since = max(x - j * step, first)
            ref = path[since, rows, chosen] + sum(costs[i, rows, chosen]
                                                  for i in range(since + step, x, step))
        path[x] = costs[x] + np.minimum(candidates, (ref + p2[x])[:, None])
        minima[x], best[x] = path[x].min(axis=1), path[x].argmin(axis=1)
        spread = max(spread, int((path[x].max(axis=1) - minima[x]).max()))
    normalised = path.copy()
    normalised[step:] -= minima[:-step, :, None]
    return normalised.transpose(1, 0, 2), spread


def score(left, right, truth, disparities, config, variant):
    transform, block, p1, p2, adapt = config
    _, step, kind, j, k = variant[:5]
    p1_columns = variant[5] if len(variant) > 5 else None
    params = StereoParams(transform=transform, block=block, disparities=disparities)
    volume = sgm.cost_volume(left, right, params)
    rows = sum(sgm.path_costs(volume, path, p1, p2, guide=left, adapt=adapt,
                              max_cost=params.max_cost).astype(np.int64)
               for path in SGM_ROW_PATHS)
    left_costs, spread = left_path(volume, p1, sgm.path_p2(left, "left", p1, p2, adapt),
                                   step, kind, j, k, p1_columns)
    summed = rows + left_costs
    # The golden model's left path: P1 into the columns of its parity only.
    golden_left = (1, "track", SGM_TRACK_STEPS, SGM_TRACK_AGE, (2, SGM_LEFT_P1_PARITY))
    if (step, kind, j, k, p1_columns) == golden_left:
        golden = sgm.aggregate(volume, p1, p2, guide=left, adapt=adapt,
                               max_cost=params.max_cost)
        assert np.array_equal(summed, golden), f"{variant[0]} must be golden/sgm.py"
    disparity = sgm.disparity_from_summed(summed, 3).disparity
    return round(evaluate(disparity, truth, disparities).correct, 3), spread


def teddy_views(pair, dataset):
    """(name, left, right, ground truth, D) of teddy and of its other view as the
    reference (mirrored, ground truth disp6.pgm)."""
    left, right = pair.gray()
    yield "teddy", left, right, pair.ground_truth, 100
    truth = read_image(Path(dataset) / "disp6.pgm", "ground truth").astype(np.float64)
    yield ("teddy mirrored", np.ascontiguousarray(right[:, ::-1]),
           np.ascontiguousarray(left[:, ::-1]),
           np.ascontiguousarray(np.where(truth == 0, np.nan, truth / 4)[:, ::-1]), 100)


def synthetic_conditions():
    """The synthetic scenes (seeds 0-2) at each noise level, D = 48."""
    for noise, seed in itertools.product(NOISE, SEEDS):
        scene = synthetic_pair(256, 192, 48, seed=seed)
        sl, sr = scene.gray()
        if noise:
            sl, sr = gaussian_noise_pair(sl, sr, noise, seed=seed)
        yield f"synthetic noise {noise:g} s{seed}", sl, sr, scene.ground_truth, 48


def conditions(dataset):
    pair = load_middlebury(dataset)
    yield from teddy_views(pair, dataset)
    yield from synthetic_conditions()


def report(rows):
    """Markdown: per configuration and variant, the change from exact SGM per condition
    (the synthetic seeds pooled by noise level) and the largest shortfall."""
    def condition(scene):
        return scene.rsplit(" ", 1)[0] if scene.startswith("synthetic") else scene
    names = list(dict.fromkeys(condition(r["scene"]) for r in rows))
    lines = []
    for config in dict.fromkeys(r["config"] for r in rows):
        table = {}
        for r in (r for r in rows if r["config"] == config):
            table.setdefault(r["variant"], {}).setdefault(condition(r["scene"]), []).append(
                (r["correct"], r["spread"]))
        exact = {c: np.mean([v for v, _ in vs]) for c, vs in table["exact"].items()}
        lines += [f"#### {config}", "", "| left path | " + " | ".join(names)
                  + " | largest shortfall | largest spread |",
                  "|---|" + "---:|" * (len(names) + 2)]
        for variant, by_condition in table.items():
            means = {c: np.mean([v for v, _ in vs]) for c, vs in by_condition.items()}
            change = {c: means[c] - exact[c] for c in means}
            spread = max(s for vs in by_condition.values() for _, s in vs)
            cells = [f"{means[c]:.2f}" if variant == "exact" else
                     f"{means[c]:.2f} ({change[c]:+.2f})" for c in names]
            shortfall = max(0.0, -min(change.values()))
            lines.append(f"| {variant} | " + " | ".join(cells) + f" | {shortfall:.2f} | "
                         f"{spread} |")
        lines.append("")
    return "\n".join(lines)


def config_label(config):
    """A configuration of :data:`CONFIGS` as the tables name it."""
    return f"{config[0]} {config[1]}x{config[1]}, P1 = {config[2]}, P2 = {config[3]}, " \
           f"t = {config[4]}"


def rows_json(rows):
    """``{"rows": [...]}`` with one row per line (a study's rows are many and alike)."""
    return "{\"rows\": [\n" + ",\n".join(json.dumps(row) for row in rows) + "\n]}\n"


def study_main(argv, description, measure, report, configs=CONFIGS, group_of=None):
    """The command line of a study: ``--report`` prints ``report(rows)`` of ``--out``;
    otherwise ``measure(dataset, config)`` yields the rows of each configuration of
    ``configs`` (default :data:`CONFIGS`), written to ``--out`` after every configuration (an interrupted run
    keeps what it measured). With ``group_of`` (a row's configuration) ``--only CONFIG``
    measures that one configuration and keeps the other rows of an existing ``--out``, so
    that an option added later costs its own run, not the whole study's."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--dataset", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--report", action="store_true",
                        help="print the table of an existing --out instead of measuring")
    if group_of is not None:
        parser.add_argument("--only", choices=configs,
                            help="measure this configuration alone, keep the other rows of "
                                 "--out")
    args = parser.parse_args(argv)
    if args.report:
        print(report(json.loads(args.out.read_text())["rows"]))
        return 0
    if args.dataset is None:
        parser.error("--dataset is needed to measure (teddy: Middlebury 2003 with disp6.pgm)")
    rows = []
    if getattr(args, "only", None):
        if args.out.exists():
            rows = [row for row in json.loads(args.out.read_text())["rows"]
                    if group_of(row) != args.only]
        configs = (args.only,)
    for config in configs:
        rows += measure(args.dataset, config)
        tmp = args.out.with_suffix(".tmp")
        tmp.write_text(rows_json(rows))
        tmp.replace(args.out)
    print(report(rows))
    return 0


def measure(dataset, config, variants=VARIANTS):
    """The rows of every scene and variant (of ``variants``) for one configuration."""
    label = config_label(config)
    for scene, left, right, truth, disparities in conditions(dataset):
        for variant in variants:
            correct, spread = score(left, right, truth, disparities, config, variant)
            print(f"{label} | {scene:26s} | {variant[0]:18s} {correct:6.2f} "
                  f"spread {spread}", flush=True)
            yield dict(config=label, scene=scene, variant=variant[0], correct=correct,
                       spread=spread)


def main(argv=None):
    return study_main(argv, __doc__.splitlines()[0], measure, report)


if __name__ == "__main__":
    sys.exit(main())
