"""Matching costs between a left pixel and the right pixel d columns to its left (Eq. 3, 5, 9).

A pair whose right pixel lies outside the image (x - d < 0) costs 0: the hardware masks it,
and such pairs only ever reach valid outputs through the right-referenced map's aggregation.
"""

import numpy as np

__all__ = ["matching_costs"]


def _shifted_pair(left, right, d):
    """Left pixels x >= d and their right partners x - d, along the last axis."""
    width = left.shape[-1]
    return left[..., d:], right[..., :width - d]


def _rank_cost(left, right, d):
    a, b = _shifted_pair(left.astype(np.int64), right.astype(np.int64), d)
    return np.abs(a - b)


def _census_cost(left, right, d):
    a, b = _shifted_pair(left, right, d)
    return np.bitwise_count(a ^ b).sum(axis=0, dtype=np.int64)


def _ext_census_cost(left, right, d):
    a, b = _shifted_pair(left, right, d)
    k = a.shape[0]
    # 128 terms of at most 255 fit uint16 even when added wrapping in int16.
    total = np.zeros(a.shape[1:], dtype=np.int64)
    for start in range(0, k, 128):
        diff = a[start:start + 128].astype(np.int16) - b[start:start + 128]
        np.abs(diff, out=diff)
        total += diff.sum(axis=0, dtype=np.int16).view(np.uint16)
    return total


_COSTS = {"rank": _rank_cost, "ext-rank": _rank_cost, "census": _census_cost,
          "ext-census": _ext_census_cost}


def matching_costs(left_t, right_t, d, params):
    """Cost of every left pixel against its right partner at disparity d. (H, W) int64."""
    costs = _COSTS[params.transform](left_t, right_t, d)
    out = np.zeros(costs.shape[:-1] + (costs.shape[-1] + d,), dtype=np.int64)
    out[..., d:] = costs
    return out
