"""``npstereo paper``: regenerate the paper's quality results (Figs. 6, 8, 10-11, 12).

Runs every transform at every block size on the clean scene (Fig. 6), with gaussian noise
of variance 0.002 (Fig. 8) and with the bayer stand-in in place of the paper's bayer-camera
scenes (Figs. 10-11), and writes a markdown report with the paper's teddy numbers side by
side, PNG plots, Fig. 12-style disparity images and all numbers as JSON. Beyond the paper,
the recommended semi-global configurations (``params.SGM_RECOMMENDED``) are measured under
the same conditions and shown beside each figure's table and in the Fig. 12 grid.
"""

import json
from pathlib import Path

import numpy as np

from ...golden.data import load_middlebury
from ...golden.quality import evaluate
from ...golden.synthetic import synthetic_pair
from ...params import SGM, SGM_RECOMMENDED, TRANSFORMS, StereoParams, UserError
from ..atomic import write_text
from ..images import save_disparity_png
from ..matching import Condition, condition_images, run_jobs
from ..reports.paper_data import PAPER_BLOCKS, PAPER_DISPARITIES, PAPER_FIG6, PAPER_FIG8, \
    PAPER_NOISE
from ..reports.plots import disparity_grid, plot_series
from .arguments import check_output_folder

__all__ = ["DESCRIPTION", "add_arguments", "run", "paper_sweep", "sgm_configurations"]

DESCRIPTION = ("Sweep all four transforms over the paper's block sizes on a Middlebury scene, "
               "clean, with gaussian noise and with the bayer stand-in; write README.md, PNG "
               "plots and results.json to --out.")

#: Bayer stand-in of an uncorrected sensor: unbalanced channel gains, as a camera without
#: white balance delivers them, and read noise in 8-bit levels. The plain mosaic runs too.
BAYER_GAINS = (0.6, 1.0, 0.75)
BAYER_READ_NOISE = 2.0


#: Row labels of the Fig. 12-style grid, in the order of the conditions.
ROW_NAMES = ("clean", "noise", "bayer", "bayer, uncorrected")


def max_shown_disparity(truth, disparities):
    """Top of the colour scale: the ground truth's maximum, so the colours use their range."""
    known = truth[~np.isnan(truth)]
    return int(np.ceil(known.max())) if known.size else disparities - 1


def _mad(measured, reference):
    pairs = [(m, r) for m, r in zip(measured, reference) if r is not None]
    return float(np.mean([abs(m - r) for m, r in pairs])) if pairs else None


def sgm_configurations(disparities):
    """The semi-global configurations measured beside the paper's box: the defaults
    (census 7x7) and census 5x5 with its own penalties (``params.SGM_RECOMMENDED``)."""
    return [StereoParams(**fields, disparities=disparities) for fields in SGM_RECOMMENDED]


def _sgm_label(params, semi_global):
    """``census 7x7, SGM P1=24 P2=79 t=5 (default)``: the row name of an SGM configuration."""
    default = " (default)" if params == semi_global[0] else ""
    return (f"{params.transform} {params.block}x{params.block}, "
            f"{params.describe_aggregation()}{default}")


def paper_sweep(pair, conditions, blocks, disparities, jobs_n):
    """Correct matches of every transform x block x condition, and of every SGM
    configuration (:func:`sgm_configurations`) x condition.

    Returns ``(rows, maps, sgm_rows)``: one result dict per box run, the disparity maps of
    the largest block size per (condition label, transform) and of the SGM default per
    (condition label, "sgm"), for the Fig. 12-style images, and one result dict per SGM
    run (with its parameters and ``describe()``).
    """
    images = {c.label: condition_images(pair, c) for c in conditions}
    semi_global = sgm_configurations(disparities)
    jobs = {}
    for c in conditions:
        for t in TRANSFORMS:
            for b in blocks:
                jobs[(c.label, t, b)] = (*images[c.label], StereoParams(t, b, disparities))
        for params in semi_global:
            jobs[(c.label, SGM, params)] = (*images[c.label], params)
    results = run_jobs(jobs, jobs_n, desc=f"paper {pair.name}")
    rows, maps, sgm_rows = [], {}, []
    for (label, t, b), (disparity, seconds) in results.items():
        quality = evaluate(disparity, pair.ground_truth, disparities)
        if t == SGM:  # b is then the configuration
            sgm_rows.append({"condition": label, "configuration": _sgm_label(b, semi_global),
                             "transform": b.transform, "block": b.block, "p1": b.p1,
                             "p2": b.p2, "p2_adapt": b.p2_adapt, **quality.as_dict(),
                             "seconds": seconds})
            if b == semi_global[0]:
                maps[(label, SGM)] = disparity
            continue
        rows.append({"condition": label, "transform": t, "block": b,
                     **quality.as_dict(), "seconds": seconds})
        if b == max(blocks):
            maps[(label, t)] = disparity
    order = {c.label: i for i, c in enumerate(conditions)}
    rows.sort(key=lambda r: (order[r["condition"]], TRANSFORMS.index(r["transform"]), r["block"]))
    configurations = [_sgm_label(p, semi_global) for p in semi_global]
    sgm_rows.sort(key=lambda r: (order[r["condition"]],
                                 configurations.index(r["configuration"])))
    return rows, maps, sgm_rows


