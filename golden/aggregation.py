"""Aggregation: the A x A box sum of matching costs (the paper's 3 x 3).

Positions outside the image contribute 0.
"""

import numpy as np

__all__ = ["aggregate"]


def aggregate(costs, size, rows=None, out=None, scratch=None):
    """Box sum of ``costs`` over ``size`` x ``size`` around every pixel.

    Parameters
    ----------
    costs : (rows, W) ndarray
        Matching costs of a band of image rows (or of the whole image).
    size : int
        Aggregation window size A (odd).
    rows : (start, stop), optional
        The rows of the band to return; their vertical neighbours must lie in the band or
        outside the image. Default: every row, the band being the whole image.
    out : ndarray, optional
        (stop - start, W) array of ``costs.dtype`` for the result.
    scratch : ndarray, optional
        An array shaped like ``costs`` for the horizontal sums (saves an allocation per d).

    Returns
    -------
    ndarray
        The aggregated costs of rows ``start .. stop - 1``.
    """
    a = (size - 1) // 2
    height, width = costs.shape
    start, stop = (0, height) if rows is None else rows
    if out is None:
        out = np.empty((stop - start, width), dtype=costs.dtype)
    if a == 0:
        out[...] = costs[start:stop]
        return out
    # The first neighbour of each direction is added while copying (one pass less).
    horizontal = np.empty_like(costs) if scratch is None else scratch
    np.add(costs[:, 1:], costs[:, :width - 1], out=horizontal[:, 1:])
    horizontal[:, 0] = costs[:, 0]
    horizontal[:, :width - 1] += costs[:, 1:]
    for i in range(2, a + 1):
        horizontal[:, i:] += costs[:, :width - i]
        horizontal[:, :width - i] += costs[:, i:]
    # Row y sums the horizontal rows y - a .. y + a that exist; rows beyond the band are
    # outside the image, so the clipped ranges are exact.
    below = min(stop, height - 1)
    if below > start:
        np.add(horizontal[start:below], horizontal[start + 1:below + 1],
               out=out[:below - start])
    out[max(0, below - start):] = horizontal[max(start, below):stop]
    above = max(start, 1)
    if above < stop:
        out[above - start:] += horizontal[above - 1:stop - 1]
    for j in range(2, a + 1):
        below = min(stop, height - j)
        if below > start:
            out[:below - start] += horizontal[start + j:below + j]
        above = max(start, j)
        if above < stop:
            out[above - start:] += horizontal[above - j:stop - j]
    return out
