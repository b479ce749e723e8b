"""Stereo pairs for the tests: one generator, small images made to produce ties.

Tests import :func:`stereo_pair`; nothing here depends on npstereo, so the golden model's
tests against ``tests/reference.py`` stay independent of it.
"""

import numpy as np

__all__ = ["KINDS", "stereo_pair"]

#: ``random``: uniform bytes; ``levels``: 3 gray levels (ties everywhere); ``flat``: constant
#: 4 x 4 tiles, some 0 like the padding; ``stripes``: period-3 columns (costs repeat every
#: 3 disparities); ``saturated``: only 0 and 255 (extreme ext. census bytes) -- each with the
#: right image the left one shifted by 1-4 columns per row and 10 % noise. ``layers``: a
#: textured plane at D/4, a nearer textured rectangle at D-2 and a flat band across the
#: bottom, the right image made from the layers' disparities (a scene with occlusions and
#: large tie areas); ``independent``: two unrelated random images.
KINDS = ("random", "levels", "flat", "stripes", "saturated", "layers", "independent")


def _layers(rng, height, width, disparities):
    texture = rng.integers(0, 256, (height, width + disparities), dtype=np.uint8)
    near = rng.integers(0, 256, (height, width + disparities), dtype=np.uint8)
    far_d, near_d = disparities // 4, disparities - 2
    right = texture[:, :width].copy()
    left = texture[:, far_d:far_d + width].copy()
    y0, y1, x0, x1 = height // 4, 3 * height // 4, width // 2, width - 2
    left[y0:y1, x0:x1] = near[y0:y1, x0:x1]
    right[y0:y1, x0 - near_d:x1 - near_d] = near[y0:y1, x0:x1]
    left[-4:, :], right[-4:, :] = 90, 90
    return left, right


def stereo_pair(kind, height, width, seed, disparities=8):
    """A left image and a right image of ``kind`` (see :data:`KINDS`), uint8 H x W."""
    rng = np.random.default_rng(seed)
    if kind == "layers":
        return _layers(rng, height, width, disparities)
    if kind == "independent":
        return (rng.integers(0, 256, (height, width), dtype=np.uint8),
                rng.integers(0, 256, (height, width), dtype=np.uint8))
    if kind == "random":
        left = rng.integers(0, 256, (height, width))
    elif kind == "levels":
        left = rng.choice([0, 100, 101], (height, width))
    elif kind == "flat":
        tiles = rng.choice([0, 7, 200], (height // 4 + 1, width // 4 + 1))
        left = np.kron(tiles, np.ones((4, 4), dtype=int))[:height, :width]
    elif kind == "stripes":
        left = np.tile(np.array([10, 50, 50]), width // 3 + 1)[None, :width].repeat(height, 0)
        left = left + (rng.random((height, width)) < 0.05) * 30
    elif kind == "saturated":
        left = rng.choice([0, 255], (height, width))
    else:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, not {kind!r}")
    shift = rng.integers(1, 5, height)[:, None]
    columns = np.clip(np.arange(width)[None, :] + shift, 0, width - 1)
    right = np.take_along_axis(left, columns, axis=1)
    noise = rng.random((height, width)) < 0.1
    right = np.where(noise, rng.integers(0, 256, (height, width)), right)
    return left.astype(np.uint8), right.astype(np.uint8)
