"""Quality side by side: npstereo's box and SGM configurations against OpenCV's matchers.

Usage: ``python tests/bench_quality.py --dataset DIR [--disparities 100] [--json FILE]``,
where DIR is a Middlebury scene folder (any layout golden/data.py loads, e.g. teddy), or
``--synthetic [--seed N]`` for the project's synthetic scene (256 x 192, D = 48); both
take ``--noise VARIANCE`` (golden/degrade.py, seeded by ``--seed``), and ``--mirrored``
makes the other view of a Middlebury 2003 folder the reference (ground truth disp6.pgm). Every
map is scored with the project's own metric (golden/quality.py: |d - gt| <= 1 over the
pixels with known ground truth at x >= D, an invalid pixel counts as wrong), with and
without the project's L/R check (threshold 3), and the table ends with the ratio of the
best npstereo SGM configuration to the best peer. The bar of issue 12: ratio >= 1.
A last column gives the mean |d - gt| of the correct pixels, where a sub-pixel fraction
shows (issue 28): the README's recommendation with F = 4 fractional bits has its row, and
OpenCV's SGBM maps with their own 1/16 fractions kept have theirs ("peer fraction", beside
the bar, not in it).

The peers (``opencv-python-headless``, a ``bench``/``test`` extra of the project):

- ``cv2.StereoSGBM`` in MODE_SGBM (the four raster-order paths, like ours) and MODE_HH
  (eight paths, two passes), blockSize 5, P1 = 8 * 5^2, P2 = 32 * 5^2, uniquenessRatio 0,
  no speckle filter, disp12MaxDiff off (the L/R check is ours, applied or not);
- ``cv2.StereoBM`` 9x9, uniquenessRatio 0 (the same no-filter treatment as SGBM; its
  defaults otherwise).

How the OpenCV maps are made comparable (docs/sgm.md, "Peers benchmark"):

- OpenCV needs numDisparities to be a multiple of 16: the next one >= D (112 for D = 100).
  OpenCV then searches 0 .. 111 where npstereo searches 0 .. D - 1, so results above D - 1
  are treated as invalid (they are outside the range the comparison is about).
- OpenCV leaves its numDisparities leftmost columns invalid: 12 columns more than the D that
  the metric skips, and, in the mirrored run for the right map, the numDisparities
  rightmost columns of the right image, which npstereo's right map covers (with the
  disparities that stay inside the frame). Both images are therefore padded on the left
  with numDisparities replicated columns and the padding is cut from the result: every
  column gets a disparity, and OpenCV is not charged for a border convention of its own.
- OpenCV reports disparities in 1/16 pixel. They are rounded to the nearest integer (the
  precision of npstereo's maps and of the L/R check); on teddy rounding scores a little
  higher than the raw fractions (86.1 vs 86.0 % for MODE_SGBM), so it is the stricter bar.
- The right-referenced map for the L/R check: the matcher run on the mirrored pair
  (left' = flip(right), right' = flip(left)), its result flipped back. A pixel whose
  partner is invalid in the right map is rejected.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from npstereo.golden import sgm
from npstereo.golden.data import StereoPair, load_middlebury, read_image
from npstereo.golden.degrade import gaussian_noise_pair
from npstereo.golden.lr_check import INVALID, lr_check
from npstereo.golden.median import median3
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.quality import evaluate, mean_absolute_error
from npstereo.golden.subpixel import levels
from npstereo.golden.synthetic import synthetic_pair
from npstereo.params import SGM_RECOMMENDED, StereoParams, UserError

#: L/R threshold of the project's default configuration (docs/semantics.md).
LR_THRESHOLD = 3

#: npstereo box configurations: (transform, block, aggregation size).
BOX = [("census", 9, 3), ("census", 5, 3), ("census", 13, 3)]

#: npstereo SGM configurations: (transform, block, P1, P2, adaptive-P2 exponent, 3x3
#: median, sub-pixel bits F[, cost term]). The recommended ones first: the default
#: (docs/sgm.md, "Choosing the defaults") and the best census 5x5 on clean real scenes; then
#: the best census 5x5 with a constant P2; then the defaults with the 3x3 median (issue 28,
#: docs/sgm.md "Quality options"), and with the median at the penalties its study chose
#: (P1 = 16, t = 4); the README's recommendation (the defaults with the median) with F = 4
#: fractional bits (docs/sgm.md, "Sub-pixel output"); the median with the ad3 cost term at
#: its default P2; last the README's recommended SGM configuration, that with the fifth
#: path as well (docs/sgm.md, "Quality options").
_DEFAULTS = tuple(SGM_RECOMMENDED[0][name]
                  for name in ("transform", "block", "p1", "p2", "p2_adapt"))
SUBPIXEL_BITS = 4
SGM = [tuple(fields[name] for name in ("transform", "block", "p1", "p2", "p2_adapt"))
       + (False, 0) for fields in SGM_RECOMMENDED] + [("census", 5, 12, 32, None, False, 0)] + [
    _DEFAULTS + (True, 0), ("census", 7, 16, 79, 4, True, 0), _DEFAULTS + (True, SUBPIXEL_BITS),
    ("census", 7, 24, 72, 5, True, 0, "ad3"), ("census", 7, 24, 72, 5, True, 0, "ad3", True)]

#: OpenCV SGBM block size and penalties as the issue prescribes (OpenCV's documented rule
#: of thumb P1 = 8 * channels * bs^2, P2 = 32 * channels * bs^2 for one gray channel).
SGBM_BLOCK = 5
BM_BLOCK = 9


def opencv_matchers(cv2, num_disparities):
    """(name, matcher) of every peer."""
    peers = []
    for name, mode in (("OpenCV StereoSGBM MODE_SGBM", cv2.STEREO_SGBM_MODE_SGBM),
                       ("OpenCV StereoSGBM MODE_HH", cv2.STEREO_SGBM_MODE_HH)):
        peers.append((name, cv2.StereoSGBM_create(
            minDisparity=0, numDisparities=num_disparities, blockSize=SGBM_BLOCK,
            P1=8 * SGBM_BLOCK ** 2, P2=32 * SGBM_BLOCK ** 2, disp12MaxDiff=-1,
            uniquenessRatio=0, speckleWindowSize=0, speckleRange=0, mode=mode)))
    bm = cv2.StereoBM_create(numDisparities=num_disparities, blockSize=BM_BLOCK)
    bm.setUniquenessRatio(0)
    peers.append((f"OpenCV StereoBM {BM_BLOCK}x{BM_BLOCK}", bm))
    return peers


def opencv_map(cv2, matcher, left, right, disparities, num_disparities, fraction=False):
    """Integer left-referenced map of an OpenCV matcher, INVALID outside 0 .. D - 1; with
    ``fraction`` the same map in OpenCV's 1/16 levels (float32, -1 invalid)."""
    # OpenCV leaves its numDisparities leftmost columns invalid; padding by as many
    # replicated columns gives every column of the image a result.
    pad = num_disparities
    padded = [cv2.copyMakeBorder(image, 0, 0, pad, 0, cv2.BORDER_REPLICATE)
              for image in (left, right)]
    raw = matcher.compute(*padded)[:, pad:].astype(np.int32)
    # Fixed point with 4 fractional bits; round half up to the nearest integer.
    rounded = (raw + 8) >> 4
    invalid = (raw < 0) | (rounded > disparities - 1)
    if fraction:
        return np.where(invalid, INVALID, raw / np.float32(16)).astype(np.float32)
    return np.where(invalid, INVALID, rounded).astype(np.int16)


