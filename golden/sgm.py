"""Semi-global aggregation (SGM) along the raster-order paths, bit-exact integers.

An aggregation choice beside the A x A box of :mod:`.aggregation`: the matching costs C of
any transform are aggregated along the paths a raster-order stream can compute
(``params.SGM_PATHS``: left, top-left, top, top-right) with integer penalties P1, P2
(optionally P2 adapted to the intensity step along the path), normalised by the previous
pixel's minimum, and summed; the left path takes its large step from the tracked reference
of the disparity best K positions back (``params.SGM_TRACK_AGE``, ``SGM_TRACK_STEPS``).
Optionally (``StereoParams.fifth_path``) a fifth path, right to left along the row, is the
left path's code run on the mirrored row. The summed costs S then go through the same WTA and
right-referenced map as the box pipeline. docs/semantics.md ("Semi-global aggregation") is
the exact contract; every function here computes it bit for bit with integer numpy
arithmetic (no floats anywhere). The paths, the rules of the parameters (P1, P2, t), the
recommended configurations and the widths they imply are defined once, in
:mod:`npstereo.params`, for this model, the command line and the hardware alike;
``golden.pipeline.disparity_map`` calls :func:`disparity_map` when
``StereoParams.aggregation`` is ``"sgm"``.

Array layout: cost volumes are (H, W, D), disparity last, so that the minimum over d and
the d - 1 / d + 1 neighbours of the recurrence are contiguous operations.
"""

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ..params import (SGM_LEFT_P1_PARITY, SGM_PATH_STEPS, SGM_PATHS, SGM_ROW_PATHS,
                      SGM_TRACK_AGE, SGM_TRACK_STEPS, ParameterError, StereoParams,
                      check_penalties, check_sgm_paths)
from .cost_term import add_cost_term
from .data import check_gray_pair
from .lr_check import INVALID, DisparityResult, lr_check
from .matching_cost import cost_dtype, matching_costs, pixel_sums
from .subpixel import fit_volume, with_fraction
from .transform import transform

__all__ = ["cost_volume", "path_p2", "path_costs", "right_path_p2", "right_path_costs",
           "aggregate", "winners",
           "disparity_from_summed", "disparity_map"]

#: Elements of one band's cost volume in :func:`disparity_map` (rows x W x D): 4 Mi, a few
#: MiB per band volume, so that memory stays bounded for any frame size while the left
#: path's loop over x still handles many rows per numpy call.
_BAND_ELEMENTS = 1 << 22

#: The fifth path's key among :func:`disparity_map`'s paths (not one of
#: ``params.SGM_PATHS``: a raster-order stream cannot compute it as those).
_FIFTH = "right"


def _dtype(max_cost, p2, fifth_path=False):
    """The narrowest unsigned dtype holding every intermediate and S with room to spare.

    Room to spare: the right-referenced map pads with the dtype's maximum, which must be
    larger than every real S. S <= (K Cmax + P2) + 3 (Cmax + P2), one more K Cmax + P2
    with the fifth path (docs/semantics.md, "Widths"); the unnormalised left path has a
    dtype of its own (:func:`_left_band`).
    """
    along = 2 if fifth_path else 1
    largest = max(max_cost + 2 * p2,
                  along * (SGM_TRACK_AGE * max_cost + p2)
                  + len(SGM_ROW_PATHS) * (max_cost + p2)) + 1
    return _fitting(largest)


def _fitting(largest):
    """The narrowest unsigned dtype that holds ``largest``."""
    for dtype in (np.uint16, np.uint32, np.uint64):
        if largest <= np.iinfo(dtype).max:
            return dtype
    raise ParameterError(f"SGM costs up to {largest} do not fit 64 bits")  # pragma: no cover


