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


def disparity_grid(path, title, rows, max_disparity):
    """A grid of disparity maps: ``rows`` is a list of (row label, [(title, map), ...])."""
    columns = max(len(images) for _, images in rows)
    height, width = np.asarray(rows[0][1][0][1]).shape[:2]
    scale = 2.2 / max(width, height) * max(width, 1)
    figure = Figure(figsize=(columns * scale, len(rows) * scale * height / width + 0.6))
    for r, (label, images) in enumerate(rows):
        for c, (name, disparity) in enumerate(images):
            axes = figure.add_subplot(len(rows), columns, r * columns + c + 1)
            axes.imshow(colour_disparity(disparity, max_disparity), interpolation="nearest")
            axes.set_title(f"{label}: {name}" if label else name, fontsize=7)
            axes.set_axis_off()
    figure.suptitle(title, fontsize=9)
    save_figure(path, figure)
