"""Figures of the commands' results: quality plots, disparity map grids, resource plots.

matplotlib figures (no pyplot state), written through :mod:`npstereo.gen.atomic` so an
interrupted command never leaves a torn PNG behind. Single disparity maps and gray images
are written by :mod:`npstereo.gen.images`, without matplotlib.
"""

from pathlib import Path

import numpy as np

from ...params import TRANSFORMS, StereoParams
from ..atomic import atomic_path
from ..images import colour_disparity
from .camera import PEERS, evaluations_per_second
from .paper_data import PAPER_BLOCKS, PAPER_CLOCK, PAPER_LOGIC, PAPER_MEMORY

__all__ = ["save_figure", "plot_series", "disparity_grid", "sweep_plots", "pareto_plot",
           "camera_plot"]


def _figure(**options):
    """A matplotlib ``Figure``. matplotlib is imported here, when a plot is drawn: it takes
    over a second to import, and ``npstereo report`` of one configuration imports this
    module without drawing anything."""
    from matplotlib.figure import Figure
    return Figure(**options)


def save_figure(path, figure):
    """Write a matplotlib figure as PNG."""
    with atomic_path(path, suffix=".png") as tmp:
        figure.savefig(tmp, format="png", dpi=110, bbox_inches="tight")


def plot_series(path, title, x_labels, measured, reference=None, ylabel="correct matches (%)"):
    """Line plot of measured series (solid) and, where given, the paper's (dashed).

    ``measured`` and ``reference`` map a series name to one value per x label; reference
    values may be None where the paper's number is not readable.
    """
    figure = _figure(figsize=(6.4, 4.2))
    axes = figure.add_subplot()
    x = np.arange(len(x_labels))
    for index, (name, values) in enumerate(measured.items()):
        colour = f"C{index}"
        axes.plot(x, values, "o-", color=colour, label=f"{name} (npstereo)")
        if reference and name in reference:
            ref = np.array([np.nan if v is None else v for v in reference[name]], dtype=float)
            axes.plot(x, ref, "s--", color=colour, alpha=0.6, label=f"{name} (paper)")
    axes.set_xticks(x, x_labels)
    axes.set_xlabel("block size")
    axes.set_ylabel(ylabel)
    axes.set_title(title)
    axes.grid(alpha=0.3)
    axes.legend(fontsize=7, ncol=2)
    save_figure(path, figure)


def disparity_grid(path, title, columns, rows, max_disparity):
    """A grid of disparity maps: one column per name in ``columns``, one row per entry of
    ``rows`` given as (row label, [map per column]); a map may be None for an empty cell.
    """
    first = next(m for _, maps in rows for m in maps if m is not None)
    height, width = np.asarray(first).shape[:2]
    cell = 2.2
    figure = _figure(figsize=(len(columns) * cell, len(rows) * cell * height / width + 0.5),
                     layout="constrained")
    for r, (label, maps) in enumerate(rows):
        for c, disparity in enumerate(maps):
            axes = figure.add_subplot(len(rows), len(columns), r * len(columns) + c + 1)
            axes.set_xticks([])
            axes.set_yticks([])
            if disparity is not None:
                axes.imshow(colour_disparity(disparity, max_disparity), interpolation="nearest")
            else:
                axes.set_frame_on(False)
            if r == 0:
                axes.set_title(columns[c], fontsize=8)
            if c == 0:
                axes.set_ylabel(label, fontsize=8)
    figure.suptitle(title, fontsize=9)
    save_figure(path, figure)


