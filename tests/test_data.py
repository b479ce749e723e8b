"""Loaders, gray conversion, synthetic scene, degradations and the quality metric."""

import numpy as np
import pytest
from PIL import Image

from npstereo.golden import data
from npstereo.golden.data import load_middlebury, read_pfm, to_gray
from npstereo.golden.degrade import bayer_mosaic, bayer_pair, gaussian_noise_pair
from npstereo.params import StereoParams, UserError
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.quality import evaluate
from npstereo.golden.synthetic import synthetic_pair


# Gray conversion -------------------------------------------------------------------------

def bt601_reference(rgb):
    r, g, b = (int(v) for v in rgb)
    return (299 * r + 587 * g + 114 * b + 500) // 1000


def test_gray_is_integer_bt601():
    rng = np.random.default_rng(0)
    image = rng.integers(0, 256, (32, 32, 3), dtype=np.uint8)
    expected = np.array([[bt601_reference(p) for p in row] for row in image], np.uint8)
    assert np.array_equal(to_gray(image), expected)
    # Hand-checked corners: rounding at .5 goes up, white stays white.
    samples = np.array([[[255, 255, 255], [2, 0, 0], [1, 0, 0], [0, 0, 5]]], np.uint8)
    assert to_gray(samples).tolist() == [[255, 1, 0, 1]]
    # The test discriminates: the same luma without the rounding term differs.
    truncated = (image.astype(np.uint32) @ np.array([299, 587, 114], np.uint32)) // 1000
    assert not np.array_equal(truncated.astype(np.uint8), expected)


def test_gray_passes_gray_through_and_drops_alpha():
    gray = np.arange(12, dtype=np.uint8).reshape(3, 4)
    assert to_gray(gray) is gray
    rgba = np.dstack([np.full((2, 2), 100, np.uint8)] * 3 + [np.zeros((2, 2), np.uint8)])
    assert to_gray(rgba).tolist() == [[100, 100], [100, 100]]
    with pytest.raises(UserError, match="8-bit"):
        to_gray(gray.astype(np.uint16))


# Middlebury folders written by the tests ---------------------------------------------------

def write_rgb(path, rng, size=(24, 16)):
    image = rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8)
    Image.fromarray(image).save(path)
    return image


def write_pfm(path, values, little_endian=True, kind=b"Pf"):
    height, width = values.shape
    scale = -1.0 if little_endian else 1.0
    payload = np.ascontiguousarray(values[::-1], dtype="<f4" if little_endian else ">f4")
    path.write_bytes(kind + b"\n" + f"{width} {height}\n{scale}\n".encode() + payload.tobytes())


@pytest.fixture
def folder_2003(tmp_path):
    rng = np.random.default_rng(3)
    left = write_rgb(tmp_path / "im2.png", rng)
    write_rgb(tmp_path / "im6.png", rng)
    truth = rng.integers(0, 256, (16, 24), dtype=np.uint8)
    truth[0, :5] = 0
    Image.fromarray(truth).save(tmp_path / "disp2.pgm")
    return tmp_path, left, truth


def test_load_2003(folder_2003):
    folder, left, truth = folder_2003
    pair = load_middlebury(folder)
    assert pair.name == folder.name and pair.is_colour
    assert np.array_equal(pair.left, left)
    assert np.isnan(pair.ground_truth[0, :5]).all()
    known = truth > 0
    assert np.array_equal(pair.ground_truth[known], truth[known] / 4.0)


@pytest.mark.parametrize("width, scale", [(24, 3), (600, 2), (1100, 1)])
def test_load_2005_scales_by_size(tmp_path, width, scale):
    rng = np.random.default_rng(5)
    write_rgb(tmp_path / "view1.png", rng, (width, 4))
    write_rgb(tmp_path / "view5.png", rng, (width, 4))
    truth = rng.integers(1, 256, (4, width), dtype=np.uint8)
    truth[1, 1] = 0
    Image.fromarray(truth).save(tmp_path / "disp1.png")
    pair = load_middlebury(tmp_path)
    assert np.isnan(pair.ground_truth[1, 1])
    assert pair.ground_truth[0, 0] == truth[0, 0] / scale


