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
from .matching_cost import cost_dtype, matching_costs
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


def _band_rows(params, height, width, workers=2):
    """Output rows per band.

    About 1 MiB of transformed pixels per image keeps a band's per-disparity temporaries in
    the L2/L3 caches; at least 16 rows per aggregation radius keeps the halo rows (whose
    costs every band recomputes) cheap; at most a quarter of the rows per worker keeps
    the threads evenly loaded.
    """
    bytes_per_row = max(1, params.transform_bits // 8) * width
    rows = max((1 << 20) // bytes_per_row, 16 * params.agg_radius, 1)
    return max(1, min(rows, -(-height // (4 * workers))))


def _match_band(left_t, right_t, params, band, rows):
    """Raw left and right maps of the output rows ``rows`` of the image rows ``band``."""
    left_t, right_t = left_t[..., band[0]:band[1], :], right_t[..., band[0]:band[1], :]
    dtype = cost_dtype(params)
    shape = left_t.shape[-2:]
    width = shape[1]
    costs, scratch = np.empty(shape, dtype), np.empty(shape, dtype)
    aggregated = np.empty((rows[1] - rows[0], width), dtype)
    if params.transform == "ext-census":
        left_sums = np.add.reduce(left_t, axis=0, dtype=dtype)
        right_sums = np.add.reduce(right_t, axis=0, dtype=dtype)
        totals = np.empty(shape, dtype)
    right_wta = RightWTA(aggregated.shape, dtype)
    partition_results = []
    for k in range(params.rounds):
        first = k * params.per_round

        def partition_costs():
            for d in range(first, first + params.per_round):
                extra = {}
                if params.transform == "ext-census":
                    extra["totals"] = np.add(left_sums[:, d:], right_sums[:, :width - d],
                                             out=totals[:, :width - d])
                cost = matching_costs(left_t, right_t, d, params, out=costs, **extra)
                summed = aggregate(cost, params.aggregation, rows, out=aggregated,
                                   scratch=scratch)
                right_wta.update(summed, d)
                yield summed

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
    threads : int, optional
        Worker threads (numpy releases the GIL); default one per core.

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
    workers = threads or os.cpu_count() or 1
    with ThreadPoolExecutor(max_workers=workers) as pool:
        left_t, right_t = pool.map(lambda image: transform(image, params), (left, right))

    step = _band_rows(params, height, width, workers)
    a = params.agg_radius
    jobs = []
    for y0 in range(0, height, step):
        y1 = min(height, y0 + step)
        band = (max(0, y0 - a), min(height, y1 + a))
        jobs.append((band, (y0 - band[0], y1 - band[0])))
    with ThreadPoolExecutor(max_workers=min(workers, len(jobs))) as pool:
        results = list(pool.map(lambda job: _match_band(left_t, right_t, params, *job), jobs))
    raw_left = np.concatenate([r[0] for r in results])
    raw_right = np.concatenate([r[1] for r in results])

    checked = raw_left if params.lr_threshold is None else lr_check(
        raw_left, raw_right, params.lr_threshold)
    return DisparityResult(invalidate_border(checked, params), raw_left, raw_right)
