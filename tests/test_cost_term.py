"""The ``ad3`` cost term: the golden model against the definition written out pixel by
pixel (docs/semantics.md, "The ad3 cost term"), its place in the SGM costs, and the
parameters' rules."""

import numpy as np
import pytest

from npstereo.golden import sgm
from npstereo.golden.cost_term import ad3_term
from npstereo.golden.pipeline import disparity_map
from npstereo.params import ParameterError, StereoParams, default_p2
from npstereo.params.cost_terms import AD3_MAX


def reference_term(left, right, disparities, right_column_zero=False, clip=31):
    """T(x, y, d) by the letter of docs/semantics.md, one pixel at a time. The keywords
    make the deliberately broken variants the tests must tell apart."""
    height, width = left.shape

    def pixel(image, x, y):
        return int(image[y, x]) if 0 <= x < width and 0 <= y < height else 0

    term = np.zeros((height, width, disparities), np.int64)
    for y in range(height):
        for x in range(width):
            for d in range(disparities):
                total = 0
                for j in (-1, 0, 1):
                    for i in (-1, 0, 1):
                        if x + i - d >= (0 if right_column_zero else 1):
                            total += min(abs(pixel(left, x + i, y + j)
                                             - pixel(right, x + i - d, y + j)), clip)
                term[y, x, d] = min(total, 255) >> 5
    return term


def random_pair(seed, shape=(7, 13)):
    rng = np.random.default_rng(seed)
    left = rng.integers(0, 256, shape, dtype=np.uint8)
    # Right: the left one shifted with small noise (small differences exercise the sum
    # below its clip) and a few arbitrary pixels (large ones exercise both clips).
    right = np.clip(np.roll(left, -2, axis=1).astype(int)
                    + rng.integers(-12, 13, shape), 0, 255).astype(np.uint8)
    right[rng.random(shape) < 0.2] = rng.integers(0, 256)
    return left, right


@pytest.mark.parametrize("seed", range(3))
def test_golden_term_is_the_definition(seed):
    left, right = random_pair(seed)
    expected = reference_term(left, right, 6)
    got = ad3_term(left, right, 6)
    assert np.array_equal(got, expected)
    assert got.min() == 0 and 0 < got.max() <= AD3_MAX and len(np.unique(got)) > 3
    # Rows of a band: the rows above and below still enter the windows.
    assert np.array_equal(ad3_term(left, right, 6, rows=(2, 5)), expected[2:5])


@pytest.mark.parametrize("broken", [dict(right_column_zero=True), dict(clip=63)])
def test_broken_definitions_are_told_apart(broken):
    left, right = random_pair(0)
    assert not np.array_equal(ad3_term(left, right, 6),
                              reference_term(left, right, 6, **broken))


def test_sgm_costs_carry_the_term(small_pair):
    left, right = (image[:24, :64] for image in small_pair.gray())
    plain = StereoParams("census", 5, 12, aggregation="sgm")
    params = plain.replace(cost_term="ad3")
    assert params.max_cost == plain.max_cost + AD3_MAX
    volume = sgm.cost_volume(left, right, params).astype(int)
    census = sgm.cost_volume(left, right, plain).astype(int)
    missing = np.arange(12)[None, :] > np.arange(64)[:, None]
    term = reference_term(left, right, 12)
    assert np.array_equal(volume[:, missing], np.full(volume[:, missing].shape,
                                                      params.max_cost))
    assert np.array_equal(volume[:, ~missing], (census + term)[:, ~missing])
    # The pipeline (bands of rows) gives the map of the whole volume's paths.
    summed = sgm.aggregate(volume, params.p1, params.p2, guide=left, adapt=params.p2_adapt,
                           max_cost=params.max_cost)
    expected = sgm.disparity_from_summed(summed, params.lr_threshold).disparity
    got = disparity_map(left, right, params).disparity
    assert np.array_equal(got, expected)
    assert not np.array_equal(got, disparity_map(left, right, plain.replace(
        p2=params.p2)).disparity)


def test_term_changes_the_default_p2_only():
    params = StereoParams("census", 7, 64, aggregation="sgm", cost_term="ad3")
    assert (params.p1, params.p2, params.p2_adapt) == (24, default_p2("ad3"), 5) == (24, 72, 5)
    assert params.path_cost_bits == 7 == StereoParams("census", 7, 64,
                                                       aggregation="sgm").path_cost_bits
    assert StereoParams("census", 7, 64, aggregation="sgm", cost_term="ad3", p2=79).p2 == 79
    assert "cost_term" not in repr(StereoParams())       # the report cache's keys stay


@pytest.mark.parametrize("changes, message", [
    (dict(cost_term="ad4", aggregation="sgm"), "cost term must be one of ad3 (or none), not 'ad4'"),
    (dict(cost_term="ad3"), "cost term ad3 needs aggregation 'sgm', not a 3x3 box"),
    (dict(cost_term="ad3", transform="rank", aggregation="sgm"),
     "cost term ad3 needs the census transform, not rank"),
])
def test_term_rules(changes, message):
    with pytest.raises(ParameterError) as error:
        StereoParams(**changes)
    assert str(error.value) == message
