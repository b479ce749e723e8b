"""The paper's quality metric: correct matches against a ground truth disparity map."""

from dataclasses import asdict, dataclass

import numpy as np

from ..params import UserError

__all__ = ["Quality", "evaluate", "mean_absolute_error"]


@dataclass(frozen=True)
class Quality:
    """Quality of one disparity map, in percent.

    Attributes
    ----------
    correct : float
        Pixels whose kept disparity is within 1 of the ground truth, over all evaluated
        pixels (invalid pixels count as not correct): the paper's "correct matches".
    density : float
        Valid pixels over all evaluated pixels.
    error_rate : float
        Valid pixels more than 1 off, over the valid pixels (0 when none is valid).
    evaluated : int
        Evaluated pixels: known ground truth and x >= D.
    """

    correct: float
    density: float
    error_rate: float
    evaluated: int

    def as_dict(self):
        return asdict(self)


def evaluate(disparity, ground_truth, disparities, tolerance=1):
    """Correct matches, density and error rate of a disparity map.

    Parameters
    ----------
    disparity : (H, W) int
        Left-referenced disparities, negative for invalid.
    ground_truth : (H, W) float
        True disparity, NaN where unknown.
    disparities : int
        D: columns x < D are not evaluated (the paper leaves them black).
    tolerance : float
        Largest |d - gt| still counted as correct (the paper: 1).
    """
    disparity, ground_truth = np.asarray(disparity), np.asarray(ground_truth, dtype=np.float64)
    if disparity.shape != ground_truth.shape:
        raise UserError(f"ground truth is {ground_truth.shape[1]}x{ground_truth.shape[0]} but "
                        f"the disparity map is {disparity.shape[1]}x{disparity.shape[0]}")
    evaluated = ~np.isnan(ground_truth)
    evaluated[:, :disparities] = False
    total = int(evaluated.sum())
    if total == 0:
        raise UserError(f"no pixel with known ground truth at x >= {disparities} to evaluate")
    valid = evaluated & (disparity >= 0)
    close = np.abs(disparity - np.nan_to_num(ground_truth)) <= tolerance
    correct = int((valid & close).sum())
    n_valid = int(valid.sum())
    return Quality(correct=100.0 * correct / total, density=100.0 * n_valid / total,
                   error_rate=100.0 * (n_valid - correct) / n_valid if n_valid else 0.0,
                   evaluated=total)


def mean_absolute_error(disparity, ground_truth, disparities, tolerance=1):
    """Mean |d - gt| over the correct pixels of :func:`evaluate` (kept, known ground truth,
    x >= D, within ``tolerance``): how close the good matches are, which whole levels
    cannot bring below about a quarter of a level and a sub-pixel fraction can; NaN when
    no pixel is correct."""
    disparity = np.asarray(disparity, dtype=np.float64)
    ground_truth = np.asarray(ground_truth, dtype=np.float64)
    evaluated = ~np.isnan(ground_truth)
    evaluated[:, :disparities] = False
    error = np.abs(disparity - np.nan_to_num(ground_truth))
    good = evaluated & (disparity >= 0) & (error <= tolerance)
    return float(error[good].mean()) if good.any() else float("nan")