def mirror(image):
    """The image flipped left to right (contiguous, as OpenCV wants it)."""
    return np.ascontiguousarray(image[:, ::-1])


def opencv_maps(cv2, matcher, left, right, disparities, num_disparities):
    """(map without check, map after the project's L/R check) of one OpenCV matcher."""
    left_map = opencv_map(cv2, matcher, left, right, disparities, num_disparities)
    # In the mirrored pair the right view is the reference and disparities stay positive:
    # right pixel xr becomes column W-1-xr of the new left image, its partner xr + d
    # column W-1-xr-d of the new right image.
    right_map = mirror(opencv_map(cv2, matcher, mirror(right), mirror(left), disparities,
                                  num_disparities))
    # lr_check compares |dL - dR|; an invalid right pixel must never pass, so it gets a
    # value no disparity is within the threshold of.
    right_map = np.where(right_map < 0, -10 * disparities, right_map)
    checked = lr_check(np.where(left_map < 0, 0, left_map), right_map, LR_THRESHOLD)
    checked = np.where(left_map < 0, INVALID, checked).astype(np.int16)
    return left_map, checked


def opencv_fraction_maps(cv2, matcher, left, right, disparities, num_disparities):
    """:func:`opencv_maps` with OpenCV's 1/16 fractions kept where the (whole-level) check
    keeps a pixel: the peer of npstereo's sub-pixel output."""
    maps = opencv_maps(cv2, matcher, left, right, disparities, num_disparities)
    fine = opencv_map(cv2, matcher, left, right, disparities, num_disparities, fraction=True)
    return tuple(np.where(whole >= 0, fine, np.float32(INVALID)) for whole in maps)


