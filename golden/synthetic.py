"""A seeded synthetic stereo scene with exact integer ground truth.

The scene is a stack of textured layers, back to front: a background plane slanted in y
(its disparity grows by one every few rows), a fronto-parallel middle plane and a few
foreground rectangles and discs. Each layer has a disparity d(y) and a texture in its own
coordinates; the left view shows texture(y, x) and the right view shows the same layer point
at x - d, so every left pixel whose layer point is visible in the right view satisfies
``left[y, x] == right[y, x - d]`` exactly. Closer layers cover farther ones in each view
independently, which produces genuine occlusions. The ground truth is the disparity of the
front-most layer at every left pixel (occluded pixels keep their true disparity).
"""

import numpy as np

from .data import StereoPair
from ..params import UserError

__all__ = ["synthetic_pair", "DEFAULT_SIZE", "DEFAULT_DISPARITIES"]

#: Default scene for ``make demo`` and the tests: small enough to run in well under a second.
DEFAULT_SIZE = (160, 120)
DEFAULT_DISPARITIES = 32


def _texture(rng, height, width):
    """RGB texture: smooth blobs at several scales plus fine grain, stretched to 0..255.

    The coarse scales give every window a distinct intensity structure (so census and
    rank find the right match), the fine grain keeps flat-looking areas matchable.
    """
    total = np.zeros((height, width, 3))
    for cell, weight in ((16, 1.0), (8, 0.8), (4, 0.6), (2, 0.5), (1, 0.35)):
        grid = rng.random((height // cell + 2, width // cell + 2, 3))
        total += weight * np.repeat(np.repeat(grid, cell, axis=0), cell, axis=1)[:height, :width]
    total -= total.min()
    total *= 255.0 / max(total.max(), 1e-9)
    tint = rng.uniform(0.55, 1.0, size=3)
    return np.round(total * tint).astype(np.uint8)


def _layers(rng, width, height, disparities):
    """(mask(y, x) in left coordinates, disparity per row, texture) of each layer, back first."""
    top = disparities - 1
    ys, xs = np.mgrid[0:height, 0:width]
    layers = []
    # Background slanted in y: disparity rises from about D/8 to D/3 down the image.
    d_lo, d_hi = max(1, top // 8), max(2, top // 3)
    background_d = d_lo + (np.arange(height) * (d_hi - d_lo + 1)) // height
    layers.append((np.ones((height, width), bool), background_d))
    # Middle plane: a wide band across the image.
    y0, y1 = int(height * rng.uniform(0.15, 0.3)), int(height * rng.uniform(0.6, 0.8))
    x0 = int(width * rng.uniform(0.3, 0.45))
    layers.append(((ys >= y0) & (ys < y1) & (xs >= x0), np.full(height, max(3, top // 2))))
    # Foreground: rectangles and discs, closer than everything else.
    for i in range(3):
        d = max(4, top - 2 - 4 * i)
        cx, cy = rng.uniform(0.3, 0.9) * width, rng.uniform(0.2, 0.8) * height
        rx, ry = rng.uniform(0.06, 0.14) * width, rng.uniform(0.1, 0.2) * height
        if i % 2:
            mask = ((xs - cx) / rx) ** 2 + ((ys - cy) / ry) ** 2 <= 1
        else:
            mask = (np.abs(xs - cx) <= rx) & (np.abs(ys - cy) <= ry)
        layers.append((mask, np.full(height, d)))
    layers.sort(key=lambda layer: layer[1].max())
    return layers


def synthetic_pair(width=DEFAULT_SIZE[0], height=DEFAULT_SIZE[1],
                   disparities=DEFAULT_DISPARITIES, seed=0, name=None):
    """A seeded RGB stereo pair of a layered scene with exact integer ground truth.

    Parameters
    ----------
    width, height : int
        Image size.
    disparities : int
        Disparity range D the scene is made for: every true disparity is <= D - 1.
    seed : int
        Seed of the layout and the textures; equal seeds give identical pairs.

    Returns
    -------
    StereoPair
        RGB images and a float ground truth holding integers (never NaN).
    """
    for label, value, low in (("width", width, 8), ("height", height, 4),
                              ("disparities", disparities, 8)):
        if not isinstance(value, int) or value < low:
            raise UserError(f"synthetic scene {label} must be an integer >= {low}, not {value!r}")
    rng = np.random.default_rng(seed)
    left = np.zeros((height, width, 3), np.uint8)
    right = np.zeros_like(left)
    truth = np.zeros((height, width))
    rows = np.arange(height)[:, None]
    for mask, row_d in _layers(rng, width, height, disparities):
        # Right pixel xr shows the layer point at left coordinate xr + d(y), which may lie
        # beyond the left image: the texture and the mask extend d columns to the right
        # (the mask by repeating its last column, so the background stays complete).
        pad = int(row_d.max())
        texture = _texture(rng, height, width + pad)
        extended = np.concatenate([mask, np.repeat(mask[:, -1:], pad, axis=1)], axis=1)
        left[mask] = texture[:, :width][mask]
        truth[mask] = np.broadcast_to(row_d[:, None], mask.shape)[mask]
        source_x = np.arange(width)[None, :] + row_d[:, None]
        right_mask = extended[rows, source_x]
        right[right_mask] = texture[rows, source_x][right_mask]
    return StereoPair(name or f"synthetic-{width}x{height}-D{disparities}-s{seed}",
                      left, right, truth)
