"""Left/right consistency check, the invalid border of the disparity map, and the map
with the raw maps it was checked from (the result of the box and the SGM pipelines)."""

import numpy as np

__all__ = ["INVALID", "DisparityResult", "lr_check", "invalidate_border"]

#: Golden-model code of an invalid pixel (the hardware clears its valid flag instead).
INVALID = -1


class DisparityResult:
    """Left map after all checks (``disparity``) and the raw maps the check compared."""

    def __init__(self, disparity, left, right):
        self.disparity = disparity
        self.left = left
        self.right = right


def lr_check(left_disparity, right_disparity, threshold):
    """Keep d at x iff |dL(x) - dR(x - dL(x))| <= threshold; others become INVALID."""
    height, width = left_disparity.shape
    x = np.arange(width)[None, :]
    partner = x - left_disparity
    inside = partner >= 0
    rows = np.arange(height)[:, None]
    right_at_partner = right_disparity[rows, np.where(inside, partner, 0)]
    keep = inside & (np.abs(left_disparity - right_at_partner) <= threshold)
    return np.where(keep, left_disparity, INVALID).astype(np.int16)


def invalidate_border(disparity, params):
    """Columns without the full disparity range (x < params.first_valid_column) are INVALID."""
    out = disparity.astype(np.int16, copy=True)
    out[:, :params.first_valid_column] = INVALID
    return out
