"""The whole golden pipeline: left-referenced disparity map, bit for bit as the hardware.

Stages in hardware order: transformation, matching costs, aggregation, WTA per partition
(calculation stage), WTA across partitions (evaluation stage), left/right consistency check.
The image is processed in bands of rows (each with the aggregation's halo) so that the
working set stays in cache; bands run in parallel threads (numpy releases the GIL).
"""

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .aggregation import aggregate
from .lr_check import invalidate_border, lr_check
from .matching_cost import matching_costs
from .params import ParameterError
from .transform import transform
from .wta import RightWTA, evaluate_partitions, wta_partition

__all__ = ["disparity_map", "DisparityResult"]


class DisparityResult:
    """Left map after all checks (``disparity``) and the raw maps the check compared."""

    def __init__(self, disparity, left, right):
        self.disparity = disparity
        self.left = left
        self.right = right


def _band_rows(params, height, width):
    """Rows per band: about 1 MiB of transformed pixels per image."""
    bytes_per_row = max(1, params.transform_bits // 8) * width
    return max(4, min(height, (1 << 20) // bytes_per_row))


def _match_band(left_t, right_t, params, band, rows):
    partition_results = []
    right_wta = RightWTA((rows[1] - rows[0], left_t.shape[-1]))
    for k in range(params.rounds):
        first = k * params.per_round

        def partition_costs():
            for d in range(first, first + params.per_round):
                costs = matching_costs(left_t[..., band[0]:band[1], :],
                                       right_t[..., band[0]:band[1], :], d, params)
                aggregated = aggregate(costs, params.aggregation, rows)
                right_wta.update(aggregated, d)
                yield aggregated

        partition_results.append(wta_partition(partition_costs(), first))
    return evaluate_partitions(partition_results), right_wta.best_disparity


def _check_images(left, right):
    for name, image in (("left", left), ("right", right)):
        if image.ndim != 2 or image.dtype != np.uint8:
            raise ParameterError(
                f"{name} image must be 8-bit gray (2-D uint8), not {image.dtype} {image.shape}")
    if left.shape != right.shape:
        raise ParameterError(
            f"left and right images must have the same size, not {left.shape[1]}x"
            f"{left.shape[0]} and {right.shape[1]}x{right.shape[0]}")


def disparity_map(left, right, params, threads=None):
    """Disparity of every left pixel, INVALID (-1) where none is reported.

    Parameters
    ----------
    left, right : (H, W) uint8
        Rectified gray images; the left one is the reference.
    params : StereoParams
        Configuration; its width/height, when set, must match the images.

    Returns
    -------
    DisparityResult
    """
    left, right = np.asarray(left), np.asarray(right)
    _check_images(left, right)
    height, width = left.shape
    if params.width is not None and (params.width, params.height) != (width, height):
        raise ParameterError(
            f"images are {width}x{height} but the configuration is for "
            f"{params.width}x{params.height}")
    params = params.with_size(width, height)
    left_t, right_t = transform(left, params), transform(right, params)

    step = _band_rows(params, height, width)
    a = params.agg_radius
    jobs = []
    for y0 in range(0, height, step):
        y1 = min(height, y0 + step)
        band = (max(0, y0 - a), min(height, y1 + a))
        jobs.append((band, (y0 - band[0], y1 - band[0])))
    workers = threads or min(len(jobs), os.cpu_count() or 1)
    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(lambda job: _match_band(left_t, right_t, params, *job), jobs))
    raw_left = np.concatenate([r[0] for r in results])
    raw_right = np.concatenate([r[1] for r in results])

    checked = raw_left if params.lr_threshold is None else lr_check(
        raw_left, raw_right, params.lr_threshold)
    return DisparityResult(invalidate_border(checked, params), raw_left, raw_right)
