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
           "max_path_penalty", "check_penalties", "SGM_TRACK_STEPS", "SGM_TRACK_AGE",
           "SGM_LEFT_P1_PARITY",
           "sgm_path_cost_bits", "sgm_left_cost_bits", "sgm_left_loop_bits",
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


#: The left path's reference of the large step (docs/semantics.md, "Semi-global
#: aggregation"): the path cost of the disparity b that was best SGM_TRACK_AGE (K) positions
#: back, carried forward from SGM_TRACK_STEPS (J) positions back by adding the matching
#: costs of b in between. Exact SGM's reference, the minimum over all D path costs of the
#: position just before, cannot close at one position per clock; this one needs nothing
#: newer than J positions back. Why these values: at one position per clock (R = 1) the
#: loop spans two positions (:data:`SGM_LEFT_P1_PARITY`) and compares ref(x) a clock before
#: a one-position loop would, so J = 8 positions cover the registers of the multiplexer
#: that picks lane b, the final additions and that clock, and the K - J = 24 the registered
#: argmin tree over D <= 256 and its hand-off. docs/sgm/left_path_study.py measured J = 8,
#: K = 32 with P1 into odd columns within 0.14 points of J = 4, K = 16 with P1 into every
#: column (docs/sgm.md, "Two clocks at R = 1").
SGM_TRACK_STEPS = 8
SGM_TRACK_AGE = 32

#: The left path's small step (P1, d +- 1) is taken only into the columns x with
#: x % 2 == SGM_LEFT_P1_PARITY; into the others the path stays at d or takes the large step.
#: Then Lu(x) of an even column depends on Lu(x - 2) through one comparison of neighbours,
#: not two, and the loop closes over two positions in two clocks at one position per clock
#: (docs/semantics.md, "The left path").
SGM_LEFT_P1_PARITY = 1

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
    """Width of a path cost L_r of a path from the row above and of its minimum:
    bitlen(Cmax + P2).

    Every candidate of the recurrence's minimum is >= the predecessor's minimum m and the
    last one is m + P2, so 0 <= L_r <= Cmax + P2 (docs/semantics.md, "Widths").
    """
    return (int(max_cost) + int(p2)).bit_length()


def _left_bound(max_cost, p2):
    """K Cmax + P2, the largest L of the left path (docs/semantics.md, "Widths")."""
    return SGM_TRACK_AGE * int(max_cost) + int(p2)


def sgm_left_cost_bits(max_cost, p2):
    """Width of the left path's L: bitlen(K Cmax + P2).

    Its reference of the large step is an upper bound of the previous position's minimum
    m(x - 1) that exceeds the minimum K positions back by at most (K - 1) Cmax, and m never
    decreases along the row, so 0 <= L <= K Cmax + P2 (docs/semantics.md, "Widths").
    """
    return _left_bound(max_cost, p2).bit_length()


def sgm_left_loop_bits(max_cost, p1, p2):
    """Width n of the hardware's unnormalised left path cost Lu, kept modulo 2^n.

    All values a step compares lie in [m(x-1), m(x-1) + K Cmax + P2 + P1], and the values of
    one position in [m(x-1), m(x-1) + K Cmax + P2]; the loop over two positions at R = 1
    compares the candidates of Lu(x - 1) plus C(x - 1) with ref(x) + P2(x), one Cmax more.
    Every difference is below 2^(n-1), so the sign bit of an n-bit difference orders them
    (docs/semantics.md, "Widths").
    """
    return (_left_bound(max_cost, p2) + int(max_cost) + int(p1)).bit_length() + 1


def sgm_summed_cost_bits(max_cost, p2, fifth_path=False):
    """Width of the summed cost S of all paths: bitlen((K Cmax + P2) + 3 (Cmax + P2)), the
    left path's bound plus the three paths from the row above; with the fifth path (the
    left path mirrored, bounded alike) bitlen(2 (K Cmax + P2) + 3 (Cmax + P2))."""
    rows = SGM_PATH_COUNT - 1
    along = 2 if fifth_path else 1
    return (along * _left_bound(max_cost, p2) + rows * (int(max_cost) + int(p2))).bit_length()
