"""Which plausible differences in the paper's set-up explain the gap to its Fig. 6?

Investigation script behind docs/quality.md (not part of the tool): it evaluates the golden
model under variants of the *inputs* and of the *evaluation* (gray conversion, ground-truth
rounding, border treatment, metric reading, L/R threshold) that the paper does not pin down.
The golden model's own semantics are never changed; each variant is applied around it.

Usage: .venv/bin/python docs/paper/variants.py --dataset DIR [--blocks 9 19] [--jobs 2]
       .venv/bin/python docs/paper/variants.py --dataset DIR --sweep [--jobs 2]
           [--noise-levels 0.00005 0.0002]
(--sweep: every gray conversion at every Fig. 6 block size, mean absolute difference to the
paper with the evaluation as defined and with the window's border pixels counted as wrong;
with --noise-levels, BT.601 plus faint gaussian noise instead of the gray conversions.)
"""

import argparse
import json
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from PIL import Image

from npstereo.gen.reports.paper_data import PAPER_BLOCKS, PAPER_FIG6
from npstereo.golden.data import load_middlebury, to_gray
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.params import TRANSFORMS, StereoParams
from npstereo.golden.pipeline import disparity_map

D = 100


def gray_variants(rgb):
    """8-bit gray conversions a 2008 tool chain might have used."""
    f = rgb.astype(np.float64)
    return {
        "BT.601 integer (ours)": to_gray(rgb),
        "PIL convert('L')": np.asarray(Image.fromarray(rgb).convert("L")),
        "MATLAB rgb2gray (rounded)": np.round(f @ [0.2989, 0.5870, 0.1140]).astype(np.uint8),
        "BT.601 truncated": np.floor(f @ [0.299, 0.587, 0.114]).astype(np.uint8),
        "mean of R, G, B": np.round(f.mean(axis=2)).astype(np.uint8),
        "green channel": rgb[..., 1].copy(),
    }


def correct(disparity, truth, strict=False, exclude=None):
    """Correct matches (%) with optional strict tolerance and excluded pixels."""
    known = ~np.isnan(truth)
    known[:, :D] = False
    if exclude is not None:
        known &= ~exclude
    error = np.abs(disparity - np.nan_to_num(truth))
    good = (disparity >= 0) & ((error < 1) if strict else (error <= 1)) & known
    return 100.0 * good.sum() / known.sum()


def match(job):
    left, right, params, pad = job
    if pad:
        # Replicate padding instead of zero padding: pad the images, crop the result.
        left = np.pad(left, pad, mode="edge")
        right = np.pad(right, pad, mode="edge")
        return disparity_map(left, right, params, threads=1).disparity[pad:-pad, pad:-pad]
    return disparity_map(left, right, params, threads=1).disparity


def border_frame(shape, block):
    """Rows and right-hand columns whose transform window leaves the image (r + 1 for the
    3x3 aggregation): a core without border handling produces no valid result there."""
    r = (block - 1) // 2 + 1
    frame = np.zeros(shape, bool)
    frame[:r], frame[-r:], frame[:, -r:] = True, True, True
    return frame


