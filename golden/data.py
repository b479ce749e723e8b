"""Stereo pairs with ground truth: gray conversion, image reading and Middlebury loaders.

Every loader returns a :class:`StereoPair` whose ground truth is a float disparity map in
pixels of the returned images, NaN where it is unknown. Every problem a user can fix (a
missing folder, an unreadable image, a size mismatch, an unexpected ground-truth format)
is raised as a one-line :class:`~npstereo.params.UserError`.

Scale conventions (what the loaders assume):

- Middlebury 2003 (``im2.png``, ``im6.png``, ``disp2.pgm``): the quarter-size ground truth
  stores 4 x disparity in 8 bits; 0 is unknown.
- Middlebury 2005/2006 (``view1.png``, ``view5.png``, ``disp1.png``): the 8-bit disparity
  PNG of every size stores the disparity scaled to the full-size images, so the disparity of
  the loaded views is value / s with s = 1 for full size (width >= 1000), 2 for half size
  (width >= 550) and 3 for third size (narrower); 0 is unknown.
- Middlebury 2014 (``im0.png``, ``im1.png``, ``disp0.pfm``): float disparity in pixels of
  the images in a PFM file (rows stored bottom to top); infinity is unknown.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from ..params import ParameterError, UserError

__all__ = ["StereoPair", "to_gray", "check_same_size", "check_gray_pair", "read_image", "read_pfm",
           "load_middlebury", "LAYOUTS"]


@dataclass(frozen=True)
class StereoPair:
    """A rectified stereo pair (left is the reference) and its ground truth.

    Attributes
    ----------
    name : str
        Short name for tables and file names.
    left, right : ndarray of uint8
        (H, W) gray or (H, W, 3) RGB images.
    ground_truth : ndarray of float64 or None
        (H, W) left-referenced disparity in pixels, NaN where unknown.
    """

    name: str
    left: np.ndarray
    right: np.ndarray
    ground_truth: np.ndarray | None

    @property
    def is_colour(self):
        return self.left.ndim == 3

    def gray(self):
        """The pair as 8-bit gray images (BT.601 integer luma for colour pairs)."""
        return to_gray(self.left), to_gray(self.right)


def to_gray(image):
    """ITU-R BT.601 integer luma ``(299 R + 587 G + 114 B + 500) // 1000`` of an 8-bit image.

    Gray (H, W) images are returned unchanged; an alpha channel is ignored.
    """
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise UserError(f"images must be 8-bit, not {image.dtype}")
    if image.ndim == 2:
        return image
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise UserError(f"images must be gray or RGB, not of shape {image.shape}")
    rgb = image[..., :3].astype(np.uint32)
    luma = (299 * rgb[..., 0] + 587 * rgb[..., 1] + 114 * rgb[..., 2] + 500) // 1000
    return luma.astype(np.uint8)


def _open(path, what):
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{what} {path} does not exist")
    try:
        image = Image.open(path)
        image.load()
    except (UnidentifiedImageError, OSError, ValueError) as error:
        raise UserError(f"{what} {path} is not a readable image ({error.__class__.__name__})")
    return image


def check_same_size(left, right, where=""):
    """Raise a one-line :class:`UserError` unless both images have the same height and
    width; ``where`` (e.g. " in folder") completes the message."""
    if left.shape[:2] != right.shape[:2]:
        raise UserError(f"left and right images{where} differ in size: {left.shape[1]}x"
                        f"{left.shape[0]} and {right.shape[1]}x{right.shape[0]}")


def check_gray_pair(left, right):
    """Raise a one-line :class:`ParameterError` unless both images are 8-bit gray (2-D
    uint8), and :func:`check_same_size`'s error unless they have the same size: what the
    matching pipelines (box and SGM) take."""
    for name, image in (("left", left), ("right", right)):
        if image.ndim != 2 or image.dtype != np.uint8:
            raise ParameterError(
                f"{name} image must be 8-bit gray (2-D uint8), not {image.dtype} {image.shape}")
    check_same_size(left, right)


def read_image(path, what="image"):
    """An 8-bit gray (H, W) or RGB (H, W, 3) image as uint8.

    Palette images are expanded to RGB; 16-bit and float images are rejected.
    """
    image = _open(path, what)
    if image.mode in ("L", "RGB"):
        return np.asarray(image)
    if image.mode in ("P", "RGBA", "LA", "PA", "1", "CMYK", "YCbCr"):
        return np.asarray(image.convert("L" if image.mode in ("LA", "1") else "RGB"))
    raise UserError(f"{what} {path} must be an 8-bit gray or RGB image, not mode {image.mode}")


def read_pfm(path, what="ground truth"):
    """A single-channel PFM file as a float64 (H, W) array, top row first."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{what} {path} does not exist")
    data = path.read_bytes()
    try:
        lines = data.split(b"\n", 3)
        kind, size, scale, payload = lines[0].strip(), lines[1].split(), float(lines[2]), lines[3]
        width, height = int(size[0]), int(size[1])
    except (IndexError, ValueError):
        raise UserError(f"{what} {path} is not a PFM file (header 'Pf', size, scale)")
    if kind != b"Pf":
        raise UserError(f"{what} {path} must be a single-channel PFM ('Pf'), not {kind!r}")
    dtype = "<f4" if scale < 0 else ">f4"
    if len(payload) < 4 * width * height:
        raise UserError(f"{what} {path} is truncated: {width}x{height} floats expected")
    values = np.frombuffer(payload, dtype=dtype, count=width * height)
    return values.reshape(height, width)[::-1].astype(np.float64)


