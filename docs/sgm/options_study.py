"""Issue 28's quality options, each alone and combined, in the golden model, beside OpenCV.

Usage: ``python docs/sgm/options_study.py --dataset DIR --out docs/sgm/options_study.json``
(DIR: the Middlebury 2003 teddy folder, with disp6.pgm for the mirrored view and colour
images for the Bayer stand-in), then ``--report`` to print the tables of an existing ``--out``.

Every map is scored with the project's metric (golden/quality.py), with the L/R check at
T = 3 and without it, on teddy (D = 100), teddy mirrored, teddy through the Bayer stand-in
(golden/degrade.py, raw RGGB mosaic as the gray image, gen/matching.py's Condition), teddy
with gaussian noise of variance 2e-3 (seed 0, bench_quality's ``--noise 0.002``: issue 28's
second bar) and the synthetic scenes (seeds 0-2, D = 48) at gaussian noise 0, 2e-4 and
2e-3. OpenCV StereoSGBM
in MODE_SGBM and MODE_HH are measured in the same run with tests/bench_quality.py's peer
code (its settings and the conversions that make them comparable, docs/sgm.md).

The options, on top of the golden SGM (census 7x7, the four raster paths with the tracked
left path, golden/sgm.py):

- ``5 paths``: a fifth path, right to left along the row, in exact SGM form (normalised by
  the successor's minimum over d), P2 adapted to |I(x) - I(x + 1)| like the left path's, so
  the left path mirrored; it is the ``top`` path of the volume transposed with x reversed;
- ``5 tracked paths`` (group ``fifth``): the fifth path as the golden model defines it
  (``StereoParams.fifth_path``, docs/semantics.md "The fifth path"): the tracked left path
  of the mirrored row, which hardware can run at one position per clock;
- ``uniq k``: reject the winner d* when some d with |d - d*| > 1 has S(d) (1 - 2^-k) < S(d*),
  in integers (S2 << k) - S2 < (S(d*) << k) with S2 the smallest S outside d* - 1 .. d* + 1:
  OpenCV's uniquenessRatio u = 100 / 2^k (k = 2, 3, 4: 25, 12.5, 6.25 %), a shift and a
  subtraction instead of a multiplication; applied to the left map beside the check;
- ``median``: a 3x3 median of the final disparity stream (after the check), pixels outside
  the frame invalid; ``plain`` takes the median of the nine values with invalid as -1 (a
  9-input median network), ``valid`` the lower median of the valid values of the window for
  a valid centre (an invalid one stays invalid), ``fill`` as ``valid`` and also for an
  invalid centre with at least 5 valid neighbours;
- costs that hold in weak texture: C = census + a term of at most 7 added to the Hamming
  distance (Cmax 55, so P2 <= 72 keeps the path costs at 7 bits): ``ad`` min(|IL(x) -
  IR(x - d)|, 31) >> 2, ``grad`` the same of the horizontal gradients I(x + 1) - I(x - 1)
  (borders replicated), ``ad3`` the 3x3 sum of min(AD, 31) over the window, at most 255,
  >> 5 (borders replicated); ``ad3 exact`` the term as built (golden/cost_term.py: zero
  padding, right column 0 left out), through the golden SGM cost volume of
  ``cost_term="ad3"``, at 24/72/5 only (``--only "ad3 exact"`` measures its rows into --out);
- ``blur``: census 7x7 on images through a 3x3 binomial prefilter (added after teddy with
  noise 2e-3 showed the gap there); the guide of adaptive P2 is the filtered image too;
- penalties P1, P2 and adaptive P2's t re-chosen on all seven conditions.
"""

import itertools
import sys
from pathlib import Path

import numpy as np

from npstereo.gen.matching import Condition, condition_images
from npstereo.golden import sgm
from npstereo.golden.data import load_middlebury
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.golden.lr_check import INVALID
from npstereo.golden.quality import evaluate
from npstereo.params import SGM_PATHS, StereoParams

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from left_path_study import (study_main, synthetic_conditions,  # noqa: E402
                             teddy_views)  # (the studies' shared command line and scenes)
from bench_quality import LR_THRESHOLD, opencv_maps, opencv_matchers  # noqa: E402

