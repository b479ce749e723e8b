"""How tests/bench_quality.py turns OpenCV's output into maps the project's metric scores.

OpenCV is replaced by a small exact matcher with OpenCV's conventions (fixed point with 4
fractional bits, -16 for invalid, the numDisparities leftmost columns invalid), so the
conversions are checked independently of OpenCV's own matching; one smoke test runs the
real OpenCV when it is installed. Broken conversions (no mirroring of the right map, no
padding, truncation instead of rounding) must fail.
"""

import numpy as np
import pytest

import bench_quality


class FakeCv2:
    """The two functions of cv2 that opencv_map uses, in numpy."""

    BORDER_REPLICATE = "replicate"

    @staticmethod
    def copyMakeBorder(image, top, bottom, left, right, border):
        assert (top, bottom, right, border) == (0, 0, 0, "replicate")
        return np.pad(image, ((0, 0), (left, 0)), mode="edge")


class ExactMatcher:
    """Winner of a 1 x 5 horizontal SAD over d = 0 .. n - 1, in OpenCV's output format."""

    def __init__(self, num_disparities):
        self.n = num_disparities

    def compute(self, left, right):
        left, right = left.astype(np.int64), right.astype(np.int64)
        height, width = left.shape
        best = np.full((height, width), np.iinfo(np.int64).max)
        out = np.zeros((height, width), np.int64)
        for d in range(self.n):
            diff = np.full((height, width), 10 ** 6)
            diff[:, d:] = np.abs(left[:, d:] - right[:, :width - d])
            # Window truncated at the image edges (zeros outside, no wrap-around).
            padded = np.pad(diff, ((0, 0), (2, 2)))
            sad = sum(padded[:, k:k + width] for k in range(5))
            better = sad < best
            best = np.where(better, sad, best)
            out = np.where(better, 16 * d, out)
        out[:, :self.n] = -16  # OpenCV's invalid left border
        return out.astype(np.int16)


class FixedMatcher:
    """Returns a given raw map whatever the input (shape of the padded input)."""

    def __init__(self, raw):
        self.raw = raw

    def compute(self, left, right):
        return self.raw[:, -left.shape[1]:] if self.raw.shape[1] >= left.shape[1] else None


def shifted_pair(shift, height=12, width=60, seed=0):
    """Random texture; the right view is the left one shifted by ``shift`` columns."""
    rng = np.random.default_rng(seed)
    scene = rng.integers(0, 256, (height, width + shift)).astype(np.uint8)
    return scene[:, :width].copy(), scene[:, shift:].copy()


def test_rounding_and_range():
    disparities, nd = 20, 32
    pad = nd
    raw = np.zeros((1, 6 + pad), np.int16)
    raw[0, pad:] = [-16, 24, 23, 16 * 19 + 7, 16 * 19 + 8, 16 * 25]
    got = bench_quality.opencv_map(FakeCv2, FixedMatcher(raw), np.zeros((1, 6), np.uint8),
                                   np.zeros((1, 6), np.uint8), disparities, nd)
    # invalid stays invalid, 1.5 rounds up, 1.4375 down, 19.4375 -> 19, 19.5 -> 20 > D-1.
    assert got.tolist() == [[-1, 2, 1, 19, -1, -1]]


def test_padding_gives_every_column_a_result():
    left, right = shifted_pair(5)
    got = bench_quality.opencv_map(FakeCv2, ExactMatcher(16), left, right, 12, 16)
    assert (got[:, 7:] == 5).all()  # beyond the window's own border every column is exact
    # Counterpart: without padding OpenCV's border convention would leave 16 columns invalid.
    raw = ExactMatcher(16).compute(left, right)
    assert (raw[:, :16] < 0).all()


def test_mirrored_right_map_passes_the_check():
    left, right = shifted_pair(4, width=70, seed=3)
    unchecked, checked = bench_quality.opencv_maps(FakeCv2, ExactMatcher(16), left, right,
                                                   12, 16)
    inner = np.s_[:, 8:-4]
    assert (unchecked[inner] == 4).all() and (checked[inner] == 4).all()


