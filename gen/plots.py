"""PNG output shared by the commands: colour-mapped disparity maps and result plots.

Every file is written through :mod:`npstereo.gen.atomic`, so an interrupted command never
leaves a torn PNG behind.
"""

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure
from PIL import Image

from .atomic import atomic_path

__all__ = ["colour_disparity", "save_disparity_png", "save_gray_png", "save_figure",
           "plot_series", "disparity_grid"]

#: Perceptually ordered map: near (large disparity) is red, far is blue.
COLOURMAP = "turbo"


def colour_disparity(disparity, max_disparity):
    """RGB uint8 rendering of a disparity map; invalid (negative or NaN) pixels are black."""
    disparity = np.asarray(disparity, dtype=np.float64)
    invalid = ~np.isfinite(disparity) | (disparity < 0)
    scaled = np.clip(np.nan_to_num(disparity) / max(max_disparity, 1), 0.0, 1.0)
    rgb = (colormaps[COLOURMAP](scaled)[..., :3] * 255 + 0.5).astype(np.uint8)
    rgb[invalid] = 0
    return rgb


def save_disparity_png(path, disparity, max_disparity):
    """Write ``disparity`` as a colour PNG (0 .. max_disparity mapped by COLOURMAP)."""
    with atomic_path(path, suffix=".png") as tmp:
        Image.fromarray(colour_disparity(disparity, max_disparity)).save(tmp, format="PNG")


def save_gray_png(path, image):
    """Write an 8-bit gray or RGB image as PNG."""
    with atomic_path(path, suffix=".png") as tmp:
        Image.fromarray(np.asarray(image, dtype=np.uint8)).save(tmp, format="PNG")


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