#: Measurement groups, one JSON update each: the peers, each matching cost, the census
#: cost's grid widened (smaller P1, t = 3 and a constant P2) once the median had changed the
#: best penalties, census on prefiltered images (added after teddy with noise), the ad3
#: term as built, the golden model's tracked fifth path, and both together (each added with
#: what it measures).
GROUPS = ("peers", "census", "ad", "grad", "ad3", "census wide", "blur", "ad3 exact",
          "fifth", "fifth ad3")
#: Penalty grids (P1, P2, t): the census one around the defaults, the others' P2 at most
#: 127 - Cmax so that the path costs stay at 7 bits as the defaults' do.
CENSUS_GRID = list(itertools.product((16, 24, 32), (48, 64, 79), (4, 5)))
EXTRA_GRID = list(itertools.product((16, 24), (64, 72), (5,)))
BLUR_GRID = list(itertools.product((16, 24), (64, 79), (5,)))
#: The tracked fifth path's penalties: the defaults, the best of the exact fifth path
#: (constant P2) and the neighbours of the defaults in each direction.
FIFTH_GRID = [(24, 79, 5), (24, 79, None), (16, 79, 5), (32, 79, 5), (24, 64, 5),
              (16, 79, 4)]
#: The ``paths`` value of the rows with the tracked fifth path (4 and 5 are the four
#: raster-order paths and the exact fifth path).
TRACKED = "5 tracked"
WIDE_GRID = list(itertools.product((8, 12), (48, 64, 79), (3, 4, 5, None))) + \
    list(itertools.product((16, 24), (64, 79), (3, None)))
UNIQUENESS = (0, 2, 3, 4)
MEDIANS = ("none", "plain", "valid", "fill")
BASE = dict(cost="census", p1=24, p2=79, adapt=5, paths=4, uniq=0, median="none")


def conditions(dataset):
    """(name, left, right, ground truth, D) of every scene."""
    pair = load_middlebury(dataset)
    yield from teddy_views(pair, dataset)
    left, right = pair.gray()
    bayer_left, bayer_right = condition_images(pair, Condition(bayer=True))
    yield "teddy bayer", bayer_left, bayer_right, pair.ground_truth, 100
    noisy_left, noisy_right = gaussian_noise_pair(left, right, 2e-3, seed=0)
    yield "teddy noise 0.002", noisy_left, noisy_right, pair.ground_truth, 100
    yield from synthetic_conditions()


def _shifted(image, d):
    """image(x - d), columns x < d replicated from column 0 (their cost is Cmax anyway)."""
    out = np.empty_like(image)
    out[:, d:] = image[:, :image.shape[1] - d]
    out[:, :d] = image[:, :1]
    return out


def extra_term(kind, left, right, disparities):
    """The added cost term of ``kind`` as (H, W, D) int64, each value 0 .. 7."""
    left, right = left.astype(np.int64), right.astype(np.int64)
    if kind == "grad":
        def gradient(image):
            padded = np.pad(image, ((0, 0), (1, 1)), mode="edge")
            return padded[:, 2:] - padded[:, :-2]
        left, right = gradient(left), gradient(right)
    term = np.empty(left.shape + (disparities,), np.int64)
    for d in range(disparities):
        clipped = np.minimum(np.abs(left - _shifted(right, d)), 31)
        if kind == "ad3":
            padded = np.pad(clipped, 1, mode="edge")
            rows, cols = clipped.shape
            clipped = sum(padded[i:i + rows, j:j + cols] for i in range(3) for j in range(3))
            term[:, :, d] = np.minimum(clipped, 255) >> 5
        else:
            term[:, :, d] = clipped >> 2
    return term


def binomial(image):
    """The 3x3 binomial filter ([1 2 1] x [1 2 1] / 16, rounded, borders replicated): a
    prefilter of two line buffers and adders in hardware, shifts only."""
    padded = np.pad(image.astype(np.int64), 1, mode="edge")
    weights = (1, 2, 1)
    height, width = image.shape
    total = sum(weights[i] * weights[j] * padded[i:i + height, j:j + width]
                for i in range(3) for j in range(3))
    return ((total + 8) >> 4).astype(np.uint8)