def _series(rows, label, metric="correct"):
    out = {}
    for t in TRANSFORMS:
        out[t] = [r[metric] for r in rows if r["condition"] == label and r["transform"] == t]
    return out


def _comparison(title, measured, reference, blocks):
    """Markdown table: measured vs paper per transform and block, with mean |difference|."""
    head = "| transform | " + " | ".join(f"{b}x{b}" for b in blocks) + " | mean abs. diff. |"
    lines = [f"### {title}", "", "Each cell: npstereo / paper.", "", head,
             "|---|" + "---:|" * (len(blocks) + 1)]
    mads, all_pairs = {}, []
    for t in TRANSFORMS:
        ref = reference[t] if reference else (None,) * len(blocks)
        cells = [f"{m:.2f} / {'?' if r is None else f'{r:.2f}'}"
                 for m, r in zip(measured[t], ref)]
        mads[t] = _mad(measured[t], ref)
        all_pairs += [abs(m - r) for m, r in zip(measured[t], ref) if r is not None]
        lines.append(f"| {t} | " + " | ".join(cells) + " | "
                     + ("-" if mads[t] is None else f"{mads[t]:.2f}") + " |")
    mads["overall"] = float(np.mean(all_pairs)) if all_pairs else None
    if mads["overall"] is not None:
        lines += ["", f"Mean absolute difference over all transforms: **{mads['overall']:.2f}** "
                      "points."]
    return "\n".join(lines), mads


def _sgm_table(sgm_rows, label):
    """Markdown rows of the SGM configurations under the condition ``label``."""
    lines = ["Beyond the paper, semi-global aggregation under the same condition (one "
             "transform size each):", "",
             "| configuration | correct (%) | density (%) | error rate (%) |",
             "|---|---:|---:|---:|"]
    lines += [f"| {r['configuration']} | {r['correct']:.2f} | {r['density']:.2f} | "
              f"{r['error_rate']:.2f} |" for r in sgm_rows if r["condition"] == label]
    return "\n".join(lines)


def _measured_table(title, measured, blocks):
    lines = [f"### {title}", "", "| transform | " + " | ".join(f"{b}x{b}" for b in blocks) + " |",
             "|---|" + "---:|" * len(blocks)]
    for t in TRANSFORMS:
        lines.append(f"| {t} | " + " | ".join(f"{v:.2f}" for v in measured[t]) + " |")
    return "\n".join(lines)


def run(args):
    blocks = tuple(args.blocks)
    if not args.noise > 0:
        raise UserError(f"--noise must be a variance > 0, not {args.noise}")
    check_output_folder(args.out)
    for b in blocks:
        StereoParams(block=b, disparities=args.disparities)
    pair = synthetic_pair(disparities=args.disparities) if args.synthetic else \
        load_middlebury(args.dataset)
    if pair.ground_truth is None:
        raise UserError(f"dataset {pair.name} has no ground truth to evaluate against")
    StereoParams(disparities=args.disparities).with_size(pair.left.shape[1], pair.left.shape[0])
    conditions = [Condition(), Condition(noise=args.noise, seed=args.seed)]
    if pair.is_colour:
        conditions += [Condition(bayer=True, seed=args.seed),
                       Condition(bayer=True, gains=BAYER_GAINS, read_noise=BAYER_READ_NOISE,
                                 seed=args.seed)]
    rows, maps, sgm_rows = paper_sweep(pair, conditions, blocks, args.disparities, args.jobs)
    _write_report(args, pair, conditions, blocks, rows, maps, sgm_rows)


