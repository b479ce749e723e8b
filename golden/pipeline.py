"""The whole golden pipeline: left-referenced disparity map, bit for bit as the hardware.

Stages in hardware order: transformation, matching costs, aggregation, WTA per partition
(calculation stage), WTA across partitions (evaluation stage), left/right consistency check,
and the optional 3x3 median of the output (:mod:`.median`).
The image is processed in bands of rows (each with the aggregation's halo) whose cost
volume is bounded in size and computed a few rows at a time so that the working set stays
in cache; bands run in parallel threads (numpy releases the GIL). docs/golden-model.md
explains the choices; none of them changes a bit of the result.

With ``aggregation="sgm"`` the map is the semi-global pipeline's (:mod:`.sgm`): every
caller of :func:`disparity_map` (the commands, the co-simulation's reference) gets either
aggregation from the parameters alone.
"""

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .aggregation import aggregate
from .data import check_gray_pair
from .lr_check import DisparityResult, invalidate_border, lr_check
from .median import median3
from .matching_cost import cost_dtype, matching_costs, pixel_sums
from ..params import ParameterError
from . import sgm, subpixel
from .transform import transform
from .wta import RightWTA, evaluate_partitions, partition_disparities, wta_partition

__all__ = ["disparity_map", "DisparityResult"]


#: Bytes of transformed pixels per image that one cost computation reads: both images'
#: rows and the temporary stay cached while all D disparities reuse them, and the calls
#: are still large enough to hide numpy's per-call cost (fastest of 256 KiB .. 4 MiB on
#: teddy with ext-census 19x19).
_CHUNK_BYTES = 1 << 20
#: Upper bound of one band's cost volume (D x rows x W), per worker thread.
_VOLUME_BYTES = 1 << 24


def _band_rows(params, height, width, workers=2):
    """Output rows per band.

    As many as keep the band's cost volume below ``_VOLUME_BYTES`` (fewer bands recompute
    fewer halo rows), but at most a quarter of the rows per worker, so that the threads
    stay evenly loaded.
    """
    volume_row = params.disparities * width * np.dtype(cost_dtype(params)).itemsize
    rows = max(1, _VOLUME_BYTES // volume_row)
    return max(1, min(rows, -(-height // (4 * workers))))


def _chunk_rows(params, width):
    """Rows of one cost computation (see ``_CHUNK_BYTES``)."""
    return max(1, _CHUNK_BYTES // (max(1, params.transform_bits // 8) * width))


def _band_costs(left_t, right_t, params):
    """Matching costs of a band for every disparity: (D, rows, W) of ``cost_dtype``.

    Computed a few rows at a time for all disparities, so that the transformed rows are
    read from the cache D times instead of from memory.
    """
    dtype = cost_dtype(params)
    height, width = left_t.shape[-2:]
    volume = np.empty((params.disparities, height, width), dtype)
    step = _chunk_rows(params, width)
    for y0 in range(0, height, step):
        left, right = left_t[..., y0:y0 + step, :], right_t[..., y0:y0 + step, :]
        sums = pixel_sums(left, right, params, dtype)
        for d in range(params.disparities):
            matching_costs(left, right, d, params, out=volume[d, y0:y0 + step], sums=sums)
    return volume


def _match_band(left_t, right_t, params, band, rows):
    """Raw left and right maps of the output rows ``rows`` of the image rows ``band``."""
    volume = _band_costs(left_t[..., band[0]:band[1], :], right_t[..., band[0]:band[1], :],
                         params)
    scratch = np.empty(volume.shape[1:], volume.dtype)
    aggregated = np.empty((rows[1] - rows[0], volume.shape[2]), volume.dtype)
    right_wta = RightWTA(aggregated.shape, volume.dtype)
    partition_results = []
    for round_ in range(params.rounds):
        disparities = partition_disparities(params, round_)

        def partition_costs():
            for d in disparities:
                summed = aggregate(volume[d], params.aggregation, rows, out=aggregated,
                                   scratch=scratch)
                right_wta.update(summed, d)
                yield summed

        partition_results.append(wta_partition(partition_costs(), disparities))
    best = evaluate_partitions(partition_results)
    if not params.subpixel_bits:
        return best, right_wta.best_disparity, None
    # The winners' neighbours: S once more, now that the winners are known.
    neighbours = subpixel.NeighbourCosts(best)
    for d in range(params.disparities):
        neighbours.update(aggregate(volume[d], params.aggregation, rows, out=aggregated,
                                    scratch=scratch), d)
    return best, right_wta.best_disparity, neighbours.values(params.disparities,
                                                             params.subpixel_bits)


def disparity_map(left, right, params, threads=None):
    """Disparity of every left pixel, INVALID (-1) where none is reported.

    Parameters
    ----------
    left, right : (H, W) uint8
        Rectified gray images; the left one is the reference.
    params : StereoParams
        Configuration; its width/height, when set, must match the images. With
        ``params.is_sgm`` the semi-global pipeline (:func:`.sgm.disparity_map` with the
        parameters' penalties) computes the map.
    threads : int, optional
        Worker threads (numpy releases the GIL); default one per core.

    Returns
    -------
    DisparityResult
    """
    left, right = np.asarray(left), np.asarray(right)
    check_gray_pair(left, right)
    height, width = left.shape
    if params.width is not None and (params.width, params.height) != (width, height):
        raise ParameterError(
            f"images are {width}x{height} but the configuration is for "
            f"{params.width}x{params.height}")
    params = params.with_size(width, height)
    if params.is_sgm:
        return _filtered(sgm.disparity_map(left, right, params, params.p1, params.p2,
                                           adapt=params.p2_adapt or None, threads=threads),
                         params)
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
    result = DisparityResult(invalidate_border(checked, params), raw_left, raw_right)
    if params.subpixel_bits:
        # The fraction first: the median (as in hardware) takes the output values.
        result = subpixel.with_fraction(result, np.concatenate([r[2] for r in results]),
                                        params.subpixel_bits)
    return _filtered(result, params)


def _filtered(result, params):
    """``result`` with the 3x3 median of its checked map when ``params.median`` (the raw
    maps unchanged: they are what the check compared)."""
    if not params.median:
        return result
    return DisparityResult(median3(result.disparity), result.left, result.right)