def test_broken_mirroring_is_caught(monkeypatch):
    # Without mirroring, the "right map" is the matcher run on the swapped pair.
    monkeypatch.setattr(bench_quality, "mirror", lambda image: image)
    left, right = shifted_pair(4, width=70, seed=3)
    _, checked = bench_quality.opencv_maps(FakeCv2, ExactMatcher(16), left, right, 12, 16)
    assert not (checked[:, 8:-4] == 4).all()


def test_invalid_right_pixels_reject():
    left, right = shifted_pair(4, width=40, seed=1)

    class HalfInvalid(ExactMatcher):
        calls = 0

        def compute(self, l, r):
            out = super().compute(l, r)
            HalfInvalid.calls += 1
            if HalfInvalid.calls == 2:  # the mirrored run: every right pixel invalid
                out[:] = -16
            return out
    unchecked, checked = bench_quality.opencv_maps(FakeCv2, HalfInvalid(16), left, right,
                                                   12, 16)
    assert (unchecked[:, 8:-4] == 4).all() and (checked < 0).all()


def test_real_opencv_on_a_synthetic_pair():
    cv2 = pytest.importorskip("cv2")
    from npstereo.golden.quality import evaluate
    from npstereo.golden.synthetic import synthetic_pair
    pair = synthetic_pair(160, 120, 32, seed=0)
    left, right = pair.gray()
    scores = {}
    for name, matcher in bench_quality.opencv_matchers(cv2, 32):
        unchecked, checked = bench_quality.opencv_maps(cv2, matcher, left, right, 32, 32)
        scores[name] = (evaluate(unchecked, pair.ground_truth, 32).correct,
                        evaluate(checked, pair.ground_truth, 32).correct)
    # The exact synthetic scene is easy: every peer gets most pixels, and the check only
    # removes pixels (occlusions), never adds them.
    for unchecked_score, checked_score in scores.values():
        assert unchecked_score > 80 and checked_score <= unchecked_score


def test_fraction_map_keeps_sixteenths():
    disparities, nd = 20, 32
    raw = np.zeros((1, 6 + nd), np.int16)
    raw[0, nd:] = [-16, 24, 23, 16 * 19 + 7, 16 * 19 + 8, 16 * 25]
    got = bench_quality.opencv_map(FakeCv2, FixedMatcher(raw), np.zeros((1, 6), np.uint8),
                                   np.zeros((1, 6), np.uint8), disparities, nd, fraction=True)
    # The range rule is the rounded map's: 19.5 rounds to 20 > D - 1 and is invalid.
    assert got.dtype == np.float32 and got.tolist() == [[-1, 1.5, 1.4375, 19.4375, -1, -1]]


def test_fraction_maps_follow_the_whole_level_check():
    left, right = shifted_pair(4, width=70, seed=3)
    whole = bench_quality.opencv_maps(FakeCv2, ExactMatcher(16), left, right, 12, 16)
    fine = bench_quality.opencv_fraction_maps(FakeCv2, ExactMatcher(16), left, right, 12, 16)
    for w, f in zip(whole, fine):
        assert np.array_equal(w < 0, f < 0) and np.array_equal(f[w >= 0], w[w >= 0])


@pytest.mark.parametrize("median", [False, True])
def test_subpixel_row_scores_the_fraction(median):
    """The F = 4 row: float levels in both maps (the unchecked one from a run without the
    check: the checked run's raw map has whole levels only), each within half a level of
    the F = 0 map, where the median (on values scaled by 2^F) allows it."""
    from npstereo.golden.synthetic import synthetic_pair
    pair = synthetic_pair(64, 24, 16, seed=1)
    left, right = pair.gray()
    args = (left, right, "census", 5, 16, 8, 32, 5, median)
    whole = bench_quality.sgm_maps(*args, 0)
    fine = bench_quality.sgm_maps(*args, 4)
    for w, f in zip(whole, fine):
        assert w.dtype == np.int16 and f.dtype == np.float32
        assert (f[f >= 0] != np.round(f[f >= 0])).any()
        assert np.all(np.round(f[f >= 0] * 16) == f[f >= 0] * 16)
        if not median:
            assert np.array_equal(w < 0, f < 0)
            assert np.abs(f[w >= 0] - w[w >= 0]).max() <= 0.5
