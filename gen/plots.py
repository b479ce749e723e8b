"""Figures of the commands' results: quality plots, disparity map grids, resource plots.

matplotlib figures (no pyplot state), written through :mod:`npstereo.gen.atomic` so an
interrupted command never leaves a torn PNG behind. Single disparity maps and gray images
are written by :mod:`.images`, without matplotlib.
"""

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..params import TRANSFORMS
from .atomic import atomic_path
from .images import colour_disparity
from .paper_resources import PAPER_BLOCKS, PAPER_CLOCK, PAPER_LOGIC, PAPER_MEMORY

__all__ = ["save_figure", "plot_series", "disparity_grid", "sweep_plots"]


def save_figure(path, figure):
    """Write a matplotlib figure as PNG."""
    with atomic_path(path, suffix=".png") as tmp:
        figure.savefig(tmp, format="png", dpi=110, bbox_inches="tight")


def plot_series(path, title, x_labels, measured, reference=None, ylabel="correct matches (%)"):
    """Line plot of measured series (solid) and, where given, the paper's (dashed).

    ``measured`` and ``reference`` map a series name to one value per x label; reference
    values may be None where the paper's number is not readable.
    """
    figure = Figure(figsize=(6.4, 4.2))
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
    figure = Figure(figsize=(len(columns) * cell, len(rows) * cell * height / width + 0.5),
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
    styles = {"transforms": "o-", "costs": "s:", "auto": "o-"}
    panels = [("logic", "cyclonev", "logic", PAPER_LOGIC,
               "logic (ours: Cyclone V ALUTs, paper: Stratix II LEs)"),
              ("memory", "cyclonev", "memory_bits", PAPER_MEMORY, "memory bits")]
    if any(r["results"].get("ecp5", {}).get("fmax_mhz") for r in reports):
        panels.append(("fmax", "ecp5", "fmax_mhz", None, "clock MHz (ours: ECP5 nextpnr)"))
    buffers = sorted({r["params"].get("line_buffer", "auto") for r in reports})
    written = []
    for name, target, key, figures, label in panels:
        figure = Figure(figsize=(7.5, 4.8))
        axes = figure.add_subplot()
        for transform in TRANSFORMS:
            for buffer in buffers:
                points = [(r["params"]["block"], r["results"][target][key]) for r in reports
                          if r["params"]["transform"] == transform
                          and r["params"].get("line_buffer", "auto") == buffer
                          and r["results"].get(target, {}).get("status") == "ok"
                          and r["results"][target].get(key) is not None]
                if points:
                    rows = "" if buffer == "auto" else f", rows above as {buffer}"
                    axes.plot(*zip(*points), styles[buffer], color=colours[transform],
                              label=f"{transform}{rows}")
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
        axes.legend(fontsize=7, ncol=2)
        axes.set_title(f"{label}, 450x375, D=100, R=10")
        figure.tight_layout()
        target_path = Path(out) / f"{name}.png"
        with atomic_path(target_path) as tmp:
            figure.savefig(tmp, dpi=110)
        written.append(target_path)
    return written
