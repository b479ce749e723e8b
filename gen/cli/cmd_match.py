"""``npstereo match``: the golden model's disparity map of one stereo pair."""

import numpy as np

from ...golden.data import read_image
from ..atomic import atomic_path
from ..images import save_disparity_png
from ..matching import match_images
from .arguments import add_matching_arguments, check_output_file, params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run", "save_raw"]

DESCRIPTION = ("Compute the left-referenced disparity map of a rectified stereo pair with the "
               "bit-exact golden model. Colour images are converted to gray (BT.601).")


def save_raw(path, disparity):
    """Write the map as a .npy file, atomically: int16 levels (-1 invalid), or with
    sub-pixel bits float32 levels (-1 invalid)."""
    disparity = np.asarray(disparity)
    dtype = np.int16 if np.issubdtype(disparity.dtype, np.integer) else np.float32
    with atomic_path(path, suffix=".npy") as tmp, open(tmp, "wb") as handle:
        np.save(handle, disparity.astype(dtype, copy=False))


def run(args):
    out = check_output_file(args.out, "--out", ".png")
    raw = None if args.raw is None else check_output_file(args.raw, "--raw", ".npy")
    params = params_from_args(args)
    left = read_image(args.left, "left image")
    right = read_image(args.right, "right image")
    disparity = match_images(left, right, params)
    save_disparity_png(out, disparity, params.disparities - 1)
    if raw is not None:
        save_raw(raw, disparity)
    valid = disparity >= 0
    print(f"{params.describe()}: {left.shape[1]}x{left.shape[0]}, "
          f"{100.0 * valid.mean():.1f}% valid -> {out}" + (f", {raw}" if raw else ""))


def add_arguments(parser):
    parser.add_argument("left", help="left (reference) image, 8-bit gray or RGB")
    parser.add_argument("right", help="right image, same size")
    add_matching_arguments(parser, positionals=True, subpixel=True)
    parser.add_argument("--out", required=True,
                        help="colour-mapped disparity PNG (invalid pixels black)")
    parser.add_argument("--raw", help="also write the H x W map as .npy: int16 levels, or "
                                      "float32 levels with --subpixel-bits > 0; -1 invalid")
    parser.set_defaults(run=run)
