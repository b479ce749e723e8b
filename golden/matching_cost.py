"""Matching costs between a left pixel and the right pixel d columns to its left (Eq. 3, 5, 9).

A pair whose right pixel lies outside the image (x - d < 0) costs 0: the hardware masks it,
and such pairs only ever reach valid outputs through the right-referenced map's aggregation.
"""

import numpy as np

__all__ = ["cost_dtype", "ext_census_totals", "matching_costs"]


def cost_dtype(params):
    """The narrowest unsigned dtype that holds every aggregated cost exactly."""
    bits = params.aggregated_cost_bits
    return np.uint16 if bits <= 16 else np.uint32 if bits <= 32 else np.uint64


def _rank_cost(left, right, out):
    # |a - b| as max - min stays exact in the transform's own unsigned dtype.
    np.subtract(np.maximum(left, right), np.minimum(left, right), out=out, casting="unsafe")


def _census_cost(left, right, out):
    ones = np.bitwise_count(np.bitwise_xor(left, right))
    # Up to 3 words (192 bits) the count fits uint8: add without widening, widen once.
    total = np.add.reduce(ones, axis=0, dtype=np.uint8 if len(ones) <= 3 else out.dtype)
    np.copyto(out, total)


def _ext_census_cost(left, right, out, totals):
    # sum |u - v| = sum u + sum v - 2 sum min(u, v): one uint8 pass over the k bytes instead
    # of three (max, min, subtract); the byte sums are computed once, not once per d.
    # Summing over the last axis is fast when each pixel's k bytes are contiguous, as
    # transform.ext_census stores them.
    smaller = np.minimum(left.transpose(1, 2, 0), right.transpose(1, 2, 0))
    np.add.reduce(smaller, axis=-1, dtype=out.dtype, out=out)
    out *= out.dtype.type(2)
    np.subtract(totals, out, out=out)


_COSTS = {"rank": _rank_cost, "ext-rank": _rank_cost, "census": _census_cost}


def ext_census_totals(left_t, right_t, d, dtype):
    """sum u + sum v of the ext-census pairs at disparity d: (rows, W - d) of ``dtype``."""
    width = left_t.shape[-1]
    return (np.add.reduce(left_t[..., d:], axis=0, dtype=dtype)
            + np.add.reduce(right_t[..., :width - d], axis=0, dtype=dtype))


def matching_costs(left_t, right_t, d, params, out=None, totals=None):
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
    totals : ndarray, optional
        ext-census only: ``ext_census_totals(left_t, right_t, d, cost_dtype(params))``, when
        the caller has it cheaper (from per-pixel byte sums computed once per image).

    Returns
    -------
    ndarray
        (rows, W) of :func:`cost_dtype`; 0 where x - d < 0.
    """
    width = left_t.shape[-1]
    if out is None:
        out = np.empty(left_t.shape[-2:], dtype=cost_dtype(params))
    out[:, :d] = 0
    left, right = left_t[..., d:], right_t[..., :width - d]
    if params.transform == "ext-census":
        if totals is None:
            totals = ext_census_totals(left_t, right_t, d, out.dtype)
        _ext_census_cost(left, right, out[:, d:], totals)
    else:
        _COSTS[params.transform](left, right, out[:, d:])
    return out
