"""Degradations the paper evaluates: gaussian noise and (a stand-in for) bayer-camera images.

Both are seeded so that every evaluation is reproducible; the left and right images get
independent noise drawn from one generator (left first).
"""

import numpy as np

from ..params import UserError

__all__ = ["gaussian_noise", "gaussian_noise_pair", "bayer_mosaic", "bayer_pair"]


def _quantise(values):
    """Clip to the 8-bit range and round to the nearest integer."""
    return np.clip(np.rint(values), 0, 255).astype(np.uint8)


def gaussian_noise(image, variance, rng):
    """Add zero-mean gaussian noise of ``variance`` on the [0, 1] intensity scale.

    As MATLAB's ``imnoise(I, 'gaussian', 0, variance)`` used by the paper (0.002): the
    standard deviation in 8-bit levels is 255 * sqrt(variance); the result is clipped and
    rounded back to uint8.
    """
    if not np.isfinite(variance) or variance < 0:
        raise UserError(f"noise variance must be a number >= 0, not {variance!r}")
    image = np.asarray(image, dtype=np.uint8)
    sigma = 255.0 * np.sqrt(variance)
    return _quantise(image + rng.normal(0.0, sigma, size=image.shape))


def gaussian_noise_pair(left, right, variance, seed):
    """Both images with independent noise from one seeded generator."""
    rng = np.random.default_rng(seed)
    return gaussian_noise(left, variance, rng), gaussian_noise(right, variance, rng)


def bayer_mosaic(image, gains=(1.0, 1.0, 1.0), read_noise=0.0, rng=None):
    """The raw RGGB mosaic of an RGB image, used directly as the gray image.

    Pixel (y, x) keeps one channel: R at (even, even), G at (even, odd) and (odd, even),
    B at (odd, odd), as a bayer camera delivers it without demosaicing. ``gains``
    multiply the R, G, B sites (an uncorrected sensor's white balance), ``read_noise`` is
    the standard deviation of gaussian sensor noise in 8-bit levels.

    Returns
    -------
    (H, W) uint8
    """
    image = np.asarray(image)
    if image.ndim != 3 or image.shape[2] < 3:
        raise UserError("the bayer stand-in needs colour (RGB) images, not gray ones")
    gains = tuple(float(g) for g in gains)
    if len(gains) != 3 or not all(np.isfinite(g) and g > 0 for g in gains):
        raise UserError(f"bayer gains must be three numbers > 0 (R G B), not {gains}")
    if not np.isfinite(read_noise) or read_noise < 0:
        raise UserError(f"bayer read noise must be a number >= 0, not {read_noise!r}")
    height, width = image.shape[:2]
    ys, xs = np.mgrid[0:height, 0:width]
    channel = np.where(ys % 2 == 0, np.where(xs % 2 == 0, 0, 1), np.where(xs % 2 == 0, 1, 2))
    raw = np.take_along_axis(image[..., :3], channel[..., None], axis=2)[..., 0]
    raw = raw * np.asarray(gains)[channel]
    if read_noise > 0:
        raw = raw + rng.normal(0.0, read_noise, size=raw.shape)
    return _quantise(raw)


def bayer_pair(left, right, gains=(1.0, 1.0, 1.0), read_noise=0.0, seed=0):
    """The bayer stand-in of a colour pair, with independent read noise per image."""
    rng = np.random.default_rng(seed)
    return (bayer_mosaic(left, gains, read_noise, rng),
            bayer_mosaic(right, gains, read_noise, rng))
