"""``npstereo eval``: the paper's quality metric for one or many configurations."""

import json

from ...golden.data import load_middlebury
from ...golden.quality import evaluate, mean_absolute_error
from ...golden.synthetic import synthetic_pair
from ...params import UserError
from ..atomic import write_text
from ..matching import Condition, condition_images, run_jobs
from ..reports.paper_data import PAPER_NOISE
from .arguments import add_matching_arguments, aggregations_from_args, check_output_file, \
    params_from_args

__all__ = ["DESCRIPTION", "add_arguments", "run", "format_table", "add_condition_arguments"]

DESCRIPTION = ("Evaluate the golden model on a Middlebury scene (2003, 2005/2006 or 2014 "
               "layout) or the embedded synthetic scene: correct matches (|d - gt| <= 1 over "
               "known pixels with x >= D, invalid counts as wrong), density and error rate "
               "among valid pixels.")


def format_table(rows):
    """Markdown table of result dicts (condition, transform, block, metrics)."""
    lines = ["| condition | transform | block | aggregation | correct (%) | density (%) "
             "| error rate (%) | time (s) |",
             "|---|---|---|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['condition']} | {r['transform']} | {r['block']}x{r['block']} | "
                     f"{r['aggregation_label']} | {r['correct']:.2f} | {r['density']:.2f} | "
                     f"{r['error_rate']:.2f} | {r['seconds']:.2f} |")
    return "\n".join(lines)


def load_pair(args):
    if args.synthetic:
        return synthetic_pair(disparities=args.disparities, seed=args.seed)
    return load_middlebury(args.dataset)


def run(args):
    params = [params_from_args(args, t, b, a) for t in args.transform for b in args.block
              for a in aggregations_from_args(args, many=True)]
    if args.json is not None:
        check_output_file(args.json, "--json", ".json")
    if (args.bayer_gains is not None or args.read_noise) and not args.bayer:
        raise UserError("--bayer-gains and --read-noise need --bayer")
    condition = Condition(noise=args.noise, bayer=args.bayer,
                          gains=tuple(args.bayer_gains or (1.0, 1.0, 1.0)),
                          read_noise=args.read_noise, seed=args.seed)
    pair = load_pair(args)
    if pair.ground_truth is None:
        raise UserError(f"dataset {pair.name} has no ground truth to evaluate against")
    left, right = condition_images(pair, condition)
    for p in params:
        p.with_size(left.shape[1], left.shape[0])
    jobs = {p: (left, right, p) for p in params}
    results = run_jobs(jobs, args.jobs, desc=f"eval {pair.name}")
    rows = []
    for p in params:
        disparity, seconds = results[p]
        quality = evaluate(disparity, pair.ground_truth, p.disparities)
        rows.append({"dataset": pair.name, "condition": condition.label,
                     "transform": p.transform, "block": p.block, "disparities": p.disparities,
                     "rounds": p.rounds, "aggregation": p.aggregation, "p1": p.p1, "p2": p.p2,
                     "p2_adapt": p.p2_adapt, "median": p.median, "cost_term": p.cost_term,
                     "fifth_path": p.fifth_path,
                     "aggregation_label": p.describe_aggregation()
                     + (f", + {p.cost_term}" if p.cost_term else "")
                     + (", 3x3 median" if p.median else ""),
                     "lr_threshold": p.lr_threshold, **quality.as_dict(),
                     "subpixel_bits": p.subpixel_bits,
                     "mean_abs_error": mean_absolute_error(disparity, pair.ground_truth,
                                                           p.disparities),
                     "seconds": seconds})
    print(f"{pair.name} ({left.shape[1]}x{left.shape[0]}), D={args.disparities}, "
          f"{condition.label}")
    print(format_table(rows))
    if args.json is not None:
        write_text(args.json, json.dumps(rows, indent=1) + "\n")


def add_condition_arguments(parser):
    parser.add_argument("--noise", type=float, default=0.0, metavar="VAR",
                        help="add gaussian noise of this variance on the [0,1] scale "
                             f"(the paper: {PAPER_NOISE:g})")
    parser.add_argument("--bayer", action="store_true",
                        help="bayer stand-in: raw RGGB mosaic of the colour pair as gray image")
    parser.add_argument("--bayer-gains", type=float, nargs=3, metavar=("R", "G", "B"),
                        help="per-channel gains of the mosaic (uncorrected sensor)")
    parser.add_argument("--read-noise", type=float, default=0.0, metavar="SIGMA",
                        help="gaussian read noise of the mosaic in 8-bit levels")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random degradation")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")


def add_arguments(parser):
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", metavar="DIR", help="Middlebury scene folder")
    source.add_argument("--synthetic", action="store_true",
                        help="the embedded synthetic scene (seeded by --seed)")
    add_matching_arguments(parser, many=True, subpixel=True)
    add_condition_arguments(parser)
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    parser.set_defaults(run=run)