def sweep_plots(reports, out):
    """PNG plots of a resource sweep: logic, memory and (if placed and routed) clock
    against block size, ours solid and the paper's dashed in the same colour.

    Parameters
    ----------
    reports : list of dict
        The sweep's reports (``npstereo report``'s JSON).
    out : path
        Folder for ``logic.png``, ``memory.png`` and ``fmax.png``.

    Returns
    -------
    list of Path
        The files written.
    """
    colours = dict(zip(TRANSFORMS, ("tab:blue", "tab:orange", "tab:green", "tab:red")))
    styles = {"auto": "o-", "transforms": "o-", "costs": "s:", "pixels": "^-."}
    panels = [("logic", "cyclonev", "logic", PAPER_LOGIC,
               "logic (ours: Cyclone V ALUTs, paper: Stratix II LEs)"),
              ("memory", "cyclonev", "memory_bits", PAPER_MEMORY, "memory bits")]
    if any(r["results"].get("ecp5", {}).get("fmax_mhz") for r in reports):
        panels.append(("fmax", "ecp5", "fmax_mhz", None, "clock MHz (ours: ECP5 nextpnr)"))
    buffers = sorted({(r["params"].get("line_buffer", "auto"),
                       r["params"].get("lut_inputs", 4)) for r in reports})
    written = []
    for name, target, key, figures, label in panels:
        figure = _figure(figsize=(7.5, 6.8))
        axes = figure.add_subplot()
        for transform in TRANSFORMS:
            for buffer, lut in buffers:
                points = [(r["params"]["block"], r["results"][target][key]) for r in reports
                          if r["params"]["transform"] == transform
                          and r["params"].get("line_buffer", "auto") == buffer
                          and r["params"].get("lut_inputs", 4) == lut
                          and r["results"].get(target, {}).get("status") == "ok"
                          and r["results"][target].get(key) is not None]
                if points:
                    rows = "" if buffer == "auto" else f", rows above as {buffer}"
                    # Arranged for 6-input LUTs: the same line, hollow markers.
                    six = {"markerfacecolor": "none"} if lut == 6 else {}
                    axes.plot(*zip(*points), styles[buffer], color=colours[transform],
                              label=f"{transform}{rows}" + (", 6-input LUTs" if six else ""),
                              **six)
            if figures is not None:
                values = [(b, v) for b, v in zip(PAPER_BLOCKS, figures[transform])
                          if v is not None]
                axes.plot(*zip(*values), "x--", color=colours[transform], alpha=0.5,
                          label=f"{transform} (paper)")
        if name == "fmax":
            axes.plot(list(PAPER_CLOCK), list(PAPER_CLOCK.values()), "ks--",
                      label="paper")
        if name == "logic":
            axes.set_yscale("log")  # ext. census is ten times the others
        axes.set_xlabel("block size B")
        axes.set_ylabel(label)
        axes.set_xticks(PAPER_BLOCKS)
        axes.grid(alpha=0.3)
        # Below the axes: with both LUT arrangements the lines fill the plot.
        axes.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.12))
        axes.set_title(f"{label}, 450x375, D=100, R=10")
        figure.tight_layout()
        target_path = Path(out) / f"{name}.png"
        with atomic_path(target_path) as tmp:
            figure.savefig(tmp, dpi=110, bbox_inches="tight")
        written.append(target_path)
    return written


