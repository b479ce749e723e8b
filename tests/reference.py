"""A slow, obviously correct per-pixel implementation of docs/semantics.md.

Written straight from the paper's equations and the semantics page with plain Python loops
over pixels, window positions and disparities, on Python integers. It shares no code with
the golden model (it imports nothing from ``npstereo``), so tests/test_golden.py can hold the
fast golden model against it. Only for tiny images: it runs at microseconds per operation.

Images are given as 2-D sequences of ints (numpy arrays work), indexed ``image[y][x]``.
"""

import numpy as np

INVALID = -1


def pixel(image, x, y):
    """P(x, y), 0 outside the image (zero padding)."""
    height, width = len(image), len(image[0])
    if 0 <= x < width and 0 <= y < height:
        return int(image[y][x])
    return 0


def window_offsets(block):
    """(dx, dy) of the B*B-1 neighbours, numbered in raster order (dy outer), no centre."""
    r = (block - 1) // 2
    offsets = []
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if (dx, dy) != (0, 0):
                offsets.append((dx, dy))
    return offsets


def xi(p, q):
    """Paper Eq. 1: 1 iff P > P' (strict)."""
    return 1 if p > q else 0


def _rank(p, neighbours):              # Eq. 2
    return sum(xi(p, q) for q in neighbours)


def _census(p, neighbours):            # Eq. 4
    return tuple(xi(p, q) for q in neighbours)


def _ext_rank(p, neighbours):          # Eq. 7
    return sum(abs(p - q) for q in neighbours)


def _ext_census(p, neighbours):        # Eq. 8
    return tuple(abs(p - q) for q in neighbours)


#: The transformed value of a pixel from its value and its neighbours' (in their order),
#: by transform name.
TRANSFORMS = {"rank": _rank, "census": _census, "ext-rank": _ext_rank,
              "ext-census": _ext_census}


def transform_pixel(image, x, y, name, block):
    """The transformed value of pixel (x, y): an int (rank, ext-rank) or a tuple (vectors).

    census is the tuple of comparison bits and ext-census the tuple of absolute differences,
    both indexed by neighbour number n.
    """
    neighbours = [pixel(image, x + dx, y + dy) for dx, dy in window_offsets(block)]
    return TRANSFORMS[name](pixel(image, x, y), neighbours)


def transform_image(image, name, block):
    """transform_pixel of every pixel: a list of rows."""
    height, width = len(image), len(image[0])
    return [[transform_pixel(image, x, y, name, block) for x in range(width)]
            for y in range(height)]


def _absolute(left_value, right_value):        # Eq. 3
    return abs(left_value - right_value)


def _hamming(left_value, right_value):         # Eq. 5
    return sum(1 for a, b in zip(left_value, right_value) if a != b)


def _byte_differences(left_value, right_value):  # Eq. 9
    return sum(abs(a - b) for a, b in zip(left_value, right_value))


#: Matching costs of two transformed pixels, by transform name.
COSTS = {"rank": _absolute, "census": _hamming, "ext-rank": _absolute,
         "ext-census": _byte_differences}


def cost(left_value, right_value, name):
    """Matching cost of two transformed pixels (Eq. 3, 5, 9)."""
    return COSTS[name](left_value, right_value)


def cost_volume(left, right, name, block, disparities):
    """C[y][x][d]: cost of left (x, y) against right (x - d, y); 0 when x - d < 0."""
    left_t = transform_image(left, name, block)
    right_t = transform_image(right, name, block)
    height, width = len(left_t), len(left_t[0])
    volume = []
    for y in range(height):
        row = []
        for x in range(width):
            costs = []
            for d in range(disparities):
                if x - d >= 0:
                    costs.append(cost(left_t[y][x], right_t[y][x - d], name))
                else:
                    costs.append(0)
            row.append(costs)
        volume.append(row)
    return volume


def aggregate(volume, size):
    """S[y][x][d]: sum of C over the size x size window; outside the image C = 0."""
    a = (size - 1) // 2
    height, width, disparities = len(volume), len(volume[0]), len(volume[0][0])
    out = []
    for y in range(height):
        row = []
        for x in range(width):
            sums = []
            for d in range(disparities):
                total = 0
                for j in range(-a, a + 1):
                    for i in range(-a, a + 1):
                        if 0 <= y + j < height and 0 <= x + i < width:
                            total += volume[y + j][x + i][d]
                sums.append(total)
            row.append(sums)
        out.append(row)
    return out


def argmin_lowest(values):
    """Index of the smallest value; among equal values the lowest index."""
    best = 0
    for d in range(len(values)):
        if values[d] < values[best]:
            best = d
    return best


def left_map(aggregated):
    """dL(x, y): argmin over all disparities of S(x, y, d), ties to the lowest d."""
    return [[argmin_lowest(sums) for sums in row] for row in aggregated]


def right_map(aggregated):
    """dR(xr, y): argmin over d <= min(D-1, W-1-xr) of S(xr + d, y, d), ties lowest."""
    out = []
    for row in aggregated:
        width, disparities = len(row), len(row[0])
        out_row = []
        for xr in range(width):
            candidates = [row[xr + d][d] for d in range(min(disparities - 1, width - 1 - xr) + 1)]
            out_row.append(argmin_lowest(candidates))
        out.append(out_row)
    return out


def disparity_from_aggregated(aggregated, aggregation, lr_threshold):
    """The final map (numpy int16, INVALID = -1) from the aggregated costs S."""
    height, width, disparities = len(aggregated), len(aggregated[0]), len(aggregated[0][0])
    a = (aggregation - 1) // 2
    first_valid = disparities - 1 + max(1, a)
    d_left = left_map(aggregated)
    d_right = right_map(aggregated) if lr_threshold is not None else None
    out = np.full((height, width), INVALID, dtype=np.int16)
    for y in range(height):
        for x in range(first_valid, width):
            d = d_left[y][x]
            if lr_threshold is not None:
                if x - d < 0 or abs(d - d_right[y][x - d]) > lr_threshold:
                    continue
            out[y, x] = d
    return out


def disparity_map(left, right, name, block, disparities, aggregation=3, lr_threshold=3):
    """The whole pipeline of docs/semantics.md for one configuration."""
    volume = cost_volume(left, right, name, block, disparities)
    return disparity_from_aggregated(aggregate(volume, aggregation), aggregation, lr_threshold)