def cost_volume(left, right, params, dtype=None, threads=None):
    """Matching costs C(x, y, d) of two gray images for SGM: (H, W, D).

    The transform and matching cost are the box pipeline's (golden/transform.py,
    golden/matching_cost.py, unchanged), plus ``params.cost_term`` if any
    (:mod:`.cost_term`). One rule differs: where x - d < 0 the pair does not exist and
    C = Cmax (the box pipeline uses 0), so that a path crossing the left border is not
    drawn towards disparities that have no partner pixel.

    Parameters
    ----------
    left, right : (H, W) uint8
    params : StereoParams
        transform, block and disparities are used.
    dtype : numpy dtype, optional
        Of the result; default uint16 when Cmax fits it.
    threads : int, optional
        Threads for the two transforms.
    """
    left_t, right_t = _transforms(left, right, params, threads)
    if dtype is None:
        dtype = np.uint16 if params.max_cost <= np.iinfo(np.uint16).max else np.uint32
    return add_cost_term(_costs_disparity_last(left_t, right_t, params, dtype), left, right,
                         params)


def _transforms(left, right, params, threads):
    """The transformed left and right images (computed in parallel)."""
    images = (np.asarray(left, np.uint8), np.asarray(right, np.uint8))
    with ThreadPoolExecutor(max_workers=threads or 2) as pool:
        return list(pool.map(lambda image: transform(image, params), images))


def _costs_disparity_last(left_t, right_t, params, dtype):
    """C of a band of transformed rows (last two axes rows, W): (rows, W, D) of ``dtype``,
    disparity last (the box pipeline's band volumes are (D, rows, W))."""
    height, width = left_t.shape[-2:]
    volume = np.empty((height, width, params.disparities), dtype)
    # matching_costs wants an output of the box pipeline's cost dtype, which is wide enough
    # for every C (it holds A*A*Cmax).
    scratch = None
    sums = pixel_sums(left_t, right_t, params, cost_dtype(params))
    for d in range(params.disparities):
        scratch = matching_costs(left_t, right_t, d, params, out=scratch, sums=sums)
        volume[:, :, d] = scratch
        volume[:, :min(d, width), d] = params.max_cost
    return volume


def path_p2(guide, path, p1, p2, adapt=None):
    """Per-pixel P2 of one path: (H, W) int64.

    Constant P2 when ``adapt`` is None. Otherwise, with g = |I(p) - I(p - r)| the 8-bit
    intensity step from the predecessor along the path, s = max(0, bitlen(g) - t) and
    P2(p) = max(P1, P2 >> s): P2 is halved for every doubling of the step beyond 2^(t-1),
    a power-of-two version of Hirschmueller's P2 / g built from compares and a shift. At
    pixels without a predecessor the value is unused; it is defined as P2 there.
    """
    guide = np.asarray(guide)
    height, width = guide.shape
    out = np.full((height, width), p2, dtype=np.int64)
    if adapt is None:
        return out
    dx, dy = SGM_PATH_STEPS[path]
    image = guide.astype(np.int64)
    # Pixels with a predecessor: y + dy >= 0 and 0 <= x + dx < W.
    ys = slice(max(0, -dy), height)
    xs = slice(max(0, -dx), width - max(0, dx))
    prev = image[max(0, -dy) + dy:height + dy, xs.start + dx:xs.stop + dx]
    step = np.abs(image[ys, xs] - prev)
    # bitlen(g) for g in 0..255 without floats: count the thresholds 2^k <= g.
    bits = np.zeros(step.shape, dtype=np.int64)
    for k in range(8):
        bits += step >= (1 << k)
    shift = np.maximum(0, bits - adapt)
    out[ys, xs] = np.maximum(p1, p2 >> shift)
    return out


def _step(costs, previous, p1, p2, out, scratch):
    """One step of the recurrence for a batch of pixels: (N, D) arrays, p2 (N, 1).

    L(p, d) = C(p, d) + min(L(p-r, d), L(p-r, d-1) + P1, L(p-r, d+1) + P1, m + P2) - m
    with m = min_k L(p-r, k); the neighbours d-1 and d+1 outside 0 .. D-1 do not exist.
    The minimum is taken first (it is >= m), so every unsigned intermediate is exact.
    """
    minimum = previous.min(axis=1, keepdims=True)
    np.copyto(scratch, previous)
    if previous.shape[1] > 1:
        np.minimum(scratch[:, 1:], previous[:, :-1] + p1, out=scratch[:, 1:])
        np.minimum(scratch[:, :-1], previous[:, 1:] + p1, out=scratch[:, :-1])
    np.minimum(scratch, minimum + p2, out=scratch)
    scratch -= minimum
    np.add(costs, scratch, out=out)