def score(disparity, truth, disparities):
    quality = evaluate(disparity, truth, disparities)
    return dict(correct=quality.correct, density=quality.density,
                error_rate=quality.error_rate,
                mean_error=mean_absolute_error(disparity, truth, disparities))


def sgm_maps(left, right, transform, block, disparities, p1, p2, adapt, median, bits,
             cost_term=None, fifth_path=False):
    """(map without check, map after the L/R check) of an npstereo SGM configuration, in
    levels (with F > 0 float32 with the fraction). The unchecked map with F > 0 is the
    fitted map of a run without the check (the checked run's raw maps are whole levels)."""
    term = dict(aggregation="sgm", cost_term=cost_term, fifth_path=fifth_path) \
        if cost_term or fifth_path else {}
    params = StereoParams(transform=transform, block=block, disparities=disparities,
                          lr_threshold=LR_THRESHOLD, subpixel_bits=bits, **term)
    result = sgm.disparity_map(left, right, params, p1, p2, adapt=adapt)
    unchecked = result.left.copy()
    if bits:
        unchecked = sgm.disparity_map(left, right, params.replace(lr_threshold=None), p1, p2,
                                      adapt=adapt).disparity.copy()
    unchecked[:, :disparities] = INVALID
    maps = (unchecked, result.disparity)
    if median:
        # As in hardware: the median of the output values (scaled by 2^F).
        maps = tuple(median3(disparity) for disparity in maps)
    return tuple(levels(disparity, bits) for disparity in maps)


