"""Semi-global aggregation's parameters: its paths, penalties, defaults and widths, once.

docs/semantics.md, "Semi-global aggregation", is the contract; the golden model
(``golden/sgm.py``), the hardware (``hdl/sgm.py``) and the command line take every path,
rule and default from here.
"""

from types import MappingProxyType

from .errors import ParameterError, is_integral

__all__ = ["SGM", "sgm_path_steps", "SGM_PATH_STEPS", "SGM_PATHS", "SGM_PATH_COUNT",
           "SGM_ROW_PATHS", "check_sgm_paths", "SGM_DEFAULT_P1", "SGM_DEFAULT_P2",
           "SGM_DEFAULT_ADAPT", "SGM_MAX_ADAPT", "P2_ADAPT_OFF", "SGM_RECOMMENDED",
           "max_path_penalty", "check_penalties", "sgm_path_cost_bits",
           "sgm_summed_cost_bits"]

#: The ``aggregation`` value that replaces the A x A box by semi-global aggregation along
#: the raster-order paths (docs/semantics.md, "Semi-global aggregation").
SGM = "sgm"


def sgm_path_steps(steps):
    """``steps`` ({path: (dx, dy)} from a pixel to its predecessor) as a read-only mapping,
    once every path is one a raster-order stream can compute: its predecessor is a
    neighbour the stream has passed already, the pixel to the left or one of the three in
    the row above. Else a one-line :class:`ParameterError`.

    The golden model computes a path with dy = 0 as the left path and the others from the
    row above; a path from the right or from below would silently be computed as another.
    """
    for path, (dx, dy) in steps.items():
        if not ((dy == -1 and -1 <= dx <= 1) or (dy, dx) == (0, -1)):
            raise ParameterError(
                f"SGM path {path!r} cannot be computed in raster order: its predecessor "
                f"(dx, dy) must be (-1, 0) or (-1 .. 1, -1), not {(dx, dy)}")
    return MappingProxyType(dict(steps))


#: The paths, each named by the direction it comes from, in the order they are summed:
#: (dx, dy) from a pixel p to its predecessor p - r (docs/semantics.md, "Paths and the
#: recurrence").
SGM_PATH_STEPS = sgm_path_steps({"left": (-1, 0), "top-left": (-1, -1), "top": (0, -1),
                                 "top-right": (1, -1)})
SGM_PATHS = tuple(SGM_PATH_STEPS)
#: Paths an SGM core sums: what its widths are made for.
SGM_PATH_COUNT = len(SGM_PATHS)
#: Paths whose predecessor lies in the previous row: the hardware keeps that row's path
#: costs in block RAM, the golden model carries them from one band of rows to the next.
SGM_ROW_PATHS = tuple(path for path, (_, dy) in SGM_PATH_STEPS.items() if dy == -1)


def check_sgm_paths(paths):
    """Raise a one-line :class:`ParameterError` unless ``paths`` is a non-empty set of
    distinct names among :data:`SGM_PATHS` (a subset, for tests and experiments)."""
    paths = tuple(paths)
    if not paths or len(set(paths)) != len(paths) or any(p not in SGM_PATH_STEPS for p in paths):
        raise ParameterError(
            f"SGM paths must be distinct names among {', '.join(SGM_PATHS)}, not {paths!r}")


#: The recommended SGM penalties, chosen by measurement together with census 7x7
#: (docs/quality.md, "SGM: choosing the defaults"): P1, P2 and the adaptive-P2 exponent t.
#: They make the census 7x7 path cost bitlen(48 + 79) = 7 bits, what the block-RAM budget
#: allows at 450 x 375, D = 100.
SGM_DEFAULT_P1 = 24
SGM_DEFAULT_P2 = 79
SGM_DEFAULT_ADAPT = 5
#: Adaptive P2 works on 8-bit gray steps g <= 255 (at most 8 bits): from t = 8 on the shift
#: bitlen(g) - t is never positive, so such a t would be a constant P2 in disguise.
SGM_MAX_ADAPT = 7
#: ``StereoParams.p2_adapt`` value of a constant P2 (``None`` there means the default t).
P2_ADAPT_OFF = 0

#: The SGM configurations the paper report, the demo and the peers benchmark show, as
#: ``StereoParams`` fields (add ``disparities``): the default (census 7x7 with the default
#: penalties), and census 5x5 with the penalties best on clean real scenes, the cheapest
#: core (docs/quality.md).
SGM_RECOMMENDED = (
    MappingProxyType({"transform": "census", "block": 7, "aggregation": SGM,
                      "p1": SGM_DEFAULT_P1, "p2": SGM_DEFAULT_P2,
                      "p2_adapt": SGM_DEFAULT_ADAPT}),
    MappingProxyType({"transform": "census", "block": 5, "aggregation": SGM, "p1": 16,
                      "p2": 96, "p2_adapt": 4}),
)


def max_path_penalty(max_cost):
    """Largest P2 allowed for a matching cost of maximum ``max_cost`` (P2max).

    The path cost may be at most two bits wider than the matching cost:
    Cmax + P2 <= 2^(bitlen(Cmax) + 2) - 1. For census 5x5 (Cmax = 24) that is P2 <= 103,
    which keeps the path cost at 7 bits, the width the block-RAM budget allows at
    450 x 375, D = 100.
    """
    return (1 << (int(max_cost).bit_length() + 2)) - 1 - int(max_cost)


def check_penalties(max_cost, p1, p2, adapt=None):
    """Validate SGM penalties; raise :class:`ParameterError` with a one-line message.

    The one definition of the rules, for :class:`~npstereo.params.StereoParams` and the
    golden model's whole-image functions (``npstereo.golden.sgm``).

    Parameters
    ----------
    max_cost : int
        Cmax, the largest matching cost of the transform (``StereoParams.max_cost``).
    p1, p2 : int
        Penalties: 0 <= P1 <= P2 <= :func:`max_path_penalty` (Cmax).
    adapt : int or None
        Adaptive-P2 threshold exponent t, 1 <= t <= :data:`SGM_MAX_ADAPT`, or None for a
        constant P2.
    """
    if not is_integral(p1) or p1 < 0:
        raise ParameterError(f"P1 must be an integer >= 0, not {p1!r}")
    if not is_integral(p2) or p2 < p1:
        raise ParameterError(f"P2 must be an integer >= P1 ({p1}), not {p2!r}")
    limit = max_path_penalty(max_cost)
    if p2 > limit:
        raise ParameterError(
            f"P2 must be <= {limit} for a matching cost of at most {max_cost} (path cost "
            f"at most {int(max_cost).bit_length() + 2} bits), not {p2!r}")
    if adapt is not None and (not is_integral(adapt) or not 1 <= adapt <= SGM_MAX_ADAPT):
        raise ParameterError(f"adaptive P2 exponent must be an integer 1 .. {SGM_MAX_ADAPT} "
                             f"(or off), not {adapt!r}")


def sgm_path_cost_bits(max_cost, p2):
    """Width of a path cost L_r and of its minimum: bitlen(Cmax + P2).

    Every candidate of the recurrence's minimum is >= the predecessor's minimum m and the
    last one is m + P2, so 0 <= L_r <= Cmax + P2 (docs/semantics.md, "Widths").
    """
    return (int(max_cost) + int(p2)).bit_length()


def sgm_summed_cost_bits(max_cost, p2, paths=SGM_PATH_COUNT):
    """Width of the summed cost S over ``paths`` paths: bitlen(paths (Cmax + P2))."""
    return (paths * (int(max_cost) + int(p2))).bit_length()