def path_costs(volume, path, p1, p2, guide=None, adapt=None, max_cost=None):
    """L_r(p, d) of one path over the whole image: (H, W, D) like ``volume``.

    Parameters
    ----------
    volume : (H, W, D) unsigned ndarray
        Matching costs C, e.g. from :func:`cost_volume`, each <= ``max_cost``.
    path : str
        One of ``params.SGM_PATHS``.
    p1, p2 : int
        Penalties (validated against ``max_cost`` by ``params.check_penalties``).
    guide : (H, W) uint8, optional
        Left gray image; required when ``adapt`` is set.
    adapt : int or None
        Adaptive-P2 threshold exponent (see :func:`path_p2`).
    max_cost : int, optional
        Cmax; default the volume's maximum (the widths depend on it).

    Returns
    -------
    ndarray
        L_r in a dtype wide enough for every intermediate (see :func:`_dtype`). Pixels
        whose predecessor lies outside the image start fresh: L_r(p, d) = C(p, d).
    """
    if path not in SGM_PATH_STEPS:
        raise ParameterError(f"SGM path must be one of {', '.join(SGM_PATHS)}, not {path!r}")
    volume = np.asarray(volume)
    if volume.ndim != 3:
        raise ParameterError(f"cost volume must be (H, W, D), not of shape {volume.shape}")
    height, width, _ = volume.shape
    largest = int(volume.max()) if volume.size else 0
    if max_cost is None:
        max_cost = largest
    check_penalties(max_cost, p1, p2, adapt)
    # The widths (and the dtype below) are derived from Cmax: a larger cost would break them.
    if largest > max_cost:
        raise ParameterError(f"matching costs must be <= Cmax = {max_cost}, not {largest}")
    if adapt is not None and guide is None:
        raise ParameterError("adaptive P2 needs the left gray image as guide")
    if guide is not None and np.shape(guide) != (height, width):
        raise ParameterError(f"guide image must be {width}x{height}, not of shape "
                             f"{np.shape(guide)}")
    dtype = _dtype(max_cost, p2)
    costs = volume.astype(dtype, copy=False)
    p1 = dtype(p1)
    p2_map = path_p2(guide if guide is not None else np.zeros((height, width), np.uint8),
                     path, int(p1), p2, adapt).astype(dtype)
    out = np.empty_like(costs)
    # params.sgm_path_steps admits no path with dy = 0 but the left one.
    dx, dy = SGM_PATH_STEPS[path]
    if dy == 0:
        return _left_band(costs, p1, p2_map, out)
    return _row_band(costs, dx, p1, p2_map, None, out)