def pareto_plot(path, points, labels, front, recommended, device, colour_key, colour_label,
                title):
    """Quality against logic of an exploration, the picture a person reads at a glance.

    Parameters
    ----------
    path : path
        The PNG to write.
    points : list of dict
        Explorer points (:func:`npstereo.gen.explore.explorer.explore`): ``logic``,
        ``memory_bits``, ``fits``, the clean quality first in ``quality``, and
        ``colour_key``.
    labels : list of str
        A short name per point, written beside it.
    front : list of int
        Indices of the Pareto front (drawn as a staircase).
    recommended : int or None
        Index of the recommendation (ringed).
    device : npstereo.gen.flow.capacity.Device
        Its logic capacity is the vertical line.
    colour_key, colour_label : str
        The point field that colours the points (Fmax, or the logic depth without place
        and route) and its colour-bar label.
    title : str
    """
    from matplotlib.ticker import FuncFormatter
    shown = [i for i, p in enumerate(points) if p["logic"] is not None
             and next(iter(p["quality"].values())).get("correct") is not None]
    figure = _figure(figsize=(8.8, 5.6))
    axes = figure.add_subplot()
    logic = np.array([points[i]["logic"] for i in shown], dtype=float)
    quality = np.array([next(iter(points[i]["quality"].values()))["correct"] for i in shown])
    memory = np.array([points[i]["memory_bits"] for i in shown], dtype=float)
    values = [points[i].get(colour_key) for i in shown]
    colours = np.array([np.nan if v is None else v for v in values], dtype=float)
    largest = max(memory.max(), 1.0) if len(memory) else 1.0
    sizes = 40 + 560 * memory / largest
    fits = np.array([bool(points[i]["fits"]) for i in shown], dtype=bool)
    finite = colours[np.isfinite(colours)]
    low, high = (finite.min(), finite.max()) if len(finite) else (0.0, 1.0)
    if high - low < 1:
        # Colours a fraction of a MHz or of a LUT level apart would look like a
        # difference that matters; below one unit they stay close.
        middle = (low + high) / 2
        low, high = middle - 0.5, middle + 0.5
    scatter = None
    for mask, edge, style in ((fits, "black", "-"), (~fits, "red", "--")):
        if mask.any():
            scatter = axes.scatter(logic[mask], quality[mask], s=sizes[mask],
                                   c=colours[mask], cmap="viridis", vmin=low, vmax=high,
                                   edgecolors=edge, linewidths=1.2, linestyles=style,
                                   alpha=0.85, zorder=3, plotnonfinite=True)
    if scatter is not None and len(finite):
        figure.colorbar(scatter, ax=axes, label=colour_label, format="%.1f")
    for k, i in enumerate(shown):
        axes.annotate(labels[i], (logic[k], quality[k]), xytext=(6, 5),
                      textcoords="offset points", fontsize=7)
    on_front = [i for i in front if i in shown]
    if on_front:
        xs = [points[i]["logic"] for i in on_front]
        ys = [next(iter(points[i]["quality"].values()))["correct"] for i in on_front]
        axes.step(xs, ys, where="post", color="black", linewidth=1.4, alpha=0.7,
                  zorder=2, label="Pareto front (more correct, less logic)")
    if recommended is not None and recommended in shown:
        k = shown.index(recommended)
        axes.scatter([logic[k]], [quality[k]], s=sizes[k] + 500, facecolors="none",
                     edgecolors="tab:red", linewidths=2.2, zorder=4)
        axes.scatter([], [], s=120, facecolors="none", edgecolors="tab:red", linewidths=2.2,
                     label=f"recommended: {labels[recommended]}")
    resource = device.logic_resource
    axes.axvline(resource.capacity, color="tab:red", linewidth=2, linestyle=":",
                 label=f"{device.part}: {resource.capacity:,} {resource.name}")
    axes.set_xscale("log")
    left = min(logic.min() if len(logic) else resource.capacity, resource.capacity) / 1.6
    right = max(logic.max() if len(logic) else resource.capacity, resource.capacity) * 1.6
    axes.set_xlim(left, right)
    axes.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:,.0f}"))
    axes.xaxis.set_minor_formatter(FuncFormatter(
        lambda value, _: f"{value:,.0f}" if str(int(value))[0] in "25" else ""))
    axes.tick_params(axis="x", which="minor", labelsize=7)
    axes.set_xlabel(f"logic ({resource.name}, log scale)")
    axes.set_ylabel("correct matches, clean (%)")
    axes.grid(alpha=0.3, which="both")
    for bits in sorted({int(largest), int(largest / 4)} - {0}):
        axes.scatter([], [], s=40 + 560 * bits / largest, color="lightgray",
                     edgecolors="black", label=f"{bits:,} memory bits")
    axes.scatter([], [], s=60, color="lightgray", edgecolors="red", linestyles="--",
                 label="does not fit the device")
    axes.legend(fontsize=7, loc="lower right", labelspacing=1.3, borderpad=0.9)
    axes.set_title(title, fontsize=9)
    figure.tight_layout()
    save_figure(path, figure)


def camera_plot(reports, out):
    """``camera.png``: the disparity evaluations per second (W H D fps) of every camera
    configuration placed and routed on the ECP5, beside the published peers, fastest on
    top. Configurations without a routed clock are left out (camera.md says why)."""
    bars = []
    for report in reports:
        p = StereoParams(**report["params"])
        result = report["results"].get("ecp5") or {}
        if result.get("status") == "ok" and result.get("frames_per_second"):
            matcher = "SGM" if p.is_sgm else f"{p.aggregation}x{p.aggregation} box"
            rate = evaluations_per_second(p.width, p.height, p.disparities,
                                          result["frames_per_second"])
            bars.append((f"census {p.block}x{p.block} {matcher}, {p.width}x{p.height}, "
                         f"D={p.disparities}, R={p.rounds} ({result['fmax_mhz']:.0f} MHz)",
                         rate / 1e9, "C0" if p.is_sgm else "C1"))
    bars += [(f"{name}, {w}x{h}, D={d}", evaluations_per_second(w, h, d, fps) / 1e9, "0.6")
             for name, w, h, d, fps in PEERS]
    bars.sort(key=lambda bar: bar[1])
    figure = _figure(figsize=(7.5, 0.32 * len(bars) + 1.2))
    axes = figure.add_subplot()
    y = np.arange(len(bars))
    axes.barh(y, [rate for _, rate, _ in bars], color=[colour for _, _, colour in bars])
    axes.set_yticks(y, [label for label, _, _ in bars], fontsize=7)
    axes.set_xlabel("disparity evaluations per second (G, W x H x D x frames/s)")
    axes.set_title("npstereo on the ECP5-85k (blue SGM, orange box) and published designs "
                   "(gray)", fontsize=8)
    axes.grid(axis="x", alpha=0.3)
    path = Path(out) / "camera.png"
    save_figure(path, figure)
    return [path]