def load(args):
    """(pair, left gray, right gray, ground truth, D) as the arguments ask."""
    if args.synthetic:
        disparities = args.disparities or 48
        pair = synthetic_pair(256, 192, disparities, seed=args.seed)
    else:
        disparities = args.disparities or 100
        pair = load_middlebury(args.dataset)
    StereoParams(disparities=disparities)
    if pair.ground_truth is None:
        raise UserError(f"{args.dataset} has no ground truth")
    left, right = pair.gray()
    truth, name = pair.ground_truth, pair.name
    if args.mirrored:
        if args.synthetic or not (args.dataset / "disp6.pgm").is_file():
            raise UserError("--mirrored needs a Middlebury 2003 folder with disp6.pgm")
        # The right view is the reference of the mirrored pair; its ground truth is stored
        # like disp2.pgm (4 x disparity, 0 unknown).
        right_truth = read_image(args.dataset / "disp6.pgm", "ground truth").astype(float)
        truth = np.where(right_truth == 0, np.nan, right_truth / 4)[:, ::-1]
        left, right = mirror(right), mirror(left)
        name += " mirrored"
    if args.noise:
        left, right = gaussian_noise_pair(left, right, args.noise, args.seed)
        name += f" noise {args.noise:g}"
    return (StereoPair(name, left, right, np.ascontiguousarray(truth)), left, right,
            np.ascontiguousarray(truth), disparities)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", type=Path, help="Middlebury scene folder (e.g. teddy)")
    source.add_argument("--synthetic", action="store_true",
                        help="the project's synthetic scene (256 x 192) instead")
    parser.add_argument("--disparities", type=int, default=None,
                        help="D (default 100, synthetic 48)")
    parser.add_argument("--noise", type=float, default=0.0,
                        help="gaussian noise variance on the [0, 1] scale (default none)")
    parser.add_argument("--seed", type=int, default=0, help="synthetic scene and noise seed")
    parser.add_argument("--mirrored", action="store_true",
                        help="the right view as the reference (Middlebury 2003: disp6.pgm)")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = parser.parse_args(argv)
    try:
        import cv2
    except ImportError:
        print("bench_quality: OpenCV is missing; install the bench extra "
              "(pip install -e '.[bench]')", file=sys.stderr)
        return 2
    try:
        pair, left, right, truth, disparities = load(args)
    except UserError as error:
        print(f"bench_quality: {error}", file=sys.stderr)
        return 2
    num_disparities = -(-disparities // 16) * 16
    print(f"quality on {pair.name} ({left.shape[1]}x{left.shape[0]}), D = {disparities}, "
          f"metric of golden/quality.py, L/R threshold {LR_THRESHOLD}; OpenCV "
          f"{cv2.__version__} with numDisparities {num_disparities}; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    rows = []

    def add(family, name, maps, seconds):
        for check, disparity in zip(("no", "yes"), maps):
            rows.append(dict(family=family, method=name, lr_check=check, seconds=seconds,
                             **score(disparity, truth, disparities)))

    for transform, block, aggregation in BOX:
        start = time.perf_counter()
        params = StereoParams(transform=transform, block=block, disparities=disparities,
                              aggregation=aggregation, lr_threshold=LR_THRESHOLD)
        result = disparity_map(left, right, params)
        unchecked = result.left.copy()
        unchecked[:, :params.first_valid_column] = INVALID
        add("npstereo box", f"npstereo {transform} {block}x{block}, {aggregation}x{aggregation}"
            f" box", (unchecked, result.disparity), time.perf_counter() - start)
    for transform, block, p1, p2, adapt, median, bits, *extra in SGM:
        start = time.perf_counter()
        maps = sgm_maps(left, right, transform, block, disparities, p1, p2, adapt, median,
                        bits, *extra)
        term, fifth = (extra + [None, False])[:2]
        p2_text = f"P2={p2}" + (f" adaptive t={adapt}" if adapt is not None else "")
        add("npstereo SGM", f"npstereo {transform} {block}x{block}, SGM {5 if fifth else 4} "
            f"paths P1={p1} {p2_text}" + (f", + {term}" if term else "")
            + (", 3x3 median" if median else "")
            + (f", sub-pixel F={bits}" if bits else ""), maps, time.perf_counter() - start)
    for name, matcher in opencv_matchers(cv2, num_disparities):
        start = time.perf_counter()
        maps = opencv_maps(cv2, matcher, left, right, disparities, num_disparities)
        add("peer", name, maps, time.perf_counter() - start)
        if "SGBM" in name:
            # Beside npstereo's fraction, OpenCV's own (not a peer of the bar: rounded,
            # above, is the stricter one).
            start = time.perf_counter()
            maps = opencv_fraction_maps(cv2, matcher, left, right, disparities,
                                        num_disparities)
            add("peer fraction", f"{name}, 1/16 fraction", maps, time.perf_counter() - start)

    print("\n| method | L/R check | correct (%) | density (%) | error rate (%) | "
          "mean abs. error of correct (levels) | seconds |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for row in rows:
        print(f"| {row['method']} | {row['lr_check']} | {row['correct']:.2f} | "
              f"{row['density']:.2f} | {row['error_rate']:.2f} | {row['mean_error']:.3f} | "
              f"{row['seconds']:.1f} |")
    best = {family: max((r for r in rows if r["family"] == family), key=lambda r: r["correct"])
            for family in ("npstereo box", "npstereo SGM", "peer")}
    best_sgm_checked = max((r for r in rows if r["family"] == "npstereo SGM"
                            and r["lr_check"] == "yes"), key=lambda r: r["correct"])
    peer = best["peer"]
    print(f"\nbest peer: {peer['method']} (L/R check {peer['lr_check']}) "
          f"{peer['correct']:.2f} %")
    default = [r for r in rows if r["family"] == "npstereo SGM"][:2]  # SGM[0], both checks
    for label, row in (("default npstereo SGM without the L/R check", default[0]),
                       ("default npstereo SGM with the L/R check", default[1]),
                       ("best npstereo SGM", best["npstereo SGM"]),
                       ("best npstereo SGM with the L/R check", best_sgm_checked),
                       ("best npstereo box", best["npstereo box"])):
        ratio = row["correct"] / peer["correct"]
        print(f"{label}: {row['method']} (L/R check {row['lr_check']}) {row['correct']:.2f} %,"
              f" ratio ours / best peer {ratio:.4f} ({'>=' if ratio >= 1 else '<'} 1)")
    if args.json:
        args.json.write_text(json.dumps(dict(scene=pair.name, disparities=disparities,
                                             rows=rows), indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