def sweep(pair, jobs_n, noise_levels=()):
    """Fig. 6 mean absolute difference for every gray conversion, two border readings.

    With ``noise_levels``, the gray variants are instead BT.601 plus faint gaussian noise of
    each variance: do all four transforms move towards the paper when the input is
    slightly noisier than ours?
    """
    truth = pair.ground_truth
    grays_l, grays_r = gray_variants(pair.left), gray_variants(pair.right)
    if noise_levels:
        base_l, base_r = grays_l["BT.601 integer (ours)"], grays_r["BT.601 integer (ours)"]
        grays_l, grays_r = {}, {}
        for level in noise_levels:
            name = f"BT.601 + noise variance {level:g}"
            grays_l[name], grays_r[name] = gaussian_noise_pair(base_l, base_r, level, seed=0)
    keys = [(name, t, b) for name in grays_l for t in TRANSFORMS for b in PAPER_BLOCKS]
    jobs = [(grays_l[n], grays_r[n], StereoParams(t, b, D), 0) for n, t, b in keys]
    with ProcessPoolExecutor(jobs_n) as pool:
        maps = dict(zip(keys, pool.map(match, jobs)))
    print("| gray conversion | border | rank | census | ext-rank | ext-census | overall |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for name in grays_l:
        for border in ("as defined (zero padding)", "counted as wrong"):
            mads = []
            for t in TRANSFORMS:
                diffs = []
                for i, b in enumerate(PAPER_BLOCKS):
                    disparity = maps[(name, t, b)]
                    if border != "as defined (zero padding)":
                        disparity = np.where(border_frame(truth.shape, b), -1, disparity)
                    diffs.append(abs(correct(disparity, truth) - PAPER_FIG6[t][i]))
                mads.append(np.mean(diffs))
            print(f"| {name} | {border} | " + " | ".join(f"{m:.2f}" for m in mads)
                  + f" | {np.mean(mads):.2f} |")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", required=True)
    parser.add_argument("--blocks", type=int, nargs="+", default=[9, 19])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--json")
    parser.add_argument("--sweep", action="store_true")
    parser.add_argument("--noise-levels", type=float, nargs="+", default=())
    args = parser.parse_args(argv)
    pair = load_middlebury(args.dataset)
    if args.sweep:
        sweep(pair, args.jobs, args.noise_levels)
        return
    truth = pair.ground_truth
    height, width = truth.shape
    grays_l, grays_r = gray_variants(pair.left), gray_variants(pair.right)
    ours = "BT.601 integer (ours)"

    jobs = {}
    for t in TRANSFORMS:
        for b in args.blocks:
            params = StereoParams(t, b, D)
            for name in grays_l:
                jobs[(t, b, name)] = (grays_l[name], grays_r[name], params, 0)
            jobs[(t, b, "replicate padding")] = (grays_l[ours], grays_r[ours], params, b)
            jobs[(t, b, "no L/R check")] = (grays_l[ours], grays_r[ours],
                                            params.replace(lr_threshold=None), 0)
            jobs[(t, b, "L/R threshold 1")] = (grays_l[ours], grays_r[ours],
                                               params.replace(lr_threshold=1), 0)
            jobs[(t, b, "xi as P >= P' (inverted images)")] = (
                255 - grays_l[ours], 255 - grays_r[ours], params, 0)
    keys = list(jobs)
    with ProcessPoolExecutor(args.jobs) as pool:
        maps = dict(zip(keys, pool.map(match, [jobs[k] for k in keys])))

    rounded, floored = np.round(truth), np.floor(truth)
    rows = []
    for t in TRANSFORMS:
        for b in args.blocks:
            base = maps[(t, b, ours)]
            frame = border_frame(truth.shape, b)
            paper = PAPER_FIG6[t][PAPER_BLOCKS.index(b)] if b in PAPER_BLOCKS else None
            results = {name: correct(maps[(t, b, name)], truth)
                       for name in list(grays_l) + ["replicate padding", "no L/R check",
                                                    "L/R threshold 1",
                                                    "xi as P >= P' (inverted images)"]}
            results["ground truth rounded to integers"] = correct(base, rounded)
            results["ground truth floored to integers"] = correct(base, floored)
            results["strict |d - gt| < 1"] = correct(base, truth, strict=True)
            results["border rows/columns of the window not evaluated"] = correct(
                base, truth, exclude=frame)
            results["border pixels counted as wrong"] = correct(
                np.where(frame, -1, base), truth)
            for name, value in results.items():
                rows.append({"transform": t, "block": b, "variant": name, "correct": value,
                             "paper": paper})
    print(f"| variant | " + " | ".join(f"{t} {b}x{b}" for t in TRANSFORMS for b in args.blocks)
          + " |")
    print("|---|" + "---:|" * (len(TRANSFORMS) * len(args.blocks)))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    table = {(r["transform"], r["block"], r["variant"]): r["correct"] for r in rows}
    print("| paper | " + " | ".join(
        f"{PAPER_FIG6[t][PAPER_BLOCKS.index(b)]:.2f}" if b in PAPER_BLOCKS else "-"
        for t in TRANSFORMS for b in args.blocks) + " |")
    for v in variants:
        print(f"| {v} | " + " | ".join(f"{table[(t, b, v)]:.2f}" for t in TRANSFORMS
                                       for b in args.blocks) + " |")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(rows, handle, indent=1)
    print(f"image {width}x{height}", file=sys.stderr)


if __name__ == "__main__":
    main()