def _left_band(costs, p1, p2_map, out):
    """The left path over a band of rows (each row is independent): writes ``out``.

    docs/semantics.md, "The left path": the unnormalised path cost Lu in exact integers,

        Lu(x, d) = C(x, d) + min(Lu(x-1, d), Lu(x-1, d +- 1) + P1, ref(x) + P2(x)),

    the P1 candidates only into columns x % 2 == ``SGM_LEFT_P1_PARITY``, ref(x) from :func:`_tracked_reference`, and L(x, d) = Lu(x, d) - min_d Lu(x-1, d)
    (L = Lu = C at x = 0). The recurrence runs along x, every row of the band at once;
    column-major copies make each step's (rows, D) slices contiguous.
    """
    width, disparities = costs.shape[1], costs.shape[2]
    # Lu grows along the row: Lu(x, .) <= m(x-1) + K Cmax + P2 and m(x) <= m(x-1) + Cmax.
    top = int(costs.max()) if costs.size else 0
    wide = _fitting((width + SGM_TRACK_AGE + 1) * top + 2 * int(p2_map.max(initial=0))
                    + int(p1))
    costs_t = np.ascontiguousarray(costs.transpose(1, 0, 2), dtype=wide)
    p2_t = np.ascontiguousarray(p2_map.T, dtype=wide)
    p1 = wide(p1)
    path = np.empty_like(costs_t)
    path[0] = costs_t[0]  # x = 0: fresh start
    index = np.arange(costs_t.shape[1])
    best = np.empty(costs_t.shape[:2], np.intp)     # argmin_d Lu(x, d), ties to the lowest
    minima = np.empty(costs_t.shape[:2], wide)      # min_d Lu(x, d)
    best[0] = path[0].argmin(axis=1)
    minima[0] = path[0, index, best[0]]
    scratch = np.empty_like(costs_t[0])
    for x in range(1, width):
        previous = path[x - 1]
        np.copyto(scratch, previous)
        if disparities > 1 and x % 2 == SGM_LEFT_P1_PARITY:
            np.minimum(scratch[:, 1:], previous[:, :-1] + p1, out=scratch[:, 1:])
            np.minimum(scratch[:, :-1], previous[:, 1:] + p1, out=scratch[:, :-1])
        reference = _tracked_reference(path, costs_t, best, x, index)
        np.minimum(scratch, (reference + p2_t[x])[:, None], out=scratch)
        np.add(costs_t[x], scratch, out=path[x])
        best[x] = path[x].argmin(axis=1)
        minima[x] = path[x, index, best[x]]
    path[1:] -= minima[:-1, :, None]
    out[...] = path.transpose(1, 0, 2)
    return out


def right_path_p2(guide, p1, p2, adapt=None):
    """P2 of the fifth path (right to left along the row) as (H, W) int64: the left path's
    rule on |I(x) - I(x + 1)|, i.e. the left path's P2 of the mirrored image, mirrored."""
    mirrored = np.asarray(guide)[:, ::-1]
    return path_p2(mirrored, "left", p1, p2, adapt)[:, ::-1]


def right_path_costs(volume, p1, p2, guide=None, adapt=None, max_cost=None):
    """L of the fifth path over the whole image: (H, W, D) like :func:`path_costs`.

    docs/semantics.md, "The fifth path": the left path (tracked reference and all) run on
    every row mirrored, x' = W - 1 - x, with P2 from :func:`right_path_p2`; so the
    predecessor of (x, y) is (x + 1, y) and the row's last column starts fresh. Parameters
    as :func:`path_costs`.
    """
    volume = np.asarray(volume)
    mirrored = volume[:, ::-1] if volume.ndim == 3 else volume
    flipped_guide = None if guide is None else np.asarray(guide)[:, ::-1]
    # path_costs checks every argument, and its left path is the one computation of the
    # recurrence; the mirrored P2 it builds from the mirrored guide is right_path_p2's.
    return path_costs(mirrored, "left", p1, p2, flipped_guide, adapt, max_cost)[:, ::-1]


def _right_band(costs, p1, p2_right, out):
    """The fifth path over a band of rows: the left path of the mirrored rows (``p2_right``
    in image order, from :func:`right_path_p2`), written into ``out`` in image order."""
    _left_band(costs[:, ::-1], p1, p2_right[:, ::-1], out[:, ::-1])
    return out


def _tracked_reference(path, costs, best, x, index):
    """ref(x) of the left path for every row of a band: (rows,).

    The path cost of b = argmin_d Lu(max(x - K, 0), d) at s = max(x - J, 0), carried to
    x - 1 along disparity b: Lu(s, b) + sum over s < i < x of C(i, b). ``path`` holds Lu
    and ``costs`` C as (W, rows, D), ``best`` the argmin of every column so far.
    """
    chosen = best[max(x - SGM_TRACK_AGE, 0)]
    since = max(x - SGM_TRACK_STEPS, 0)
    reference = path[since, index, chosen].copy()
    for i in range(since + 1, x):
        reference += costs[i, index, chosen]
    return reference


