"""Matching costs between a left pixel and the right pixel d columns to its left (Eq. 3, 5, 9).

A pair whose right pixel lies outside the image (x - d < 0) costs 0: the hardware masks it,
and such pairs only ever reach valid outputs through the right-referenced map's aggregation.
"""

import numpy as np

from ..params import check_transform_table

__all__ = ["cost_dtype", "pixel_sums", "matching_costs"]


def cost_dtype(params):
    """The narrowest unsigned dtype that holds every aggregated cost exactly."""
    bits = params.aggregated_cost_bits
    return np.uint16 if bits <= 16 else np.uint32 if bits <= 32 else np.uint64


def _absolute_cost(left, right, out, totals):
    # |a - b| as max - min stays exact in the transform's own unsigned dtype.
    np.subtract(np.maximum(left, right), np.minimum(left, right), out=out, casting="unsafe")


def _hamming_cost(left, right, out, totals):
    ones = np.bitwise_count(np.bitwise_xor(left, right))
    # Up to 3 words (192 bits) the count fits uint8: add without widening, widen once.
    total = np.add.reduce(ones, axis=0, dtype=np.uint8 if len(ones) <= 3 else out.dtype)
    np.copyto(out, total)


def _byte_sad_cost(left, right, out, totals):
    # sum |u - v| = sum u + sum v - 2 sum min(u, v): one uint8 pass over the k bytes instead
    # of three (max, min, subtract); ``totals`` (sum u + sum v) come from byte sums
    # computed once, not once per d. Summing over the last axis is fast when each pixel's
    # k bytes are contiguous, as transform.ext_census stores them.
    smaller = np.minimum(left.transpose(1, 2, 0), right.transpose(1, 2, 0))
    np.add.reduce(smaller, axis=-1, dtype=out.dtype, out=out)
    out *= out.dtype.type(2)
    np.subtract(totals, out, out=out)


def _byte_sums(transformed, dtype):
    """Sum of each pixel's bytes: (rows, W) of ``dtype``."""
    return np.add.reduce(transformed, axis=0, dtype=dtype)


#: Per transform: ``cost(left, right, out, totals)``, the costs of aligned pairs of
#: transformed pixels into ``out``; and the per-pixel sums it needs for ``totals`` (the left
#: sum plus the right sum of each pair), computed once for all disparities, or None.
_COSTS = check_transform_table({
    "rank": (_absolute_cost, None),
    "census": (_hamming_cost, None),
    "ext-rank": (_absolute_cost, None),
    "ext-census": (_byte_sad_cost, _byte_sums),
}, "golden.matching_cost._COSTS")


def pixel_sums(left_t, right_t, params, dtype):
    """The per-pixel sums the cost of ``params.transform`` reuses for every disparity, as
    (left, right) of ``dtype``, or None if it needs none (see :func:`matching_costs`)."""
    summed = _COSTS[params.transform][1]
    return None if summed is None else (summed(left_t, dtype), summed(right_t, dtype))


def matching_costs(left_t, right_t, d, params, out=None, sums=None):
    """Cost of every left pixel against its right partner at disparity d.

    Parameters
    ----------
    left_t, right_t : ndarray
        Transformed images (or bands of rows of them) as :func:`.transform.transform`
        returns them; the last two axes are rows and columns.
    d : int
        Disparity: left column x is matched with right column x - d.
    params : StereoParams
    out : ndarray, optional
        (rows, W) array of :func:`cost_dtype` to write into (saves an allocation per d).
    sums : tuple, optional
        ``pixel_sums(left_t, right_t, params, out.dtype)``, when the caller computes the
        costs of many disparities (saves a pass over the transformed pixels per d).

    Returns
    -------
    ndarray
        (rows, W) of :func:`cost_dtype`; 0 where x - d < 0.
    """
    width = left_t.shape[-1]
    if out is None:
        out = np.empty(left_t.shape[-2:], dtype=cost_dtype(params))
    out[:, :d] = 0
    cost, summed = _COSTS[params.transform]
    totals = None
    if summed is not None:
        left_sums, right_sums = (sums if sums is not None else
                                 pixel_sums(left_t, right_t, params, out.dtype))
        totals = left_sums[:, d:] + right_sums[:, :width - d]
    cost(left_t[..., d:], right_t[..., :width - d], out[:, d:], totals)
    return out
