"""Aggregation: the A x A box sum of matching costs (the paper's 3 x 3).

Positions outside the image contribute 0.
"""

import numpy as np

__all__ = ["aggregate"]


def aggregate(costs, size, rows=None):
    """Box sum of ``costs`` over ``size`` x ``size`` around every pixel.

    ``costs`` covers a band of image rows; ``rows`` (start, stop) selects the rows of the
    band to return, whose vertical neighbours must lie in the band or outside the image.
    """
    a = (size - 1) // 2
    height, width = costs.shape
    padded = np.zeros((height, width + 2 * a), dtype=costs.dtype)
    padded[:, a:a + width] = costs
    horizontal = padded[:, 0:width].copy()
    for i in range(1, 2 * a + 1):
        horizontal += padded[:, i:i + width]
    start, stop = (0, height) if rows is None else rows
    out = np.zeros((stop - start, width), dtype=costs.dtype)
    for j in range(-a, a + 1):
        lo, hi = max(start + j, 0), min(stop + j, height)
        out[lo - start - j:hi - start - j] += horizontal[lo:hi]
    return out
