"""Winner-Takes-All inside one calculation round (partition) and across partitions.

Round j evaluates the disparities j*D/R .. (j+1)*D/R - 1 (the paper's partitions; cost
unit i holds disparity j*D/R + i). Every WTA here keeps, among equal costs, the lowest
disparity: a pair replaces the winner if its cost is lower, or equal with a lower
disparity, so the result is the global argmin with ties to the lowest disparity whatever
the order of the visits and for every R, which tests/test_golden.py checks. (The hardware
visits disparities in increasing order and needs only a strict ``<`` on the cost.)
"""

import numpy as np

__all__ = ["partition_disparities", "wta_partition", "evaluate_partitions", "RightWTA"]


def partition_disparities(params, round_):
    """Disparities of calculation round ``round_``, in increasing order."""
    return range(round_ * params.per_round, (round_ + 1) * params.per_round)


def _beats(cost, disparity, best_cost, best_disparity, out):
    """Where (cost, disparity) beats the best pair: a lower cost, or an equal cost with a
    lower disparity (into the bool array ``out``)."""
    np.equal(cost, best_cost, out=out)
    out &= np.less(disparity, best_disparity)
    out |= np.less(cost, best_cost)
    return out


class _Winner:
    """Running (best cost, best disparity) of a WTA, updated in place."""

    def __init__(self, cost, disparity):
        self.cost = cost
        self.disparity = disparity

    def update(self, cost, disparity, mask):
        """Take ``cost``/``disparity`` where the pair beats the winner (``mask``: scratch).

        A pair wins if its cost is lower, or equal with a lower disparity: the lowest
        disparity among equal costs, whatever the order of the visits.
        """
        _beats(cost, disparity, self.cost, self.disparity, mask)
        # The best cost is the minimum whichever equal candidate wins the tie.
        np.minimum(self.cost, cost, out=self.cost)
        np.copyto(self.disparity, disparity, where=mask)


def wta_partition(aggregated_costs, disparities):
    """WTA over one partition's aggregated costs, one array per disparity of ``disparities``.

    Returns (best cost, best disparity) arrays; the costs are copied, never kept.
    """
    winner = mask = None
    for d, costs in zip(disparities, aggregated_costs):
        if winner is None:
            winner = _Winner(costs.copy(), np.full(costs.shape, d, np.int16))
            mask = np.empty(costs.shape, dtype=bool)
            continue
        winner.update(costs, np.int16(d), mask)
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
    disparities d <= W - 1 - xr take part. Disparities may come in any order.
    """

    def __init__(self, shape, dtype=np.int64):
        self.best_cost = np.full(shape, np.iinfo(dtype).max, dtype=dtype)
        self.best_disparity = np.full(shape, np.iinfo(np.int16).max, dtype=np.int16)
        self._mask = np.empty(shape, dtype=bool)

    def update(self, aggregated_costs, d):
        width = aggregated_costs.shape[-1]
        winner = _Winner(self.best_cost[:, :width - d], self.best_disparity[:, :width - d])
        winner.update(aggregated_costs[:, d:], np.int16(d), self._mask[:, :width - d])
