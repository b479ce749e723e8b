"""Winner-Takes-All inside one calculation round (partition) and across partitions.

Both compare with a strict ``<`` while disparities (and partitions) are visited in increasing
order, so a tie keeps the lowest disparity; the result is therefore the same for every
round count R, which tests/test_golden.py checks.
"""

import numpy as np

__all__ = ["wta_partition", "evaluate_partitions", "RightWTA"]

#: The comparison of every WTA: a candidate replaces the best so far only if strictly
#: better, so among equal costs the first visited (lowest) disparity stays.
_better = np.less


class _Winner:
    """Running (best cost, best disparity) of a WTA, updated in place."""

    def __init__(self, cost, disparity):
        self.cost = cost
        self.disparity = disparity

    def update(self, cost, disparity, mask):
        """Take ``cost``/``disparity`` where they beat the current winner (``mask``: scratch)."""
        _better(cost, self.cost, out=mask)
        # The best cost is the minimum whichever equal candidate wins the tie.
        np.minimum(self.cost, cost, out=self.cost)
        np.copyto(self.disparity, disparity, where=mask)


def wta_partition(aggregated_costs, first_disparity):
    """WTA over one partition's aggregated costs, given in increasing disparity order.

    Returns (best cost, best disparity) arrays; the costs are copied, never kept.
    """
    winner = mask = None
    for offset, costs in enumerate(aggregated_costs):
        if winner is None:
            winner = _Winner(costs.copy(), np.full(costs.shape, first_disparity, np.int16))
            mask = np.empty(costs.shape, dtype=bool)
            continue
        winner.update(costs, first_disparity + offset, mask)
    return winner.cost, winner.disparity


def evaluate_partitions(partition_results):
    """The evaluation stage: WTA across the partitions' (cost, disparity) results."""
    winner = mask = None
    for cost, disparity in partition_results:
        if winner is None:
            winner = _Winner(cost.copy(), disparity.copy())
            mask = np.empty(cost.shape, dtype=bool)
            continue
        winner.update(cost, disparity, mask)
    return winner.disparity


class RightWTA:
    """WTA of the right-referenced map, fed from the same aggregated costs.

    Right pixel xr at disparity d uses the left pixel's cost at x = xr + d, so only
    disparities d <= W - 1 - xr take part. Disparities must come in increasing order.
    """

    def __init__(self, shape, dtype=np.int64):
        self.best_cost = np.full(shape, np.iinfo(dtype).max, dtype=dtype)
        self.best_disparity = np.zeros(shape, dtype=np.int16)
        self._mask = np.empty(shape, dtype=bool)

    def update(self, aggregated_costs, d):
        width = aggregated_costs.shape[-1]
        winner = _Winner(self.best_cost[:, :width - d], self.best_disparity[:, :width - d])
        winner.update(aggregated_costs[:, d:], d, self._mask[:, :width - d])
