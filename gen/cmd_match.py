"""``npstereo match``: the golden model's disparity map of one stereo pair.

Also home of the stereo-parameter options shared by ``eval``, ``paper`` and ``demo``.
"""

import argparse
import contextlib
import os
from pathlib import Path

import numpy as np

from ..golden.data import read_image, to_gray
from ..golden.pipeline import disparity_map
from ..params import (LINE_BUFFERS, LUT_INPUTS, P2_ADAPT_OFF, SGM, SGM_DEFAULT_ADAPT,
                      SGM_DEFAULT_P1, SGM_DEFAULT_P2, SGM_MAX_ADAPT, TRANSFORMS, StereoParams,
                      UserError)
from .atomic import atomic_path
from .images import save_disparity_png

__all__ = ["add_parser", "run", "add_matching_arguments", "add_hardware_arguments",
           "aggregation_value", "aggregations_from_args", "params_from_args", "match_images",
           "save_raw", "output_errors", "check_output_folder"]


#: The aggregation when ``--aggregation`` is not given: the paper's 3 x 3 box.
DEFAULT_AGGREGATION = 3


def aggregation_value(text):
    """Type of ``--aggregation``: ``sgm`` or a window size (StereoParams checks the size)."""
    if text == SGM:
        return SGM
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be an odd window size or {SGM}, not {text!r}") from None


def add_matching_arguments(parser, many=False, max_block=None, max_disparities=None,
                           positionals=False):
    """Options of the matching pipeline; with ``many``, transform, block and aggregation
    take lists (a grid of configurations).

    ``--aggregation`` is always collected as a list (``None`` when not given), so that a
    command of one configuration names a second value in its error
    (:func:`aggregations_from_args`) instead of silently keeping the last. It takes several
    values per occurrence, except for a command with ``positionals`` (``match``), whose
    image arguments it would swallow: there each ``--aggregation`` takes one.

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
    parser.add_argument("--aggregation", type=aggregation_value, metavar="A|sgm",
                        nargs=None if positionals else "+",
                        action="append" if positionals else "extend",
                        help="cost aggregation: an A x A box, A odd >= 1, or sgm "
                             "(semi-global, four paths)" + (" (one or more)" if many else "")
                             + f" (default {DEFAULT_AGGREGATION})")
    lr = parser.add_mutually_exclusive_group()
    lr.add_argument("--lr-threshold", type=int, default=3,
                    help="left/right consistency threshold T >= 0 (default 3)")
    lr.add_argument("--no-lr-check", action="store_true", help="skip the left/right check")
    sgm = parser.add_argument_group("semi-global aggregation (only with --aggregation sgm)")
    sgm.add_argument("--p1", type=int, metavar="N",
                     help=f"penalty of a disparity step of 1 along a path, 0 <= P1 <= P2 "
                          f"(default {SGM_DEFAULT_P1})")
    sgm.add_argument("--p2", type=int, metavar="N",
                     help="penalty of a larger step, P1 <= P2 <= 2^(bitlen(Cmax) + 2) - 1 - "
                          "Cmax for the transform's largest cost Cmax (census 7x7: 207) "
                          f"(default {SGM_DEFAULT_P2})")
    adapt = sgm.add_mutually_exclusive_group()
    adapt.add_argument("--p2-adapt", type=int, metavar="T",
                       help=f"adaptive P2: halved for every doubling of the intensity step "
                            f"along the path from 2^T on, 1 <= T <= {SGM_MAX_ADAPT} "
                            f"(default {SGM_DEFAULT_ADAPT})")
    adapt.add_argument("--no-p2-adapt", action="store_true", help="a constant P2")


def add_hardware_arguments(parser):
    """Options of the generated hardware that change its resources, never its results."""
    parser.add_argument("--line-buffer", choices=LINE_BUFFERS, default="auto",
                        help="what the core keeps of the rows above for the vertical "
                             "aggregation: their pixels or their transformed pixels (the "
                             "costs are computed again), or their costs; auto: pixels for "
                             "census, costs for ext-census, else transforms (default auto)")
    parser.add_argument("--lut-inputs", type=int, choices=LUT_INPUTS, default=4,
                        help="inputs of the target fabric's LUTs, which the sums of absolute "
                             "differences (ext-census cost, ext-rank transform) are arranged "
                             "for: 4 for ECP5, iCE40, Gowin; 6 for Intel (ALMs) and "
                             "AMD/Xilinx (default 4)")


def _sgm_options(args):
    """The SGM options given on the command line, as the user spelled them."""
    given = [name for name, value in (("--p1", args.p1), ("--p2", args.p2),
                                      ("--p2-adapt", args.p2_adapt)) if value is not None]
    return given + (["--no-p2-adapt"] if args.no_p2_adapt else [])


def aggregations_from_args(args, many=False):
    """The ``--aggregation`` values after the checks only the command line can make.

    A command of one configuration (``many`` false) takes one value; the SGM options need
    ``sgm`` among the values. Raises :class:`UserError` (one line) otherwise.
    """
    values = args.aggregation or [DEFAULT_AGGREGATION]
    if not many and len(values) > 1:
        if SGM in values and len(set(values)) > 1:
            windows = " ".join(str(v) for v in values if v != SGM)
            raise UserError(f"--aggregation sgm replaces the aggregation window: give sgm or "
                            f"a window size, not both (sgm and {windows})")
        raise UserError(f"--aggregation takes one value for one configuration, not "
                        f"{' '.join(str(v) for v in values)}")
    given = _sgm_options(args)
    if given and SGM not in values:
        verb = "is an SGM option: it needs" if len(given) == 1 else \
            "are SGM options: they need"
        raise UserError(f"{' and '.join(given)} {verb} --aggregation sgm")
    return values


def params_from_args(args, transform=None, block=None, aggregation=None):
    """The validated StereoParams of the parsed options (one transform, block and
    aggregation; without ``aggregation`` the command line's only one)."""
    if aggregation is None:
        (aggregation,) = aggregations_from_args(args)
    sgm = aggregation == SGM
    adapt = P2_ADAPT_OFF if args.no_p2_adapt else args.p2_adapt
    return StereoParams(
        transform=args.transform if transform is None else transform,
        block=args.block if block is None else block,
        disparities=args.disparities, rounds=args.rounds, aggregation=aggregation,
        lr_threshold=None if args.no_lr_check else args.lr_threshold,
        line_buffer=getattr(args, "line_buffer", "auto"),
        lut_inputs=getattr(args, "lut_inputs", 4),
        p1=args.p1 if sgm else None, p2=args.p2 if sgm else None,
        p2_adapt=adapt if sgm else None)


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
    add_matching_arguments(parser, positionals=True)
    parser.add_argument("--out", required=True,
                        help="colour-mapped disparity PNG (invalid pixels black)")
    parser.add_argument("--raw", help="also write the H x W int16 map (-1 invalid) as .npy")
    parser.set_defaults(run=run)
