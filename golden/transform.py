"""Transformation: the four non-parametric transforms of the paper (Eq. 1, 2, 4, 6, 7, 8).

Every transform looks at the B x B window around a pixel without its centre. Pixels outside
the image are 0 (zero padding), exactly as the hardware masks window columns and rows that
fall outside the frame. Neighbours are numbered n = 0 .. k-1 in raster order of the window
(row by row, top to bottom, left to right), skipping the centre.
"""

import numpy as np

from ..params import check_transform_table

__all__ = ["window_offsets", "neighbour_planes", "rank", "census", "ext_rank", "ext_census",
           "transform"]


def window_offsets(block):
    """(dy, dx) of the k = B*B-1 neighbours in their numbering order."""
    r = (block - 1) // 2
    return [(dy, dx) for dy in range(-r, r + 1) for dx in range(-r, r + 1) if (dy, dx) != (0, 0)]


def _padded(image, r):
    """The image with r rows and columns of zeros around it (the border rule)."""
    height, width = image.shape
    padded = np.zeros((height + 2 * r, width + 2 * r), dtype=np.uint8)
    padded[r:r + height, r:r + width] = image
    return padded


def neighbour_planes(image, block):
    """Yield (n, P'_n) for every neighbour: the image shifted so that P'_n(y, x) = P(y+dy, x+dx)."""
    image = np.asarray(image, dtype=np.uint8)
    r = (block - 1) // 2
    height, width = image.shape
    padded = _padded(image, r)
    for n, (dy, dx) in enumerate(window_offsets(block)):
        yield n, padded[r + dy:r + dy + height, r + dx:r + dx + width]


def _xi(centre, neighbour):
    """Eq. 1: 1 where the centre is strictly brighter than the neighbour (bool array)."""
    return np.greater(centre, neighbour)


def _absolute_difference(centre, neighbour, out):
    """Eq. 6: |P - P'| on 8-bit pixels into ``out``, without leaving uint8."""
    np.maximum(centre, neighbour, out=out)
    out -= np.minimum(centre, neighbour)
    return out


def rank(image, block):
    """Eq. 2: number of neighbours darker than the centre. (H, W) uint16."""
    image = np.asarray(image, dtype=np.uint8)
    # k <= 255 comparisons still fit the uint8 counter; wider windows count in uint16.
    count = np.zeros(image.shape, dtype=np.uint8 if block * block - 1 <= 255 else np.uint16)
    for _, plane in neighbour_planes(image, block):
        count += _xi(image, plane).view(np.uint8)
    return count.astype(np.uint16)


def census(image, block):
    """Eq. 4: bit vector of the same comparisons.

    Returns (ceil(k/64), H, W) uint64: bit b of word w is neighbour 64*w + b.
    """
    image = np.asarray(image, dtype=np.uint8)
    k = block * block - 1
    words = (k + 63) // 64
    height, width = image.shape
    # Collect the bits in bytes (byte j holds neighbours 8j .. 8j+7, uint8 arithmetic is
    # 8 times cheaper than uint64), then regroup 8 bytes into a little-endian word.
    octets = np.zeros((words * 8, height, width), dtype=np.uint8)
    for n, plane in neighbour_planes(image, block):
        bits = _xi(image, plane).view(np.uint8)
        octets[n // 8] |= bits << np.uint8(n % 8)
    packed = np.ascontiguousarray(octets.reshape(words, 8, height, width).transpose(0, 2, 3, 1))
    return packed.view("<u8").reshape(words, height, width).astype(np.uint64, copy=False)


def ext_rank(image, block):
    """Eq. 7: sum of |P - P'| over the neighbours. (H, W) uint32."""
    image = np.asarray(image, dtype=np.uint8)
    out = np.zeros(image.shape, dtype=np.uint32)
    difference = np.empty(image.shape, dtype=np.uint8)
    for _, plane in neighbour_planes(image, block):
        out += _absolute_difference(image, plane, difference)
    return out


def ext_census(image, block):
    """Eq. 8: the vector of |P - P'|, one byte per neighbour. (k, H, W) uint8.

    The array is a transposed view of (H, W, k) memory: each pixel's k bytes are contiguous,
    which makes the matching-cost sums over them several times faster.
    """
    image = np.asarray(image, dtype=np.uint8)
    k = block * block - 1
    height, width = image.shape
    out = np.empty((height, width, k), dtype=np.uint8)
    # Plane by plane is the fast way to compute; a few rows at a time keeps the planes in
    # the cache until they are transposed into place.
    rows = 32
    planes = np.empty((k, rows, width), dtype=np.uint8)
    neighbours = [plane for _, plane in neighbour_planes(image, block)]
    for y0 in range(0, height, rows):
        y1 = min(height, y0 + rows)
        for n, plane in enumerate(neighbours):
            _absolute_difference(image[y0:y1], plane[y0:y1], planes[n, :y1 - y0])
        out[y0:y1] = planes[:, :y1 - y0].transpose(1, 2, 0)
    return out.transpose(2, 0, 1)


#: The transform functions ``(image, block) -> transformed`` by transform name.
_TRANSFORMS = check_transform_table(
    {"rank": rank, "census": census, "ext-rank": ext_rank, "ext-census": ext_census},
    "golden.transform._TRANSFORMS")


def transform(image, params):
    """The transform ``params.transform`` of an 8-bit gray image."""
    return _TRANSFORMS[params.transform](image, params.block)