def _read_8bit_truth(path, scale, shape):
    image = _open(path, "ground truth")
    if image.mode != "L":
        raise UserError(f"ground truth {path} must be an 8-bit gray image, not mode {image.mode}")
    values = np.asarray(image)
    _check_truth_size(path, values, shape)
    truth = values.astype(np.float64) / scale
    truth[values == 0] = np.nan
    return truth


def _check_truth_size(path, truth, shape):
    if truth.shape != shape[:2]:
        raise UserError(f"ground truth {path} is {truth.shape[1]}x{truth.shape[0]} but the images "
                        f"are {shape[1]}x{shape[0]}")


def _scale_2005(width):
    return 1 if width >= 1000 else 2 if width >= 550 else 3


def _truth_2003(path, shape):
    return _read_8bit_truth(path, 4, shape)


def _truth_2005(path, shape):
    return _read_8bit_truth(path, _scale_2005(shape[1]), shape)


def _truth_2014(path, shape):
    truth = read_pfm(path)
    _check_truth_size(path, truth, shape)
    truth[~np.isfinite(truth)] = np.nan
    return truth


#: Folder layouts: (name, left, right, ground truth, ground-truth reader).
LAYOUTS = (
    ("Middlebury 2003", "im2.png", "im6.png", "disp2.pgm", _truth_2003),
    ("Middlebury 2005/2006", "view1.png", "view5.png", "disp1.png", _truth_2005),
    ("Middlebury 2014", "im0.png", "im1.png", "disp0.pfm", _truth_2014),
)


def load_middlebury(folder):
    """Load a Middlebury scene folder, detecting its layout from the files it holds.

    Parameters
    ----------
    folder : str or Path
        A scene folder of the 2003, 2005/2006 or 2014 datasets (see the module docstring).

    Returns
    -------
    StereoPair
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise UserError(f"dataset folder {folder} does not exist")
    for _, left_name, right_name, truth_name, read_truth in LAYOUTS:
        if (folder / left_name).exists():
            left = read_image(folder / left_name, "left image")
            right = read_image(folder / right_name, "right image")
            check_same_size(left, right, f" in {folder}")
            if left.ndim != right.ndim:
                raise UserError(f"left and right images in {folder} must both be gray or RGB")
            truth = read_truth(folder / truth_name, left.shape)
            return StereoPair(folder.resolve().name, left, right, truth)
    expected = "; ".join(f"{n}: {a}, {b}, {c}" for n, a, b, c, _ in LAYOUTS)
    raise UserError(f"unknown dataset layout in {folder}: expected the files of {expected}")
