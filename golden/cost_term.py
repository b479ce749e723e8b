"""The ``ad3`` term of the matching cost, bit for bit as the hardware (docs/semantics.md,
"The ad3 cost term"); the one definition the SGM cost volume, the commands, the
co-simulation's reference and the options study use.

T(x, y, d) = min(sum over i, j in -1 .. 1 of A(x + i, y + j, d), 255) >> 5, with
A(x', y', d) = min(|PL(x', y') - PR(x' - d, y')|, 31) where the right pixel's column
x' - d is at least 1, and 0 otherwise; pixels outside the image are 0 (the zero padding of
the transforms). Why column 0 of the right image is left out: the hardware takes the right
pixels of a term from the word of the right column x - d, which carries the column to its
right; right column 0 would come from the word of column -1, which does not exist.
"""

import numpy as np

from ..params.cost_terms import AD3_CLIP, AD3_LIMIT, AD3_SHIFT, check_cost_term

__all__ = ["ad3_term", "add_cost_term"]


def ad3_term(left, right, disparities, rows=None):
    """T of every pixel of the rows ``rows`` (default all) and disparity: (rows, W, D)
    uint8, 0 .. 7. ``left``, ``right``: the whole (H, W) gray images (the rows above and
    below the band are part of its windows)."""
    left, right = np.asarray(left, np.int16), np.asarray(right, np.int16)
    height, width = left.shape
    y0, y1 = (0, height) if rows is None else rows
    # The band's rows and one row either side, zero outside the image.
    padded = np.zeros((2, y1 - y0 + 2, width + 2), np.int16)
    for plane, image in zip(padded, (left, right)):
        top, bottom = max(0, y0 - 1), min(height, y1 + 1)
        plane[top - (y0 - 1):bottom - (y0 - 1), 1:width + 1] = image[top:bottom]
    band_left, band_right = padded
    term = np.empty((y1 - y0, width, disparities), np.uint8)
    differences = np.zeros((y1 - y0 + 2, width + 2), np.int16)
    for d in range(disparities):
        # Padded column c is image column c - 1; A(x', d) needs x' - d >= 1, x' = c - 1.
        differences[:] = 0
        first = min(d + 2, width + 2)
        np.minimum(np.abs(band_left[:, first:] - band_right[:, first - d:width + 2 - d]),
                   AD3_CLIP, out=differences[:, first:])
        rows3 = differences[:-2] + differences[1:-1] + differences[2:]
        total = rows3[:, :-2] + rows3[:, 1:-1] + rows3[:, 2:]
        term[:, :, d] = np.minimum(total, AD3_LIMIT) >> AD3_SHIFT
    return term


def add_cost_term(volume, left, right, params, rows=None):
    """Add ``params.cost_term`` (if any) in place to ``volume`` (rows, W, D), the SGM
    matching costs of the rows ``rows`` of the gray images, where the pair exists
    (x - d >= 0: elsewhere the cost is already Cmax, which includes the term's maximum)."""
    if params.cost_term is None:
        return volume
    check_cost_term(params.cost_term, params.transform, params.is_sgm, params.aggregation)
    term = ad3_term(left, right, params.disparities, rows)
    width = volume.shape[1]
    exists = np.arange(params.disparities)[None, :] <= np.arange(width)[:, None]
    volume += np.where(exists, term, 0).astype(volume.dtype)
    return volume
