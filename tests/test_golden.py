"""The golden model against the slow per-pixel reference (tests/reference.py).

Every stage (transform, matching costs, aggregation) and the whole disparity map are compared
pixel for pixel on small synthetic images, for all four transforms, several block sizes,
disparity ranges, round counts, aggregation sizes and L/R settings. The images are chosen to
produce many tied costs (few gray levels, flat regions, periodic stripes), where the border
and tie rules decide the result. The ``test_broken_*`` cases break one rule of the golden
model at a time and check that the comparison with the reference catches it.
"""

import numpy as np
import pytest

from npstereo.golden import aggregation as golden_aggregation
from npstereo.golden import matching_cost as golden_cost
from npstereo.golden import pipeline as golden_pipeline
from npstereo.golden import transform as golden_transform
from npstereo.golden import wta as golden_wta
from npstereo.params import TRANSFORMS, StereoParams

import reference
from scenes import stereo_pair

def divisors(n):
    return [r for r in range(1, n + 1) if n % r == 0]


# Transform --------------------------------------------------------------------------------


def unpack_transform(values, name, block, x, y):
    """The golden transform of pixel (x, y) in the reference's form (int or tuple)."""
    k = block * block - 1
    if name == "census":
        return tuple((int(values[n // 64, y, x]) >> (n % 64)) & 1 for n in range(k))
    if name == "ext-census":
        return tuple(int(values[n, y, x]) for n in range(k))
    return int(values[y, x])


def transform_mismatches(image, name, block):
    """Pixels whose golden transform differs from the reference's."""
    params = StereoParams(transform=name, block=block)
    golden = golden_transform.transform(image, params)
    expected = reference.transform_image(image, name, block)
    height, width = image.shape
    return [(x, y) for y in range(height) for x in range(width)
            if unpack_transform(golden, name, block, x, y) != expected[y][x]]


@pytest.mark.parametrize("name", TRANSFORMS)
@pytest.mark.parametrize("block,kind", [(3, "random"), (5, "levels"), (7, "saturated"),
                                        (9, "flat"), (11, "random")])
def test_transform_matches_reference(name, block, kind):
    image, _ = stereo_pair(kind, 13, 17, seed=block)
    assert transform_mismatches(image, name, block) == []


def test_transform_of_image_smaller_than_window():
    image = np.array([[3, 200, 5]], dtype=np.uint8)
    for name in TRANSFORMS:
        assert transform_mismatches(image, name, 7) == []


# Matching costs and aggregation -----------------------------------------------------------


def stage_mismatches(name, block, aggregation, kind):
    """(stage, d) of every disparity whose golden costs or aggregated costs differ."""
    height, width, disparities = 9, 21, 6
    left, right = stereo_pair(kind, height, width, seed=block + aggregation)
    params = StereoParams(transform=name, block=block, disparities=disparities,
                          aggregation=aggregation)
    volume = reference.cost_volume(left, right, name, block, disparities)
    aggregated = reference.aggregate(volume, aggregation)
    left_t = golden_transform.transform(left, params)
    right_t = golden_transform.transform(right, params)
    mismatches = []
    for d in range(disparities):
        costs = golden_cost.matching_costs(left_t, right_t, d, params)
        expected = np.array([[volume[y][x][d] for x in range(width)] for y in range(height)])
        if not np.array_equal(costs, expected):
            mismatches.append(("costs", d))
        expected = np.array([[aggregated[y][x][d] for x in range(width)]
                             for y in range(height)])
        if not np.array_equal(golden_aggregation.aggregate(costs, aggregation), expected):
            mismatches.append(("aggregated", d))
    return mismatches


@pytest.mark.parametrize("name", TRANSFORMS)
@pytest.mark.parametrize("block,aggregation,kind", [(3, 3, "levels"), (5, 1, "random"),
                                                    (7, 5, "saturated"), (17, 3, "random")])
def test_costs_and_aggregation_match_reference(name, block, aggregation, kind):
    assert stage_mismatches(name, block, aggregation, kind) == []


# The whole disparity map ------------------------------------------------------------------

#: (transform, block, D, aggregation sizes, image kind, height, width). Every case is checked
#: for every R dividing D and for T = off, 0, 1, 3.
MAP_CASES = [
    ("rank", 3, 4, (1, 3), "levels", 10, 24),
    ("rank", 5, 8, (3, 5), "random", 12, 30),
    ("rank", 7, 12, (3,), "stripes", 16, 40),
    ("census", 3, 8, (1, 3), "levels", 12, 28),
    ("census", 5, 12, (3, 5), "stripes", 14, 36),
    ("census", 7, 4, (3,), "flat", 16, 40),
    ("census", 9, 8, (3,), "random", 12, 32),
    ("ext-rank", 3, 12, (3,), "flat", 12, 36),
    ("ext-rank", 5, 4, (1, 3, 5), "saturated", 10, 24),
    ("ext-rank", 7, 8, (3,), "levels", 14, 30),
    ("ext-census", 3, 8, (3, 5), "saturated", 12, 28),
    ("ext-census", 5, 12, (3,), "levels", 12, 36),
    ("ext-census", 7, 4, (1, 3), "stripes", 16, 24),
]
THRESHOLDS = (None, 0, 1, 3)


def golden_map(left, right, name, block, disparities, rounds, aggregation, threshold):
    params = StereoParams(transform=name, block=block, disparities=disparities, rounds=rounds,
                          aggregation=aggregation, lr_threshold=threshold)
    return golden_pipeline.disparity_map(left, right, params).disparity


@pytest.mark.parametrize("name,block,disparities,aggregations,kind,height,width", MAP_CASES)
def test_disparity_map_matches_reference(name, block, disparities, aggregations, kind,
                                         height, width):
    left, right = stereo_pair(kind, height, width, seed=block * disparities)
    volume = reference.cost_volume(left, right, name, block, disparities)
    for aggregation in aggregations:
        aggregated = reference.aggregate(volume, aggregation)
        for threshold in THRESHOLDS:
            expected = reference.disparity_from_aggregated(aggregated, aggregation, threshold)
            # Results must not depend on the round count R: each R meets the same reference.
            for rounds in divisors(disparities):
                got = golden_map(left, right, name, block, disparities, rounds, aggregation,
                                 threshold)
                np.testing.assert_array_equal(
                    got, expected, err_msg=f"A={aggregation} T={threshold} R={rounds}")
    # The images must exercise the check: some pixels valid, some rejected at T = 0.
    strict = reference.disparity_from_aggregated(aggregated, aggregation, 0)
    assert (strict[:, disparities + 1:] >= 0).any()


def test_disparity_map_of_wide_aggregation_and_band_seams(monkeypatch):
    """A = 7, bands of 4 rows, cost chunks of 1 row, 1 or 3 threads: nothing may change."""
    monkeypatch.setattr(golden_pipeline, "_band_rows", lambda *args: 4)
    monkeypatch.setattr(golden_pipeline, "_CHUNK_BYTES", 1)
    left, right = stereo_pair("levels", 11, 24, seed=7)
    for name in ("census", "ext-census"):
        expected = reference.disparity_map(left, right, name, 5, 6, aggregation=7)
        params = StereoParams(transform=name, block=5, disparities=6, rounds=3, aggregation=7)
        for threads in (1, 3):
            got = golden_pipeline.disparity_map(left, right, params, threads=threads)
            np.testing.assert_array_equal(got.disparity, expected)


def test_disparity_map_of_one_block_9_ext_census():
    left, right = stereo_pair("random", 10, 24, seed=9)
    expected = reference.disparity_map(left, right, "ext-census", 9, 8, lr_threshold=1)
    np.testing.assert_array_equal(golden_map(left, right, "ext-census", 9, 8, 2, 3, 1),
                                  expected)


# Deliberately broken golden models must be caught ----------------------------------------

BROKEN_CASE = ("census", 5, 8, 3, "levels", 12, 30)


def broken_case_differs():
    """Whether the golden map of BROKEN_CASE differs from the reference (with R = 1, 2)."""
    name, block, disparities, aggregation, kind, height, width = BROKEN_CASE
    left, right = stereo_pair(kind, height, width, seed=3)
    expected = reference.disparity_map(left, right, name, block, disparities, aggregation, 3)
    return any(not np.array_equal(
        golden_map(left, right, name, block, disparities, rounds, aggregation, 3), expected)
        for rounds in (1, 2))


def test_broken_model_baseline_matches():
    """The unbroken model passes the case every broken variant below must fail."""
    assert not broken_case_differs()


def test_broken_comparison_is_caught(monkeypatch):
    monkeypatch.setattr(golden_transform, "_xi", lambda centre, neighbour: centre >= neighbour)
    assert broken_case_differs()
    image, _ = stereo_pair("levels", 8, 9, seed=1)
    assert transform_mismatches(image, "rank", 3)


def test_broken_tie_rule_is_caught(monkeypatch):
    """Ties kept at the highest disparity instead of the lowest."""
    def higher_wins_ties(cost, disparity, best_cost, best_disparity, out):
        np.equal(cost, best_cost, out=out)
        out &= np.greater(disparity, best_disparity)
        out |= np.less(cost, best_cost)
        return out
    monkeypatch.setattr(golden_wta, "_beats", higher_wins_ties)
    assert broken_case_differs()


def test_broken_padding_is_caught(monkeypatch):
    """Border pixels repeated instead of zero padding."""
    monkeypatch.setattr(golden_transform, "_padded",
                        lambda image, r: np.pad(image, r, mode="edge"))
    assert broken_case_differs()
    image, _ = stereo_pair("flat", 8, 9, seed=1)
    assert transform_mismatches(image, "ext-census", 3)


def test_broken_costs_are_caught(monkeypatch):
    """Census bits combined with OR instead of XOR, ext-census without the factor 2."""
    def with_or(left, right, out, totals):
        np.copyto(out, np.bitwise_count(left | right).sum(axis=0))
    monkeypatch.setitem(golden_cost._COSTS, "census", (with_or, None))
    assert stage_mismatches("census", 3, 3, "levels")

    def half(left, right, out, totals):
        np.add.reduce(np.minimum(left, right), axis=0, dtype=out.dtype, out=out)
        np.subtract(totals, out, out=out)
    monkeypatch.setitem(golden_cost._COSTS, "ext-census",
                        (half, golden_cost._COSTS["ext-census"][1]))
    assert stage_mismatches("ext-census", 3, 3, "levels")


def test_broken_aggregation_border_is_caught(monkeypatch):
    """The aggregation wrapping around the image instead of counting 0 outside."""
    def wrapping(costs, size, rows=None, **buffers):
        a = (size - 1) // 2
        out = sum(np.roll(costs, (j, i), axis=(0, 1))
                  for j in range(-a, a + 1) for i in range(-a, a + 1))
        return out if rows is None else out[rows[0]:rows[1]]
    monkeypatch.setattr(golden_pipeline, "aggregate", wrapping)
    assert broken_case_differs()


def test_broken_lr_threshold_is_caught(monkeypatch):
    """|dL - dR| < T instead of <= T."""
    real = golden_pipeline.lr_check
    monkeypatch.setattr(golden_pipeline, "lr_check",
                        lambda left, right, threshold: real(left, right, threshold - 1))
    assert broken_case_differs()
