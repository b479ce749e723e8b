"""Winner-Takes-All inside one calculation round (partition) and across partitions.

Both compare with a strict ``<`` while disparities (and partitions) are visited in increasing
order, so a tie keeps the lowest disparity; the result is therefore the same for every
round count R, which tests/test_golden.py checks.
"""

import numpy as np

__all__ = ["wta_partition", "evaluate_partitions", "RightWTA"]


def wta_partition(aggregated_costs, first_disparity):
    """WTA over one partition's aggregated costs, given in increasing disparity order.

    Returns (best cost, best disparity) arrays.
    """
    best_cost = best_disparity = None
    for offset, costs in enumerate(aggregated_costs):
        if best_cost is None:
            best_cost = costs.copy()
            best_disparity = np.full(costs.shape, first_disparity, dtype=np.int16)
            continue
        better = costs < best_cost
        best_cost[better] = costs[better]
        best_disparity[better] = first_disparity + offset
    return best_cost, best_disparity


def evaluate_partitions(partition_results):
    """The evaluation stage: WTA across the partitions' (cost, disparity) results."""
    best_cost = best_disparity = None
    for cost, disparity in partition_results:
        if best_cost is None:
            best_cost, best_disparity = cost.copy(), disparity.copy()
            continue
        better = cost < best_cost
        best_cost[better] = cost[better]
        best_disparity[better] = disparity[better]
    return best_disparity


class RightWTA:
    """WTA of the right-referenced map, fed from the same aggregated costs.

    Right pixel xr at disparity d uses the left pixel's cost at x = xr + d, so only
    disparities d <= W - 1 - xr take part.
    """

    def __init__(self, shape):
        self.best_cost = np.full(shape, np.iinfo(np.int64).max, dtype=np.int64)
        self.best_disparity = np.zeros(shape, dtype=np.int16)

    def update(self, aggregated_costs, d):
        width = aggregated_costs.shape[-1]
        candidate = aggregated_costs[:, d:]
        current = self.best_cost[:, :width - d]
        better = candidate < current
        current[better] = candidate[better]
        self.best_disparity[:, :width - d][better] = d
