"""``npstereo match``: the golden model's disparity map of one stereo pair.

Also home of the stereo-parameter options shared by ``eval``, ``paper`` and ``demo``.
"""

import contextlib
import os
from pathlib import Path

import numpy as np

from ..golden.data import read_image, to_gray
from ..golden.pipeline import disparity_map
from ..params import LINE_BUFFERS, TRANSFORMS, StereoParams, UserError
from .atomic import atomic_path
from .images import save_disparity_png

__all__ = ["add_parser", "run", "add_matching_arguments", "add_hardware_arguments",
           "params_from_args", "match_images",
           "save_raw", "output_errors", "check_output_folder"]


def add_matching_arguments(parser, many=False, max_block=None, max_disparities=None):
    """Options of the matching pipeline; with ``many``, transform and block take lists.

    ``max_block``, ``max_disparities``: the limits of a command that generates hardware
    (:mod:`npstereo.hdl.plan`), named in the help; the golden model has none.
    """
    count = "+" if many else None
    parser.add_argument("--transform", nargs=count, choices=TRANSFORMS,
                        default=["census"] if many else "census",
                        help="non-parametric transform (default census)")
    parser.add_argument("--block", nargs=count, type=int, default=[9] if many else 9,
                        help="transform window size B, odd >= 3"
                             + (f", at most {max_block}" if max_block else "") + " (default 9)")
    parser.add_argument("--disparities", type=int, default=100,
                        help="disparity range D >= 2"
                             + (f", at most {max_disparities}" if max_disparities else "")
                             + " (default 100, as in the paper)")
    parser.add_argument("--rounds", type=int, default=1,
                        help="calculation rounds R, must divide D (default 1)")
    parser.add_argument("--aggregation", type=int, default=3,
                        help="cost aggregation window A, odd >= 1 (default 3)")
    lr = parser.add_mutually_exclusive_group()
    lr.add_argument("--lr-threshold", type=int, default=3,
                    help="left/right consistency threshold T >= 0 (default 3)")
    lr.add_argument("--no-lr-check", action="store_true", help="skip the left/right check")


def add_hardware_arguments(parser):
    """Options of the generated hardware that change its resources, never its results."""
    parser.add_argument("--line-buffer", choices=LINE_BUFFERS, default="auto",
                        help="what the core keeps of the rows above for the vertical "
                             "aggregation: their transformed pixels (the costs are computed "
                             "again) or their costs; auto: costs for ext-census, else "
                             "transforms (default auto)")


def params_from_args(args, transform=None, block=None):
    """The validated StereoParams of the parsed options (one transform and block)."""
    return StereoParams(
        transform=args.transform if transform is None else transform,
        block=args.block if block is None else block,
        disparities=args.disparities, rounds=args.rounds, aggregation=args.aggregation,
        lr_threshold=None if args.no_lr_check else args.lr_threshold,
        line_buffer=getattr(args, "line_buffer", "auto"))


def match_images(left, right, params, threads=None):
    """Disparity map (int16, -1 invalid) of two 8-bit images, colour converted to gray.

    Raises a UserError for images of different size or narrower than the disparity range
    (the golden model checks both).
    """
    return disparity_map(to_gray(left), to_gray(right), params, threads=threads).disparity


def save_raw(path, disparity):
    """Write the int16 map (-1 invalid) as a .npy file, atomically."""
    with atomic_path(path, suffix=".npy") as tmp, open(tmp, "wb") as handle:
        np.save(handle, np.asarray(disparity, dtype=np.int16))


@contextlib.contextmanager
def output_errors():
    """Report a failed write (read-only folder, a file where a folder should be) as a
    one-line UserError instead of a traceback."""
    try:
        yield
    except OSError as error:
        target = error.filename or "the output"
        raise UserError(f"cannot write {target}: {error.strerror or error}") from None


def check_output_folder(value, option="--out"):
    """Fail before any work when the folder ``value`` cannot be created or written."""
    path = Path(value)
    if path.exists() and not path.is_dir():
        raise UserError(f"{option} {value} exists and is not a folder")
    existing = next(p for p in (path, *path.parents) if p.exists())
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        raise UserError(f"{option} {value} cannot be created: {existing} is not a writable "
                        "folder")
    return path


def _output_path(value, suffix, option):
    path = Path(value)
    if path.suffix.lower() != suffix:
        raise UserError(f"{option} must name a {suffix} file, not {value}")
    if path.is_dir():
        raise UserError(f"{option} {value} is a directory")
    check_output_folder(path.parent, option)
    return path


def run(args):
    out = _output_path(args.out, ".png", "--out")
    raw = None if args.raw is None else _output_path(args.raw, ".npy", "--raw")
    params = params_from_args(args)
    left = read_image(args.left, "left image")
    right = read_image(args.right, "right image")
    disparity = match_images(left, right, params)
    with output_errors():
        save_disparity_png(out, disparity, params.disparities - 1)
        if raw is not None:
            save_raw(raw, disparity)
    valid = disparity >= 0
    print(f"{params.describe()}: {left.shape[1]}x{left.shape[0]}, "
          f"{100.0 * valid.mean():.1f}% valid -> {out}" + (f", {raw}" if raw else ""))


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "match", help="disparity map of one stereo pair (golden model)",
        description="Compute the left-referenced disparity map of a rectified stereo pair with "
                    "the bit-exact golden model. Colour images are converted to gray (BT.601).")
    parser.add_argument("left", help="left (reference) image, 8-bit gray or RGB")
    parser.add_argument("right", help="right image, same size")
    add_matching_arguments(parser)
    parser.add_argument("--out", required=True,
                        help="colour-mapped disparity PNG (invalid pixels black)")
    parser.add_argument("--raw", help="also write the H x W int16 map (-1 invalid) as .npy")
    parser.set_defaults(run=run)