@pytest.mark.parametrize("little_endian", [True, False])
def test_load_2014_pfm(tmp_path, little_endian):
    rng = np.random.default_rng(14)
    write_rgb(tmp_path / "im0.png", rng)
    write_rgb(tmp_path / "im1.png", rng)
    truth = rng.uniform(0, 60, (16, 24)).astype(np.float32)
    truth[2, 3] = np.inf
    write_pfm(tmp_path / "disp0.pfm", truth, little_endian)
    pair = load_middlebury(tmp_path)
    assert np.isnan(pair.ground_truth[2, 3])
    known = np.isfinite(truth)
    # Rows come back top first although PFM stores them bottom first.
    assert np.array_equal(pair.ground_truth[known], truth[known].astype(np.float64))


def one_line_error(call, *words):
    with pytest.raises(UserError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message
    for word in words:
        assert word in message
    return message


def test_loader_errors(tmp_path, folder_2003):
    folder, _, _ = folder_2003
    one_line_error(lambda: load_middlebury(tmp_path / "nope"), "does not exist")
    empty = tmp_path / "empty"
    empty.mkdir()
    one_line_error(lambda: load_middlebury(empty), "unknown dataset layout",
                   "im2.png", "view1.png", "im0.png", "disp0.pfm")
    # Size mismatch between the views.
    rng = np.random.default_rng(0)
    write_rgb(folder / "im6.png", rng, (20, 16))
    one_line_error(lambda: load_middlebury(folder), "differ in size")
    # Unreadable image: text in a .png.
    (folder / "im6.png").write_text("not an image")
    one_line_error(lambda: load_middlebury(folder), "im6.png", "not a readable image")
    (folder / "im6.png").unlink()
    one_line_error(lambda: load_middlebury(folder), "im6.png", "does not exist")


def test_ground_truth_errors(folder_2003):
    folder, _, _ = folder_2003
    Image.fromarray(np.zeros((16, 24), np.uint16)).save(folder / "disp2.png")
    (folder / "disp2.png").rename(folder / "disp2.pgm")
    one_line_error(lambda: load_middlebury(folder), "disp2.pgm", "8-bit")
    Image.fromarray(np.zeros((16, 23), np.uint8)).save(folder / "disp2.pgm")
    one_line_error(lambda: load_middlebury(folder), "disp2.pgm", "23x16")


def test_pfm_errors(tmp_path):
    write_pfm(tmp_path / "colour.pfm", np.zeros((2, 2), np.float32), kind=b"PF")
    one_line_error(lambda: read_pfm(tmp_path / "colour.pfm"), "single-channel")
    (tmp_path / "bad.pfm").write_bytes(b"Pf\nx y\n")
    one_line_error(lambda: read_pfm(tmp_path / "bad.pfm"), "not a PFM")
    (tmp_path / "short.pfm").write_bytes(b"Pf\n4 4\n-1.0\n" + b"\0" * 8)
    one_line_error(lambda: read_pfm(tmp_path / "short.pfm"), "truncated")


def test_sixteen_bit_input_image_is_rejected(tmp_path):
    Image.fromarray(np.zeros((4, 4), np.uint16)).save(tmp_path / "deep.png")
    one_line_error(lambda: data.read_image(tmp_path / "deep.png"), "8-bit")


# Synthetic scene ---------------------------------------------------------------------------

def test_synthetic_ground_truth_is_exact(default_pair):
    pair = default_pair
    truth = pair.ground_truth
    assert pair.left.shape == (120, 160, 3) and not np.isnan(truth).any()
    assert np.array_equal(truth, np.round(truth)) and truth.min() >= 1 and truth.max() <= 31
    assert len(np.unique(truth)) >= 5
    ys, xs = np.mgrid[0:120, 0:160]
    partner = xs - truth.astype(int)
    seen = partner >= 0
    same = (pair.left[ys[seen], xs[seen]] == pair.right[ys[seen], partner[seen]]).all(-1)
    # Exact correspondence wherever the point is visible, and real occlusions elsewhere.
    assert 0.8 < same.mean() < 0.99


def test_synthetic_is_seeded(small_pair):
    again = synthetic_pair(width=64, height=40, disparities=16, seed=1)
    other = synthetic_pair(width=64, height=40, disparities=16, seed=2)
    assert np.array_equal(small_pair.left, again.left)
    assert np.array_equal(small_pair.ground_truth, again.ground_truth)
    assert not np.array_equal(small_pair.left, other.left)


def test_census_matches_the_synthetic_scene(default_pair):
    left, right = default_pair.gray()
    params = StereoParams(transform="census", block=7, disparities=32)
    quality = evaluate(disparity_map(left, right, params).disparity,
                       default_pair.ground_truth, 32)
    assert quality.correct > 85
    # Shifting the ground truth by 2 must ruin the score: the metric compares for real.
    shifted = evaluate(disparity_map(left, right, params).disparity,
                       default_pair.ground_truth + 2, 32)
    assert shifted.correct < 20


def test_synthetic_rejects_bad_sizes():
    one_line_error(lambda: synthetic_pair(width=4), "width")


# Degradations ----------------------------------------------------------------------------

def test_gaussian_noise_statistics_and_seed():
    flat = np.full((200, 200), 128, np.uint8)
    a, b = gaussian_noise_pair(flat, flat, 0.002, seed=7)
    sigma = 255 * np.sqrt(0.002)
    for noisy in (a, b):
        residual = noisy.astype(float) - 128
        assert abs(residual.mean()) < 0.3 and abs(residual.std() - sigma) < 0.3
    assert not np.array_equal(a, b)
    again = gaussian_noise_pair(flat, flat, 0.002, seed=7)
    assert np.array_equal(a, again[0]) and np.array_equal(b, again[1])
    white = gaussian_noise_pair(np.full((50, 50), 255, np.uint8), flat[:50, :50], 0.002, 1)[0]
    assert white.max() == 255 and (white == 255).mean() > 0.4
    one_line_error(lambda: gaussian_noise_pair(flat, flat, -0.1, 0), "variance")


def test_bayer_mosaic_is_rggb():
    image = np.zeros((4, 4, 3), np.uint8)
    image[..., 0], image[..., 1], image[..., 2] = 10, 20, 30
    assert bayer_mosaic(image).tolist() == [[10, 20] * 2, [20, 30] * 2] * 2
    gained = bayer_mosaic(image, gains=(2.0, 1.0, 0.5))
    assert gained[:2, :2].tolist() == [[20, 20], [20, 15]]
    one_line_error(lambda: bayer_mosaic(image[..., 0]), "colour")
    one_line_error(lambda: bayer_mosaic(image, gains=(1, 0, 1)), "gains")


def test_bayer_read_noise_is_seeded(small_pair):
    a = bayer_pair(small_pair.left, small_pair.right, read_noise=2.0, seed=3)
    b = bayer_pair(small_pair.left, small_pair.right, read_noise=2.0, seed=3)
    clean = bayer_pair(small_pair.left, small_pair.right)
    assert np.array_equal(a[0], b[0]) and not np.array_equal(a[0], clean[0])
    assert np.abs(a[0].astype(int) - clean[0]).mean() < 3


# Quality metric ----------------------------------------------------------------------------

def test_quality_counts_by_hand():
    truth = np.array([[5.0, 5.0, 5.0, 5.0, 5.0, np.nan],
                      [5.0, 5.0, 5.0, 5.0, 5.0, 5.0]])
    disparity = np.array([[9, 9, 4, 6, 7, 5],
                          [9, 9, -1, 5, 3, 6]])
    # D = 2: columns 0, 1 ignored; NaN ignored -> evaluated: 3 + 4 = 7 pixels.
    # Correct: (0,2)=4 (0,3)=6 (1,3)=5 (1,5)=6 -> 4; valid: 6 (one -1); wrong valid: 2.
    quality = evaluate(disparity, truth, 2)
    assert quality.evaluated == 7
    assert quality.correct == pytest.approx(100 * 4 / 7)
    assert quality.density == pytest.approx(100 * 6 / 7)
    assert quality.error_rate == pytest.approx(100 * 2 / 6)


def test_quality_tolerance_boundary():
    truth = np.array([[0.0, 3.0, 3.0, 3.25, 3.25]])
    disparity = np.array([[0, 4, 2, 2, 5]])
    # |4-3| = 1 and |2-3| = 1 are correct; |2-3.25| and |5-3.25| are not.
    assert evaluate(disparity, truth, 1).correct == pytest.approx(50.0)
    one_line_error(lambda: evaluate(disparity, truth[:, :4], 1), "ground truth")
    one_line_error(lambda: evaluate(disparity, np.full((1, 5), np.nan), 1), "no pixel")
