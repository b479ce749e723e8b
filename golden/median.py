"""The 3x3 median of the output map (``StereoParams.median``), bit for bit as the hardware.

docs/semantics.md, "3x3 median": the last step of both pipelines, after the L/R check and
the invalid border. For each pixel the window is its 3x3 neighbourhood, pixels outside the
frame counting as invalid. With n the number of valid disparities in the window, the
result is the lower median of those n values (the ((n + 1) // 2)-th smallest) when the
centre is valid or n >= 5, and invalid otherwise. So an isolated outlier takes its
neighbours' value, a pixel the check rejected is filled when most of its window is valid,
and no pixel becomes valid from fewer than five valid neighbours. docs/sgm.md ("Quality
options") has the measurements that chose this form over the plain median of nine (invalid
as the smallest value) and over a median that leaves invalid pixels invalid.
"""

import numpy as np

from ..params import MEDIAN_FILL
from .lr_check import INVALID

__all__ = ["median3"]


def median3(disparity):
    """The 3x3 median of an (H, W) map, ``INVALID`` (-1) for invalid: (H, W) int16.

    Invalid values sort before every disparity, so with k invalid values in the window the
    lower median of the valid ones is the ((8 + k) // 2)-th of the sorted nine (from 0).
    """
    disparity = np.asarray(disparity)
    height, width = disparity.shape
    padded = np.full((height + 2, width + 2), INVALID, np.int16)
    padded[1:-1, 1:-1] = np.where(disparity < 0, INVALID, disparity)
    window = np.sort(np.stack([padded[i:i + height, j:j + width]
                               for i in range(3) for j in range(3)]), axis=0)
    invalid = (window < 0).sum(axis=0)
    lower = np.take_along_axis(window, ((8 + invalid) // 2)[None], axis=0)[0]
    keep = (invalid < 9) & ((disparity >= 0) | (9 - invalid >= MEDIAN_FILL))
    return np.where(keep, lower, INVALID).astype(np.int16)