def _write_report(args, pair, conditions, blocks, rows, maps, sgm_rows):
    """README.md, plots, Fig. 12 grid and results.json of a finished sweep."""
    # Compare with the paper only for its own configuration (teddy blocks 7..19, D=100).
    is_paper = (blocks == PAPER_BLOCKS and args.disparities == PAPER_DISPARITIES
                and not args.synthetic)
    out = Path(args.out)
    labels = [f"{b}x{b}" for b in blocks]
    sections, summary = [], {}
    figures = [("fig6", "Fig. 6: correct matches (%), clean", conditions[0], PAPER_FIG6),
               ("fig8", f"Fig. 8: correct matches (%), gaussian noise {args.noise:g}",
                conditions[1], PAPER_FIG8 if args.noise == PAPER_NOISE else None)]
    figures += [(f"bayer{i}", f"Bayer stand-in ({c.label}) in place of Figs. 10-11", c, None)
                for i, c in enumerate(conditions[2:], 1)]
    for key, title, condition, reference in figures:
        measured = _series(rows, condition.label)
        reference = reference if is_paper else None
        plot_series(out / f"{key}.png", f"{pair.name}: {title}", labels, measured, reference)
        if reference:
            text, mads = _comparison(title, measured, reference, blocks)
            summary[key] = mads
        else:
            text = _measured_table(title, measured, blocks)
        sections.append(f"{text}\n\n{_sgm_table(sgm_rows, condition.label)}\n\n"
                        f"![{key}]({key}.png)\n")

    shown = max_shown_disparity(pair.ground_truth, args.disparities)
    short = {c.label: name for c, name in zip(conditions, ROW_NAMES)}
    grid = [(short[c.label], [pair.ground_truth] + [maps[(c.label, t)] for t in TRANSFORMS]
             + [maps[(c.label, SGM)]]) for c in conditions]
    largest = max(blocks)
    default = sgm_configurations(args.disparities)[0]
    disparity_grid(out / "fig12.png", f"{pair.name}: disparity maps after the L/R check, "
                   f"{largest}x{largest} transform, 3x3 aggregation, D={args.disparities}; "
                   f"last column {default.transform} {default.block}x{default.block} with "
                   f"SGM", ["ground truth", *TRANSFORMS,
                            f"{default.transform} {default.block}x{default.block} SGM"],
                   grid, shown)
    save_disparity_png(out / "ground_truth.png", pair.ground_truth, shown)

    total = sum(r["seconds"] for r in rows + sgm_rows)
    document = "\n".join([
        f"# Paper reproduction: {pair.name}", "",
        f"Generated by `npstereo paper` ({len(rows) + len(sgm_rows)} disparity maps, "
        f"{total:.0f} s of matching with {args.jobs} job(s)). D = {args.disparities}, 3x3 "
        "aggregation, L/R check T = 3, correct = |d - gt| <= 1 over pixels with known ground "
        "truth and x >= D (invalid counts as wrong), noise and bayer seed "
        f"{args.seed}. What the numbers mean and why they differ from the paper: "
        "[docs/quality.md](../quality.md). Beside each figure the semi-global configurations "
        "(the SGM default and census 5x5, docs/semantics.md \"Semi-global aggregation\"), "
        "with the same check and metric. Raw numbers (also density and error rate): "
        "[results.json](results.json).", "",
        *sections,
        "### Fig. 12-style disparity maps", "",
        "![fig12](fig12.png)", ""])
    write_text(out / "results.json", json.dumps(
        {"dataset": pair.name, "disparities": args.disparities, "blocks": list(blocks),
         "seed": args.seed, "mean_abs_diff": summary, "paper_fig6": PAPER_FIG6,
         "paper_fig8_best_reading": PAPER_FIG8, "results": rows, "sgm": sgm_rows},
        indent=1) + "\n")
    write_text(out / "README.md", document)
    for key, mads in summary.items():
        print(f"{key}: mean abs. diff. to the paper " + ", ".join(
            f"{t} {v:.2f}" for t, v in mads.items() if v is not None))
    for configuration in dict.fromkeys(r["configuration"] for r in sgm_rows):
        print(f"{configuration}: correct " + ", ".join(
            f"{r['condition']} {r['correct']:.2f} %" for r in sgm_rows
            if r["configuration"] == configuration))
    print(f"wrote {out / 'README.md'}")


def add_arguments(parser):
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--dataset", metavar="DIR", help="Middlebury scene folder (teddy)")
    source.add_argument("--synthetic", action="store_true", help="the embedded synthetic scene")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--blocks", type=int, nargs="+", default=list(PAPER_BLOCKS),
                        help=f"block sizes (default {PAPER_BLOCKS[0]} {PAPER_BLOCKS[1]} .. "
                             f"{PAPER_BLOCKS[-1]})")
    parser.add_argument("--disparities", type=int, default=PAPER_DISPARITIES,
                        help=f"D (default {PAPER_DISPARITIES})")
    parser.add_argument("--noise", type=float, default=PAPER_NOISE,
                        help=f"gaussian noise variance of the Fig. 8 sweep "
                             f"(default {PAPER_NOISE:g})")
    parser.add_argument("--seed", type=int, default=0, help="seed of the degradations")
    parser.set_defaults(run=run)
