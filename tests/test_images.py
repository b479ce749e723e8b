"""PNG output without matplotlib: the embedded turbo table is matplotlib's, pixel for pixel,
and ``npstereo match`` loads neither matplotlib nor the hardware tool chain."""

import numpy as np
import pytest
from matplotlib import colormaps

from npstereo.gen import images
from npstereo.gen.images import TURBO, colour_disparity


def matplotlib_rendering(disparity, max_disparity):
    """How the maps were drawn with matplotlib's colour map (the reference)."""
    disparity = np.asarray(disparity, dtype=np.float64)
    invalid = ~np.isfinite(disparity) | (disparity < 0)
    scaled = np.clip(np.nan_to_num(disparity) / max(max_disparity, 1), 0.0, 1.0)
    rgb = (colormaps[images.COLOURMAP](scaled)[..., :3] * 255 + 0.5).astype(np.uint8)
    rgb[invalid] = 0
    return rgb


def test_table_is_matplotlibs():
    table = colormaps[images.COLOURMAP](np.arange(256))[:, :3]
    assert np.array_equal(TURBO, (table * 255 + 0.5).astype(np.uint8))


def sample_maps():
    """Integer maps (the commands' int16, -1 invalid, values beyond the top) and float maps
    (ground truth, NaN unknown)."""
    rng = np.random.default_rng(0)
    integers = rng.integers(-1, 100, (30, 40)).astype(np.int16)
    integers[0, :2] = (99, 150)
    floats = integers.astype(np.float64)
    floats[1, 0] = np.nan
    return [(m, top) for m in (integers, floats) for top in (99, 37, 0)] + [
        (rng.random((20, 20)) * 80, 79), (np.full((2, 3), -1, np.int16), 10)]


def test_maps_look_as_matplotlib_draws_them():
    for disparity, top in sample_maps():
        assert np.array_equal(colour_disparity(disparity, top),
                              matplotlib_rendering(disparity, top))


def test_an_off_by_one_table_is_caught(monkeypatch):
    """Broken variant: the table shifted by one colour no longer matches."""
    monkeypatch.setattr(images, "TURBO", np.roll(TURBO, 1, axis=0))
    with pytest.raises(AssertionError, match="assert False"):
        test_maps_look_as_matplotlib_draws_them()


def test_match_imports_no_plotting_or_hardware_libraries(tmp_path, small_pair,
                                                         libraries_loaded):
    """What keeps ``npstereo match`` fast: it loads only numpy, Pillow and the golden model."""
    from PIL import Image
    left, right = tmp_path / "l.png", tmp_path / "r.png"
    Image.fromarray(small_pair.left).save(left)
    Image.fromarray(small_pair.right).save(right)
    code, output, loaded = libraries_loaded(
        ["match", str(left), str(right), "--block", "3", "--disparities", "16", "--out",
         str(tmp_path / "d.png")], {"matplotlib", "amaranth", "cocotb", "cocotb_tools", "tqdm"})
    assert code == 0, output
    assert loaded == "[]"
