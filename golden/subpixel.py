"""Sub-pixel disparity: a parabola through the winner's summed costs, in integers.

docs/semantics.md ("Sub-pixel disparity") is the contract; this is its executable form for
the box and the SGM pipeline alike (the winner-takes-all is theirs, shared). For the winner
d of S(x, y, .) with 1 <= d <= D-2 and F fractional bits, with a = S(d-1) - S(d) >= 1 and
b = S(d+1) - S(d) >= 0 (ties go to the lowest disparity):

    q = floor((a 2^(F+1) + a + b) / (2 (a + b)))        0 <= q <= 2^F
    value = d 2^F - 2^(F-1) + q

which is d 2^F + round_half_up((S(d-1) - S(d+1)) 2^F / (2 (a + b))), OpenCV StereoSGBM's
parabola with F bits instead of 4. At d = 0 and d = D-1 the value is d 2^F. The map holds
the values (integers scaled by 2^F, -1 invalid); :func:`levels` turns them into disparity
levels. With F = 0 nothing is fitted: the map is the plain WTA's.
"""

import numpy as np

from .lr_check import INVALID, DisparityResult

__all__ = ["fit", "fit_volume", "NeighbourCosts", "with_fraction", "levels"]


def fit(before, centre, after, disparity, disparities, bits):
    """The values d 2^F + offset of winners ``disparity`` with summed costs ``before`` =
    S(d-1), ``centre`` = S(d), ``after`` = S(d+1) (arrays of one shape; the neighbours are
    ignored at d = 0 and d = D-1). Returns int64."""
    d = np.asarray(disparity, dtype=np.int64)
    inner = (d >= 1) & (d <= disparities - 2)
    centre = np.asarray(centre, dtype=np.int64)
    a = np.where(inner, np.asarray(before, dtype=np.int64) - centre, 1)
    b = np.where(inner, np.asarray(after, dtype=np.int64) - centre, 0)
    if np.any(a < 1) or np.any(b < 0):
        raise ValueError("S(d) must be the minimum with ties to the lowest disparity: "
                         "S(d-1) > S(d) <= S(d+1)")
    quotient = ((a << (bits + 1)) + a + b) // (2 * (a + b))
    fitted = (d << bits) - (1 << bits >> 1) + quotient
    return np.where(inner, fitted, d << bits)


def fit_volume(summed, winners, bits):
    """:func:`fit` of the winners of an (H, W, D) volume of S (SGM's layout)."""
    summed = np.asarray(summed)
    disparities = summed.shape[-1]
    d = np.asarray(winners, dtype=np.intp)[..., None]

    def at(offset):
        return np.take_along_axis(summed, np.clip(d + offset, 0, disparities - 1), -1)[..., 0]
    return fit(at(-1), at(0), at(1), d[..., 0], disparities, bits)


class NeighbourCosts:
    """S(d-1), S(d), S(d+1) of known winners, gathered from the box pipeline's (rows, W)
    arrays of S, one disparity at a time (the pipeline keeps no volume of S)."""

    def __init__(self, winners):
        self.winners = np.asarray(winners)
        self.costs = np.zeros((3, *self.winners.shape), np.int64)

    def update(self, summed, d):
        for k, offset in enumerate((-1, 0, 1)):
            # S(d) is the neighbour at ``offset`` of the winner d - offset.
            where = self.winners == d - offset
            self.costs[k][where] = summed[where]

    def values(self, disparities, bits):
        return fit(*self.costs, self.winners, disparities, bits)


def with_fraction(result, values, bits):
    """``result`` with its kept pixels' disparities replaced by ``values`` (the map of
    fitted values of the raw left winners); the raw maps stay whole levels. F = 0 gives
    ``result`` itself."""
    if not bits:
        return result
    disparity = np.where(result.disparity >= 0, values, INVALID).astype(np.int16)
    return DisparityResult(disparity, result.left, result.right)


def levels(disparity, bits):
    """Disparities in levels: with F > 0 float32 value / 2^F, -1 invalid; with F = 0 the
    int16 map as it is."""
    disparity = np.asarray(disparity)
    if not bits:
        return disparity.astype(np.int16, copy=False)
    return np.where(disparity >= 0, disparity / np.float32(1 << bits),
                    np.float32(INVALID)).astype(np.float32)
