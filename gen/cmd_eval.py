"""``npstereo eval``: the paper's quality metric for one or many configurations.

Also the machinery ``paper`` reuses: degraded input conditions and a process-parallel
runner with a progress bar.
"""

import json
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

from tqdm import tqdm

from ..golden.data import load_middlebury
from ..golden.degrade import bayer_pair, gaussian_noise_pair
from ..golden.quality import evaluate
from ..golden.synthetic import synthetic_pair
from ..params import UserError
from .atomic import write_text
from .cmd_match import (add_matching_arguments, aggregations_from_args, match_images,
                        output_errors, params_from_args)

__all__ = ["add_parser", "run", "Condition", "condition_images", "run_jobs", "format_table"]


@dataclass(frozen=True)
class Condition:
    """How the input images are prepared: clean gray, gaussian noise and/or bayer stand-in.

    The bayer stand-in replaces the gray conversion (raw mosaic values are the gray image);
    noise, when given too, is added afterwards.
    """

    noise: float = 0.0
    bayer: bool = False
    gains: tuple = (1.0, 1.0, 1.0)
    read_noise: float = 0.0
    seed: int = 0

    @property
    def label(self):
        parts = []
        if self.bayer:
            gains = "" if self.gains == (1.0, 1.0, 1.0) else " gains " + "/".join(
                f"{g:g}" for g in self.gains)
            noise = f" read noise {self.read_noise:g}" if self.read_noise else ""
            parts.append(f"bayer{gains}{noise}")
        if self.noise:
            parts.append(f"noise {self.noise:g}")
        return ", ".join(parts) or "clean"


def condition_images(pair, condition):
    """The gray left/right images of ``pair`` under ``condition``."""
    if condition.bayer:
        left, right = bayer_pair(pair.left, pair.right, condition.gains, condition.read_noise,
                                 condition.seed)
    else:
        left, right = pair.gray()
    if condition.noise:
        # Independent of the bayer read noise: a different stream of the same seed.
        left, right = gaussian_noise_pair(left, right, condition.noise, condition.seed + 1)
    return left, right


def _job(key, left, right, params, threads):
    start = time.perf_counter()
    disparity = match_images(left, right, params, threads=threads)
    return key, disparity, time.perf_counter() - start


def _cost(params):
    """Rough relative run time, to start the slowest jobs first.

    SGM's four paths cost about as much as a 15 x 15 census transform (teddy: 1.1 s for
    census 7x7 SGM against 0.4 s for the census 9x9 box).
    """
    weight = {"rank": 1, "ext-rank": 1, "census": 1, "ext-census": 4}[params.transform]
    return weight * params.block * params.block + (225 if params.is_sgm else 0)


def run_jobs(jobs, jobs_n=1, desc="matching"):
    """Run ``{key: (left, right, params)}``; returns ``{key: (disparity, seconds)}``.

    With ``jobs_n`` > 1 the jobs run in that many processes, each single-threaded (the
    machine's cores are shared between the processes rather than oversubscribed).
    """
    if jobs_n < 1:
        raise UserError(f"--jobs must be an integer >= 1, not {jobs_n}")
    order = sorted(jobs, key=lambda key: -_cost(jobs[key][2]))
    results = {}
    with tqdm(total=len(order), desc=desc, unit="map", leave=False) as progress:
        if jobs_n == 1:
            for key in order:
                _, disparity, seconds = _job(key, *jobs[key], None)
                results[key] = (disparity, seconds)
                progress.update()
        else:
            threads = max(1, (os.cpu_count() or 1) // jobs_n)
            with ProcessPoolExecutor(max_workers=jobs_n) as pool:
                futures = [pool.submit(_job, key, *jobs[key], threads) for key in order]
                for future in as_completed(futures):
                    key, disparity, seconds = future.result()
                    results[key] = (disparity, seconds)
                    progress.update()
    return results


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
    if args.json is not None and not args.json.endswith(".json"):
        raise UserError(f"--json must name a .json file, not {args.json}")
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
                     "p2_adapt": p.p2_adapt, "aggregation_label": p.describe_aggregation(),
                     "lr_threshold": p.lr_threshold, **quality.as_dict(), "seconds": seconds})
    print(f"{pair.name} ({left.shape[1]}x{left.shape[0]}), D={args.disparities}, "
          f"{condition.label}")
    print(format_table(rows))
    if args.json is not None:
        with output_errors():
            write_text(args.json, json.dumps(rows, indent=1) + "\n")


def add_condition_arguments(parser):
    parser.add_argument("--noise", type=float, default=0.0, metavar="VAR",
                        help="add gaussian noise of this variance on the [0,1] scale "
                             "(the paper: 0.002)")
    parser.add_argument("--bayer", action="store_true",
                        help="bayer stand-in: raw RGGB mosaic of the colour pair as gray image")
    parser.add_argument("--bayer-gains", type=float, nargs=3, metavar=("R", "G", "B"),
                        help="per-channel gains of the mosaic (uncorrected sensor)")
    parser.add_argument("--read-noise", type=float, default=0.0, metavar="SIGMA",
                        help="gaussian read noise of the mosaic in 8-bit levels")
    parser.add_argument("--seed", type=int, default=0, help="seed of every random degradation")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "eval", help="correct matches (%%) against ground truth for one or many configurations",
        description="Evaluate the golden model on a Middlebury scene (2003, 2005/2006 or 2014 "
                    "layout) or the embedded synthetic scene: correct matches (|d - gt| <= 1 "
                    "over known pixels with x >= D, invalid counts as wrong), density and "
                    "error rate among valid pixels.")
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", metavar="DIR", help="Middlebury scene folder")
    source.add_argument("--synthetic", action="store_true",
                        help="the embedded synthetic scene (seeded by --seed)")
    add_matching_arguments(parser, many=True)
    add_condition_arguments(parser)
    parser.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    parser.set_defaults(run=run)