def right_path(volume, p1, p2, guide, adapt, max_cost):
    """L of the path from the right (exact SGM form): the top path of the volume with x
    reversed and transposed, so that the predecessor of (x, y) is (x + 1, y)."""
    flipped = np.ascontiguousarray(volume[:, ::-1].transpose(1, 0, 2))
    guide_t = np.ascontiguousarray(guide[:, ::-1].T)
    path = sgm.path_costs(flipped, "top", p1, p2, guide=guide_t, adapt=adapt,
                          max_cost=max_cost)
    return path.transpose(1, 0, 2)[:, ::-1].astype(np.int64)


def uniqueness_reject(summed, k):
    """(H, W) bool: the winner is not unique at 1 - 2^-k (module docstring)."""
    best = summed.argmin(axis=2)
    best_cost = np.take_along_axis(summed, best[..., None], axis=2)[..., 0]
    far = np.abs(np.arange(summed.shape[2])[None, None, :] - best[..., None]) > 1
    second = np.where(far, summed, np.iinfo(np.int64).max // 4).min(axis=2)
    return (second << k) - second < (best_cost << k)


def median3(disparity, kind):
    """3x3 median of a map (INVALID = -1), pixels outside the frame invalid."""
    if kind == "none":
        return disparity
    padded = np.pad(disparity.astype(np.int16), 1, constant_values=INVALID)
    rows, cols = disparity.shape
    window = np.sort(np.stack([padded[i:i + rows, j:j + cols] for i in range(3)
                               for j in range(3)]), axis=0)
    if kind == "plain":
        return window[4]
    invalid = (window < 0).sum(axis=0)                   # invalid values sort first
    lower = np.take_along_axis(window, ((8 + invalid) // 2)[None], axis=0)[0]
    keep = (invalid < 9) & ((disparity >= 0) if kind == "valid" else
                            (disparity >= 0) | (invalid <= 4))
    return np.where(keep, lower, INVALID).astype(np.int16)


def stored(row):
    """Whether a row is kept in ``--out``: every variant at the defaults' penalties (those
    of :data:`ALONE`), at the other penalties only those without uniqueness test with no or
    the chosen (``fill``) median, which the tables of the best penalties compare."""
    if "method" in row:
        return True
    base = (row["p1"], row["p2"], row["adapt"]) in ((24, 79, 5), (24, 72, 5))
    return base or (row["uniq"] == 0 and row["median"] in ("none", "fill"))


def score_summed(summed, truth, disparities):
    """Rows (paths set by the caller) of every uniqueness, check and median variant."""
    checked = sgm.disparity_from_summed(summed, LR_THRESHOLD)
    unchecked = checked.left.copy()
    unchecked[:, :disparities] = INVALID
    for k in UNIQUENESS:
        reject = uniqueness_reject(summed, k) if k else np.zeros(unchecked.shape, bool)
        for lr, base in (("no", unchecked), ("yes", checked.disparity)):
            kept = np.where(reject, INVALID, base).astype(np.int16)
            for median in MEDIANS:
                correct = evaluate(median3(kept, median), truth, disparities).correct
                yield dict(uniq=k, lr=lr, median=median, correct=round(correct, 3))


def measure_peers(dataset):
    import cv2
    for scene, left, right, truth, disparities in conditions(dataset):
        num_disparities = -(-disparities // 16) * 16
        for name, matcher in opencv_matchers(cv2, num_disparities):
            if "SGBM" not in name:
                continue
            maps = opencv_maps(cv2, matcher, left, right, disparities, num_disparities)
            for lr, disparity in zip(("no", "yes"), maps):
                correct = round(evaluate(disparity, truth, disparities).correct, 3)
                print(f"{scene:26s} | {name} L/R {lr}: {correct:6.2f}", flush=True)
                yield dict(scene=scene, method=name, lr=lr, correct=correct)


def measure(dataset, group):
    """The rows of one group of :data:`GROUPS` over every scene."""
    if group == "peers":
        yield from measure_peers(dataset)
        return
    grid = {"census": CENSUS_GRID, "census wide": WIDE_GRID, "blur": BLUR_GRID,
            "ad3 exact": [(24, 72, 5)], "fifth": FIFTH_GRID,
            "fifth ad3": [(24, 72, 5)]}.get(group, EXTRA_GRID)
    cost = {"fifth": "census", "ad3 exact": "ad3 exact",
            "fifth ad3": "ad3 exact"}.get(group, group.split()[0])
    for scene, left, right, truth, disparities in conditions(dataset):
        params = StereoParams(transform="census", block=7, disparities=disparities)
        if cost == "ad3 exact":
            params = params.replace(aggregation="sgm", cost_term="ad3")
        if cost == "blur":
            left, right = binomial(left), binomial(right)
        volume = sgm.cost_volume(left, right, params).astype(np.int64)
        max_cost = params.max_cost
        if cost not in ("census", "blur", "ad3 exact"):
            volume = volume + extra_term(cost, left, right, disparities)
            max_cost += 7
            # x - d < 0: no partner pixel, Cmax as golden/sgm.py's cost_volume has it.
            volume[:, np.arange(disparities)[None, :] > np.arange(left.shape[1])[:, None]] \
                = max_cost
        for p1, p2, adapt in grid:
            four = sum(sgm.path_costs(volume, path, p1, p2, guide=left, adapt=adapt,
                                      max_cost=max_cost).astype(np.int64)
                       for path in SGM_PATHS)
            if group in ("fifth", "fifth ad3"):
                five = four + sgm.right_path_costs(volume, p1, p2, left, adapt,
                                                   max_cost).astype(np.int64)
                variants = ((TRACKED, five),)
            else:
                five = four + right_path(volume, p1, p2, left, adapt, max_cost)
                variants = ((4, four), (5, five))
            for paths, summed in variants:
                for row in score_summed(summed, truth, disparities):
                    row = dict(scene=scene, cost=cost, p1=p1, p2=p2, adapt=adapt,
                               paths=paths, **row)
                    if stored(row):
                        yield row
            print(f"{group:6s} {scene:26s} P1={p1} P2={p2} t={adapt}: 4 paths "
                  f"{_base(four, truth, disparities):6.2f}, {variants[-1][0]} paths "
                  f"{_base(five, truth, disparities):6.2f} (L/R check)", flush=True)


def _base(summed, truth, disparities):
    return evaluate(sgm.disparity_from_summed(summed, LR_THRESHOLD).disparity, truth,
                    disparities).correct


def condition_of(scene):
    return scene.rsplit(" ", 1)[0] if scene.startswith("synthetic") else scene


def means(rows, **fixed):
    """{condition: mean correct} of the rows matching ``fixed`` (seeds pooled)."""
    pooled = {}
    for r in rows:
        if all(r.get(key) == value for key, value in fixed.items()):
            pooled.setdefault(condition_of(r["scene"]), []).append(r["correct"])
    return {c: float(np.mean(v)) for c, v in pooled.items()}


#: The rows of the first table: each option alone on the defaults, then combinations, as
#: (cost, P1, P2, t, paths, uniq, median).
ALONE = [("census", 24, 79, 5, 4, 0, "none"), ("census", 24, 79, 5, 5, 0, "none"),
         ("blur", 24, 79, 5, 4, 0, "none"), ("blur", 24, 79, 5, 4, 0, "fill"),
         ("census", 24, 79, 5, 4, 0, "plain"), ("census", 24, 79, 5, 4, 0, "valid"),
         ("census", 24, 79, 5, 4, 0, "fill"), ("census", 24, 79, 5, 4, 2, "none"),
         ("census", 24, 79, 5, 4, 3, "none"), ("census", 24, 79, 5, 4, 4, "none"),
         ("ad", 24, 72, 5, 4, 0, "none"), ("grad", 24, 72, 5, 4, 0, "none"),
         ("ad3", 24, 72, 5, 4, 0, "none"),
         ("census", 24, 79, 5, 5, 0, "fill"), ("census", 24, 79, 5, 4, 4, "fill"),
         ("ad", 24, 72, 5, 4, 0, "fill"), ("ad3", 24, 72, 5, 4, 0, "fill"),
         ("ad", 24, 72, 5, 5, 0, "fill"), ("ad3", 24, 72, 5, 5, 0, "fill"),
         ("ad3 exact", 24, 72, 5, 4, 0, "none"), ("ad3 exact", 24, 72, 5, 4, 0, "fill"),
         ("ad3 exact", 24, 72, 5, 5, 0, "fill"),
         ("census", 24, 79, 5, TRACKED, 0, "none"), ("census", 24, 79, 5, TRACKED, 0, "fill"),
         ("census", 24, 79, None, 5, 0, "none"), ("census", 24, 79, None, TRACKED, 0, "none"),
         ("census", 24, 79, None, 5, 0, "fill"), ("census", 24, 79, None, TRACKED, 0, "fill"),
         ("ad3 exact", 24, 72, 5, TRACKED, 0, "none"), ("ad3 exact", 24, 72, 5, TRACKED, 0, "fill")]


def _label(key):
    cost, p1, p2, adapt, paths, uniq, median = key
    t = "off" if adapt is None else adapt
    return (f"{cost} {p1}/{p2}/t={t}, {paths} paths" + (f", uniq {uniq}" if uniq else "")
            + ("" if median == "none" else f", median {median}"))


def report(rows):
    """Markdown tables per L/R check: the peers, each option alone and combined (with the
    defaults' penalties), and the best penalties of each combination of cost, paths and
    median; means over the six conditions and the differences to OpenCV MODE_HH."""
    peers = [r for r in rows if "method" in r]
    ours = [r for r in rows if "method" not in r]
    names = list(dict.fromkeys(condition_of(r["scene"]) for r in rows))
    fields = ("cost", "p1", "p2", "adapt", "paths", "uniq", "median")
    table = {}
    for r in ours:
        key = tuple(r[f] for f in fields)
        table.setdefault((r["lr"], key), {}).setdefault(condition_of(r["scene"]), []).append(
            r["correct"])
    lines = []
    for lr in ("yes", "no"):
        hh = means(peers, method="OpenCV StereoSGBM MODE_HH", lr=lr)

        def line(label, values):
            mean = np.mean([values[c] for c in names])
            worst = min(values[c] - hh[c] for c in names)
            return (f"| {label} | " + " | ".join(f"{values[c]:.2f}" for c in names)
                    + f" | {mean:.2f} | {mean - np.mean(list(hh.values())):+.2f} | "
                    f"{worst:+.2f} |")

        def values_of(key):
            pooled = table.get((lr, key), {})
            if len(pooled) < len(names):
                return None
            return {c: float(np.mean(v)) for c, v in pooled.items()}

        lines += [f"#### L/R check {'on (T = 3)' if lr == 'yes' else 'off'}", "",
                  "| configuration | " + " | ".join(names)
                  + " | mean | mean vs HH | worst condition vs HH |",
                  "|---|" + "---:|" * (len(names) + 3)]
        for method in dict.fromkeys(r["method"] for r in peers):
            lines.append(line(method, means(peers, method=method, lr=lr)))
        lines += [line(_label(key), values) for key in ALONE
                  if (values := values_of(key)) is not None]
        lines += ["", "Best penalties of each combination (mean over the conditions):", "",
                  "| cost, paths, median | best P1/P2/t | " + " | ".join(names)
                  + " | mean | mean vs HH | worst condition vs HH |",
                  "|---|---|" + "---:|" * (len(names) + 3)]
        for cost, paths, median in itertools.product(("census", "ad", "grad", "ad3", "blur",
                                                      "ad3 exact"),
                                                     (4, 5, TRACKED),
                                                     ("none", "fill")):
            candidates = [(np.mean(list(values.values())), key, values)
                          for (check, key), _ in table.items()
                          if check == lr and key[0] == cost and key[4] == paths
                          and key[5] == 0 and key[6] == median
                          and (values := values_of(key)) is not None]
            if candidates:
                _, key, values = max(candidates, key=lambda c: c[0])
                t = "off" if key[3] is None else key[3]
                lines.append(line(f"{cost}, {paths} paths, median {median} | "
                                  f"{key[1]}/{key[2]}/t={t}", values))
        lines.append("")
    return "\n".join(lines)


def group_of(row):
    """The group of :data:`GROUPS` that measured ``row`` (``--only`` replaces its rows)."""
    if "method" in row:
        return "peers"
    if row["paths"] == TRACKED:
        return "fifth ad3" if row["cost"] == "ad3 exact" else "fifth"
    if row["cost"] != "census":
        return row["cost"]
    census = (row["p1"], row["p2"], row["adapt"]) in CENSUS_GRID
    return "census" if census else "census wide"


def main(argv=None):
    return study_main(argv, __doc__.splitlines()[0], measure, report, configs=GROUPS,
                      group_of=group_of)


if __name__ == "__main__":
    sys.exit(main())
