"""The golden model on images: the disparity map of one pair, the degraded conditions the
paper measures under, and many configurations at once in worker processes."""

import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

from ..golden.data import to_gray
from ..golden.degrade import bayer_pair, gaussian_noise_pair
from ..golden.pipeline import disparity_map
from ..golden.subpixel import levels
from ..params import UserError

__all__ = ["match_images", "Condition", "condition_images", "run_jobs"]


def match_images(left, right, params, threads=None):
    """Disparity map (int16, -1 invalid; with F > 0 sub-pixel bits float32 levels, -1
    invalid) of two 8-bit images, colour converted to gray.

    Raises a UserError for images of different size or narrower than the disparity range
    (the golden model checks both).
    """
    result = disparity_map(to_gray(left), to_gray(right), params, threads=threads)
    return levels(result.disparity, params.subpixel_bits)


@dataclass(frozen=True)
class Condition:
    """How the input images are prepared: clean gray, gaussian noise and/or bayer stand-in.

    The bayer stand-in replaces the gray conversion (raw mosaic values are the gray image);
    noise, when given too, is added afterwards.
    """

    noise: float = 0.0
    bayer: bool = False
    gains: tuple = (1.0, 1.0, 1.0)
    read_noise: float = 0.0
    seed: int = 0

    @property
    def label(self):
        parts = []
        if self.bayer:
            gains = "" if self.gains == (1.0, 1.0, 1.0) else " gains " + "/".join(
                f"{g:g}" for g in self.gains)
            noise = f" read noise {self.read_noise:g}" if self.read_noise else ""
            parts.append(f"bayer{gains}{noise}")
        if self.noise:
            parts.append(f"noise {self.noise:g}")
        return ", ".join(parts) or "clean"


def condition_images(pair, condition):
    """The gray left/right images of ``pair`` under ``condition``."""
    if condition.bayer:
        left, right = bayer_pair(pair.left, pair.right, condition.gains, condition.read_noise,
                                 condition.seed)
    else:
        left, right = pair.gray()
    if condition.noise:
        # Independent of the bayer read noise: a different stream of the same seed.
        left, right = gaussian_noise_pair(left, right, condition.noise, condition.seed + 1)
    return left, right


def _job(key, left, right, params, threads):
    start = time.perf_counter()
    disparity = match_images(left, right, params, threads=threads)
    return key, disparity, time.perf_counter() - start


def _cost(params):
    """Rough relative run time, to start the slowest jobs first.

    SGM's four paths cost about as much as a 15 x 15 census transform (teddy: 1.1 s for
    census 7x7 SGM against 0.4 s for the census 9x9 box).
    """
    return params.spec.golden_weight * params.block * params.block + (225 if params.is_sgm else 0)


def run_jobs(jobs, jobs_n=1, desc="matching"):
    """Run ``{key: (left, right, params)}``; returns ``{key: (disparity, seconds)}``.

    With ``jobs_n`` > 1 the jobs run in that many processes, each single-threaded (the
    machine's cores are shared between the processes rather than oversubscribed).
    """
    if jobs_n < 1:
        raise UserError(f"--jobs must be an integer >= 1, not {jobs_n}")
    order = sorted(jobs, key=lambda key: -_cost(jobs[key][2]))
    # tqdm only here: ``npstereo match`` imports this module for match_images alone, and
    # every 10 ms counts against its matching time.
    from tqdm import tqdm
    results = {}
    with tqdm(total=len(order), desc=desc, unit="map", leave=False) as progress:
        if jobs_n == 1:
            for key in order:
                _, disparity, seconds = _job(key, *jobs[key], None)
                results[key] = (disparity, seconds)
                progress.update()
        else:
            threads = max(1, (os.cpu_count() or 1) // jobs_n)
            with ProcessPoolExecutor(max_workers=jobs_n) as pool:
                futures = [pool.submit(_job, key, *jobs[key], threads) for key in order]
                for future in as_completed(futures):
                    key, disparity, seconds = future.result()
                    results[key] = (disparity, seconds)
                    progress.update()
    return results