def _row_band(costs, dx, p1, p2_map, previous, out):
    """A path from the row above (dy = -1, predecessor column x + dx) over a band of rows.

    ``previous`` is L of the image row just above the band, or None when the band starts
    at the top of the image (y = 0: fresh start). The recurrence runs along y, every
    column of a row at once; the predecessor row is the previous output row shifted by dx.
    """
    rows, width = costs.shape[:2]
    x0, x1 = max(0, -dx), width - max(0, dx)  # columns that have a predecessor
    scratch = np.empty_like(costs[0, x0:x1])
    for y in range(rows):
        above = out[y - 1] if y else previous
        if above is None:
            out[y] = costs[y]
            continue
        # The column whose predecessor is outside the image starts fresh.
        out[y, :x0] = costs[y, :x0]
        out[y, x1:] = costs[y, x1:]
        _step(costs[y, x0:x1], above[x0 + dx:x1 + dx], p1, p2_map[y, x0:x1, None],
              out[y, x0:x1], scratch)
    return out


def aggregate(volume, p1, p2, paths=SGM_PATHS, guide=None, adapt=None, max_cost=None,
              threads=None, fifth_path=False):
    """S(p, d): the sum of L_r over ``paths``, and of the fifth path's L with
    ``fifth_path``. (H, W, D) unsigned.

    Parameters are those of :func:`path_costs`; ``threads`` computes paths in parallel
    (numpy releases the GIL; the sum does not depend on it).
    """
    volume = np.asarray(volume)
    if max_cost is None:
        max_cost = int(volume.max()) if volume.size else 0
    check_penalties(max_cost, p1, p2, adapt)
    check_sgm_paths(paths)
    workers = max(1, min(len(paths), threads or os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        parts = list(pool.map(lambda path: path_costs(volume, path, p1, p2, guide, adapt,
                                                      max_cost), paths))
        if fifth_path:
            parts.append(right_path_costs(volume, p1, p2, guide, adapt, max_cost))
    summed = parts[0].astype(_dtype(max_cost, p2, fifth_path))
    for part in parts[1:]:
        summed += part
    return summed


def winners(summed):
    """Left and right raw maps from S: argmin with ties to the lowest disparity.

    dL(x, y) = argmin_d S(x, y, d); dR(xr, y) = argmin over d <= min(D-1, W-1-xr) of
    S(xr + d, y, d), the box pipeline's definition. Returns two (H, W) int16 arrays.
    """
    summed = np.asarray(summed)
    height, width, disparities = summed.shape
    left = np.argmin(summed, axis=2).astype(np.int16)  # argmin keeps the first (lowest) d
    # Right map: pad D columns with a value above every S, then view the padded volume
    # with V[y, xr, d] = S[y, xr + d, d] (stride of x plus stride of d along d).
    padded = np.full((height, width + disparities, disparities), np.iinfo(summed.dtype).max,
                     summed.dtype)
    padded[:, :width] = summed
    sy, sx, sd = padded.strides
    diagonal = np.lib.stride_tricks.as_strided(padded, (height, width, disparities),
                                               (sy, sx, sx + sd), writeable=False)
    right = np.argmin(diagonal, axis=2).astype(np.int16)
    return left, right


def disparity_from_summed(summed, lr_threshold):
    """The final map from S: WTA, L/R check (threshold or None), columns x < D invalid."""
    raw_left, raw_right = winners(summed)
    return _checked(raw_left, raw_right, summed.shape[2], lr_threshold)


def _checked(raw_left, raw_right, disparities, lr_threshold):
    """DisparityResult of the raw maps: L/R check (threshold or None), x < D invalid."""
    checked = raw_left if lr_threshold is None else lr_check(raw_left, raw_right, lr_threshold)
    checked = checked.astype(np.int16, copy=True)
    checked[:, :disparities] = INVALID
    return DisparityResult(checked, raw_left, raw_right)


def disparity_map(left, right, params, p1, p2, paths=SGM_PATHS, adapt=None, threads=None):
    """Disparity map of the SGM pipeline, INVALID (-1) where none is reported.

    Parameters
    ----------
    left, right : (H, W) uint8
        Rectified gray images; the left one is the reference.
    params : StereoParams
        transform, block, disparities, lr_threshold, subpixel_bits and fifth_path are
        used. ``aggregation`` and the
        parameters' own penalties are not: they are the arguments below, so that tests and
        sweeps can vary them on any configuration (``golden.pipeline.disparity_map`` passes
        an SGM configuration's own). ``rounds`` does not change the result (ties go to the
        lowest disparity whatever the partitioning, as in the box pipeline).
    p1, p2 : int
        Penalties, 0 <= P1 <= P2 <= ``max_path_penalty(params.max_cost)``.
    paths : sequence of str
        Subset of ``params.SGM_PATHS`` to sum.
    adapt : int or None
        Adaptive-P2 threshold exponent t (1 .. 7), None for a constant P2.
    threads : int, optional
        Worker threads (paths run in parallel).

    Returns
    -------
    DisparityResult
        ``disparity`` after the check and the border rule, ``left``/``right`` raw maps.
    """
    if not isinstance(params, StereoParams):
        raise ParameterError("params must be a StereoParams")
    left, right = np.asarray(left), np.asarray(right)
    check_gray_pair(left, right)
    check_penalties(params.max_cost, p1, p2, adapt)
    check_sgm_paths(paths)
    paths = tuple(paths)
    height, width = left.shape
    dtype = _dtype(params.max_cost, p2, params.fifth_path)
    left_t, right_t = _transforms(left, right, params, threads)
    p2_maps = {path: path_p2(left, path, p1, p2, adapt).astype(dtype) for path in paths}
    if params.fifth_path:
        p2_maps[_FIFTH] = right_path_p2(left, p1, p2, adapt).astype(dtype)
        paths += (_FIFTH,)
    p1 = dtype(p1)
    # Bands of rows bound the memory (a few band volumes instead of several image volumes);
    # the paths from above carry their last row from one band into the next, the left
    # path and the winners work row by row anyway, so bands change no bit of the result.
    rows = max(1, _BAND_ELEMENTS // (width * params.disparities))
    previous = {path: None for path in paths if path in SGM_ROW_PATHS}
    raw_left, raw_right, fitted = [], [], []
    workers = max(1, min(len(paths), threads or os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for y0 in range(0, height, rows):
            y1 = min(height, y0 + rows)
            costs = add_cost_term(_costs_disparity_last(left_t[..., y0:y1, :],
                                                        right_t[..., y0:y1, :], params, dtype),
                                  left, right, params, (y0, y1))

            def one_path(path):
                out = np.empty_like(costs)
                if path == _FIFTH:
                    return _right_band(costs, p1, p2_maps[path][y0:y1], out)
                if path not in SGM_ROW_PATHS:
                    return _left_band(costs, p1, p2_maps[path][y0:y1], out)
                return _row_band(costs, SGM_PATH_STEPS[path][0], p1, p2_maps[path][y0:y1],
                                 previous[path], out)

            parts = list(pool.map(one_path, paths))
            for path, part in zip(paths, parts):
                if path in SGM_ROW_PATHS:
                    previous[path] = part[-1].copy()
            summed = parts[0]
            for part in parts[1:]:
                summed += part
            band_left, band_right = winners(summed)
            raw_left.append(band_left)
            raw_right.append(band_right)
            if params.subpixel_bits:
                fitted.append(fit_volume(summed, band_left, params.subpixel_bits))
    result = _checked(np.concatenate(raw_left), np.concatenate(raw_right), params.disparities,
                      params.lr_threshold)
    if not params.subpixel_bits:
        return result
    return with_fraction(result, np.concatenate(fitted), params.subpixel_bits)
