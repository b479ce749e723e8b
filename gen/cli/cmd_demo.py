"""``npstereo demo``: the main job on the embedded synthetic scene, no external files needed.

:func:`golden_demo` is the golden-model part (disparity maps of all four transforms with
the paper's 3x3 box, the semi-global default beside them, and their quality);
:func:`hardware_demo` generates the Verilog of one core for the scene and co-simulates the
whole frame under Verilator, bit for bit against the golden map.
"""

import json
from pathlib import Path

from tqdm import tqdm

from ...golden.quality import evaluate
from ...golden.synthetic import DEFAULT_DISPARITIES, synthetic_pair
from ...hdl.verilog import core_verilog
from ...params import SGM_RECOMMENDED, TRANSFORMS, StereoParams
from ...sim.cosim import run_frame
from ..atomic import write_text
from ..images import save_disparity_png, save_gray_png
from ..matching import match_images
from .arguments import STEREO_DEFAULTS, check_output_folder
from .verdict import print_verdict

__all__ = ["DESCRIPTION", "add_arguments", "run", "golden_demo", "hardware_demo"]

DESCRIPTION = ("Golden-model disparity maps of all four transforms (3x3 aggregation) and of "
               "semi-global aggregation (census 7x7, the SGM defaults) on the seeded "
               "synthetic scene, with ground truth and correct matches; then the Verilog of a "
               "census core for the scene, co-simulated under Verilator bit for bit.")


#: File name (without .png) of the semi-global map beside the transforms' box maps.
SGM_NAME = "sgm"


def demo_configurations(block):
    """``(name, params)`` of the demo's maps: every transform with the 3x3 box at
    ``block``, then the SGM default (census 7x7, ``params.SGM_RECOMMENDED[0]``)."""
    box = [(t, StereoParams(transform=t, block=block, disparities=DEFAULT_DISPARITIES))
           for t in TRANSFORMS]
    return box + [(SGM_NAME, StereoParams(**SGM_RECOMMENDED[0],
                                          disparities=DEFAULT_DISPARITIES))]


def golden_demo(out, block=9, seed=0):
    """Golden-model disparity maps of the default synthetic scene for every transform with
    the 3x3 box, and with the SGM default beside them.

    Writes ``left.png``, ``right.png``, ``ground_truth.png``, ``<transform>.png``,
    ``sgm.png``, ``golden.json`` and ``summary.md`` into ``out``.

    Returns
    -------
    list of dict
        One row per map: its name (the transform, or ``sgm``), the transform, the
        aggregation, the parameters' description and the quality metrics.
    """
    out = Path(out)
    pair = synthetic_pair(seed=seed)
    left, right = pair.gray()
    top = DEFAULT_DISPARITIES - 1
    rows = []
    maps = {}
    for name, params in demo_configurations(block):
        maps[name] = match_images(left, right, params)
        quality = evaluate(maps[name], pair.ground_truth, params.disparities)
        rows.append({"name": name, "transform": params.transform, "block": params.block,
                     "aggregation": params.describe_aggregation(),
                     "params": params.describe(), **quality.as_dict()})
    save_gray_png(out / "left.png", pair.left)
    save_gray_png(out / "right.png", pair.right)
    save_disparity_png(out / "ground_truth.png", pair.ground_truth, top)
    for name, disparity in maps.items():
        save_disparity_png(out / f"{name}.png", disparity, top)
    write_text(out / "golden.json", json.dumps({"scene": pair.name, "results": rows}, indent=1)
               + "\n")
    lines = [f"# Golden model on {pair.name}", "",
             f"D = {DEFAULT_DISPARITIES}, L/R check T = 3; the four transforms {block}x{block} "
             "with the paper's 3x3 aggregation, then semi-global aggregation (SGM) with its "
             "defaults. Correct = |d - gt| <= 1 over pixels with x >= D.", "",
             "| transform | aggregation | correct (%) | density (%) | error rate (%) | map |",
             "|---|---|---:|---:|---:|---|"]
    lines += [f"| {r['transform']} {r['block']}x{r['block']} | {r['aggregation']} | "
              f"{r['correct']:.2f} | {r['density']:.2f} | {r['error_rate']:.2f} | "
              f"![{r['name']}]({r['name']}.png) |" for r in rows]
    lines += ["", "Ground truth: ![ground truth](ground_truth.png)", ""]
    write_text(out / "summary.md", "\n".join(lines))
    return rows


def hardware_demo(out, transform="census", block=9, rounds=4, seed=0):
    """Generate ``core.v`` for the synthetic scene and co-simulate one frame under Verilator.

    Returns the :class:`~npstereo.sim.cosim.RunResult` of the frame and the parameters.
    """
    out = Path(out)
    pair = synthetic_pair(seed=seed)
    left, right = pair.gray()
    height, width = left.shape
    params = StereoParams(transform=transform, block=block, disparities=DEFAULT_DISPARITIES,
                          rounds=rounds, width=width, height=height)
    verilog = core_verilog(params)
    write_text(out / "core.v", verilog)
    with tqdm(total=width * height, desc="cosim verilator", unit="px", leave=False) as bar:
        result = run_frame("verilator", params, left, right, core_text=verilog,
                           progress=bar.update)
    save_disparity_png(out / "hardware.png", result.disparity, params.disparities - 1)
    return result, params


def run(args):
    check_output_folder(args.out)
    StereoParams(block=args.block, disparities=DEFAULT_DISPARITIES)
    rows = golden_demo(args.out, block=args.block, seed=args.seed)
    print(f"golden model on the synthetic scene (seed {args.seed}), D={DEFAULT_DISPARITIES}, "
          f"L/R check T=3:")
    for row in rows:
        label = f"{row['transform']} {row['block']}x{row['block']} {row['aggregation']}"
        print(f"  {label:<34} correct {row['correct']:6.2f}%  "
              f"density {row['density']:6.2f}%  error rate {row['error_rate']:5.2f}%")
    print(f"disparity PNGs, summary.md and golden.json in {args.out}")
    if args.no_hardware:
        return 0
    print(f"generating the census {args.block}x{args.block} core (R=4) and co-simulating the "
          f"frame under Verilator (the first build takes a minute or two) ...")
    result, params = hardware_demo(args.out, block=args.block, seed=args.seed)
    _, comparison = result.frames[0]
    print(f"hardware ({params.describe()}): {args.out}/core.v, map {args.out}/hardware.png")
    print_verdict(comparison, result.cycles, params.width * params.height)
    return 0 if comparison.ok else 1


def add_arguments(parser):
    parser.add_argument("--out", default="build/demo", help="output folder (default build/demo)")
    parser.add_argument("--block", type=int, default=STEREO_DEFAULTS["block"],
                        help=f"transform block size of the box maps "
                             f"(default {STEREO_DEFAULTS['block']})")
    parser.add_argument("--seed", type=int, default=0, help="scene seed (default 0)")
    parser.add_argument("--no-hardware", action="store_true",
                        help="golden model only: skip Verilog generation and co-simulation")
    parser.set_defaults(run=run)
