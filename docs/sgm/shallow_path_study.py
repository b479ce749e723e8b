"""Issue 27: can the left path's loop be avoided by a shallow path from the row above?

Usage: ``python docs/sgm/shallow_path_study.py --dataset DIR --out docs/sgm/shallow_path_study.json``
(DIR: the Middlebury 2003 teddy folder), then ``--report`` to print the table of ``--out``.

The left path is the only one whose predecessor is in the same row, so the only one with a
loop that must close within a position's clocks (docs/sgm.md, "What is left in the loop").
A path whose predecessor is k columns back in the row above, (x - k, y - 1), runs mostly
along the row as well, but its predecessor was finished a row earlier, as for top-left: no
loop at all, one more row of path costs in block RAM. Each variant keeps golden/sgm.py's
three paths from above and replaces the left path by such a path (exact SGM of that path,
adaptive P2 from the step to its predecessor, fresh starts where it lies outside), or by
nothing. Scored with the project's metric, L/R check at 3, on teddy, teddy mirrored and the
synthetic scenes (seeds 0-2) at noise 0, 2e-4 and 2e-3, for the two configurations of
docs/sgm/left_path_study.py.
"""

import sys
from pathlib import Path

import numpy as np

from npstereo.golden import sgm
from npstereo.golden.quality import evaluate
from npstereo.params import SGM_ROW_PATHS, StereoParams

sys.path.insert(0, str(Path(__file__).parent))
from left_path_study import (conditions, config_label,  # noqa: E402
                             study_main)

#: Columns back in the row above of each shallow path measured.
SHALLOW = (2, 3, 4)
BASELINE = "tracked left (default)"


def shallow_p2(guide, k, p1, p2, adapt):
    """P2 of the path (x - k, y - 1) -> (x, y): docs/semantics.md's adaptive P2 for its step."""
    gray = guide.astype(np.int64)
    step = np.zeros(gray.shape, np.int64)
    step[1:, k:] = np.abs(gray[1:, k:] - gray[:-1, :-k])
    lengths = np.array([v.bit_length() for v in range(256)])
    return np.maximum(p1, p2 >> np.maximum(0, lengths[step] - adapt))


def shallow_path(volume, k, p1, p2_map):
    """L of the path from (x - k, y - 1), normalised as the paths from above: (H, W, D)."""
    costs = volume.astype(np.int64)
    path = costs.copy()
    for y in range(1, costs.shape[0]):
        before = path[y - 1, :-k]
        best = before.copy()
        best[:, 1:] = np.minimum(best[:, 1:], before[:, :-1] + p1)
        best[:, :-1] = np.minimum(best[:, :-1], before[:, 1:] + p1)
        minimum = before.min(axis=1)[:, None]
        path[y, k:] = costs[y, k:] + np.minimum(best - minimum, p2_map[y, k:, None])
    return path


def variants(left, right, config, disparities):
    """(name, summed costs S) of each variant."""
    transform, block, p1, p2, adapt = config
    params = StereoParams(transform=transform, block=block, disparities=disparities)
    volume = sgm.cost_volume(left, right, params)
    above = sum(sgm.path_costs(volume, path, p1, p2, guide=left, adapt=adapt,
                               max_cost=params.max_cost).astype(np.int64)
                for path in SGM_ROW_PATHS)
    yield BASELINE, sgm.aggregate(volume, p1, p2, guide=left, adapt=adapt,
                                  max_cost=params.max_cost)
    yield "no left path (three paths)", above
    for k in SHALLOW:
        yield f"({-k}, -1) instead of left", above + shallow_path(
            volume, k, p1, shallow_p2(left, k, p1, p2, adapt))


def report(rows):
    """Markdown: per configuration and variant, the mean per condition (synthetic seeds
    pooled by noise level) and the change from the default."""
    def condition(scene):
        return scene.rsplit(" ", 1)[0] if scene.startswith("synthetic") else scene
    lines = []
    for config in dict.fromkeys(r["config"] for r in rows):
        table = {}
        for r in (r for r in rows if r["config"] == config):
            table.setdefault(r["variant"], {}).setdefault(condition(r["scene"]), []).append(
                r["correct"])
        names = list(table[BASELINE])
        base = {c: np.mean(v) for c, v in table[BASELINE].items()}
        lines += [f"#### {config}", "", "| left path | " + " | ".join(names) + " |",
                  "|---|" + "---:|" * len(names)]
        for variant, by_condition in table.items():
            means = {c: np.mean(v) for c, v in by_condition.items()}
            cells = [f"{means[c]:.2f}" if variant == BASELINE else
                     f"{means[c]:.2f} ({means[c] - base[c]:+.2f})" for c in names]
            lines.append(f"| {variant} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def measure(dataset, config):
    """The rows of every scene and variant for one configuration."""
    label = config_label(config)
    for scene, left, right, truth, disparities in conditions(dataset):
        for variant, summed in variants(left, right, config, disparities):
            disparity = sgm.disparity_from_summed(summed, 3).disparity
            correct = round(evaluate(disparity, truth, disparities).correct, 3)
            print(f"{label} | {scene:26s} | {variant:28s} {correct:6.2f}", flush=True)
            yield dict(config=label, scene=scene, variant=variant, correct=correct)


def main(argv=None):
    return study_main(argv, __doc__.splitlines()[0], measure, report)


if __name__ == "__main__":
    sys.exit(main())
