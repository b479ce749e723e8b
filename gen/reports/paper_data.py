"""The paper's data (Ambrosch et al. 2008): its quality and resource figures, and the
sweep that puts ours beside them.

Correct matches on teddy (Fig. 6 clean, Fig. 8 with gaussian noise), which ``npstereo
paper`` reproduces; Stratix II EP2S180 logic elements and memory bits of the four
transforms at block sizes 7 .. 19 (Figs. 13 and 14, 450 x 375, D = 100, R = 10) and the
clock the paper states, with the configurations ``npstereo report --paper`` runs.
"""

import dataclasses

from ...params import TRANSFORM_SPECS, TRANSFORMS, StereoParams

__all__ = ["PAPER_BLOCKS", "PAPER_FIG6", "PAPER_FIG8", "PAPER_NOISE", "PAPER_LOGIC",
           "PAPER_DID_NOT_FIT", "PAPER_MEMORY", "PAPER_CLOCK", "PAPER_SIZE",
           "PAPER_DISPARITIES", "PAPER_ROUNDS", "paper_configurations", "is_default_line_buffer",
           "SAD_TRANSFORMS", "sweep_targets"]

#: Block sizes of the paper's figures 6, 8, 13 and 14.
PAPER_BLOCKS = (7, 9, 11, 13, 15, 17, 19)

#: Fig. 6, correct matches (%) on teddy, 7x7 .. 19x19 (clean text in the paper's data table).
PAPER_FIG6 = {
    "rank": (39.16, 42.17, 43.88, 44.82, 45.27, 45.37, 45.11),
    "ext-rank": (43.67, 44.73, 44.86, 44.76, 44.27, 43.57, 42.50),
    "census": (73.22, 76.15, 76.98, 76.91, 76.24, 75.35, 74.49),
    "ext-census": (74.01, 76.13, 76.06, 75.34, 74.34, 73.17, 72.00),
}

#: Fig. 8 (teddy, gaussian noise 0.002): best reading of the PDF extraction, which scrambles
#: the figure's data table. Low confidence; None where no number could be assigned. The
#: reasoning is in docs/quality.md.
PAPER_FIG8 = {
    "rank": (9.02, 9.29, 9.76, 10.37, 11.16, 11.70, None),
    "ext-rank": (18.01, 18.98, 19.09, 19.14, 19.43, 19.58, None),
    "census": (26.16, 32.69, 37.57, 44.24, 41.31, 40.42, None),
    "ext-census": (26.59, 30.68, 33.85, 38.57, 36.31, 30.11, None),
}
#: The variance of Fig. 8's gaussian noise (on the [0, 1] scale).
PAPER_NOISE = 0.002

#: Stratix II logic elements (Fig. 13); None where the design did not fit and no figure exists.
PAPER_LOGIC = {
    "rank": (10174, 13514, 17475, 21999, 23554, 28686, 34053),
    "ext-rank": (17624, 24673, 33179, 43406, 52356, 64524, 79015),
    "census": (17713, 26788, 38006, 51370, 62998, 79664, 97824),
    "ext-census": (80598, 131616, 148213, 205448, 272068, 348133, None),
}
#: Blocks where the paper's ext. census did not fit the EP2S180 (figure value still given).
PAPER_DID_NOT_FIT = {("ext-census", b) for b in (11, 13, 15, 17, 19)}
_RANK_MEMORY = (557056, 589824, 622592, 655360, 688128, 720896, 753664)
_CENSUS_MEMORY = (688128, 720896, 753664, 786432, 819200, 851968, 884736)
#: Memory bits (Fig. 14).
PAPER_MEMORY = {"rank": _RANK_MEMORY, "ext-rank": _RANK_MEMORY,
                "census": _CENSUS_MEMORY, "ext-census": _CENSUS_MEMORY}
#: The paper's clock in MHz, given only at the ends of the sweep.
PAPER_CLOCK = {7: 100.0, 19: 50.0}
PAPER_SIZE = (450, 375)
PAPER_DISPARITIES, PAPER_ROUNDS = 100, 10


#: Transforms with sums of absolute differences (the ext. rank transform, the ext. census
#: cost), whose arithmetic ``lut_inputs`` arranges: the sweep has them for both LUT sizes.
SAD_TRANSFORMS = tuple(name for name, spec in TRANSFORM_SPECS.items() if spec.sums_differences)


def paper_configurations(line_buffers=("transforms", "costs", "pixels")):
    """The paper's sweep, one configuration per transform, block and line buffer (the
    hardware's three ways to keep the rows above: a user trades block RAM for logic), and
    for :data:`SAD_TRANSFORMS` each of those again arranged for 6-input LUTs (measured on
    Cyclone V only, :func:`sweep_targets`)."""
    width, height = PAPER_SIZE
    return [StereoParams(transform=t, block=b, disparities=PAPER_DISPARITIES,
                         rounds=PAPER_ROUNDS, width=width, height=height, line_buffer=lb,
                         lut_inputs=lut)
            for b in PAPER_BLOCKS for t in TRANSFORMS for lut in (4, 6) for lb in line_buffers
            if lut == 4 or t in SAD_TRANSFORMS]


def sweep_targets(params, targets):
    """The targets of ``targets`` the sweep measures ``params`` on: a core arranged for
    6-input LUTs is not measured on the ECP5, whose LUTs have 4 (it would be larger there
    than the one arranged for them)."""
    return tuple(t for t in targets if not (t == "ecp5" and params.lut_inputs == 6))


def is_default_line_buffer(params):
    """Whether ``params`` keeps the rows above as ``line_buffer="auto"`` would."""
    return params.stored_rows == dataclasses.replace(params, line_buffer="auto").stored_rows
