"""The four transforms of the paper, each described once.

Whatever differs between transforms is read from its :class:`TransformSpec`: the widths of
:class:`~npstereo.params.StereoParams`, the line buffer ``auto`` chooses, the hardware's
register plans and copies; the golden model's and the hardware's functions are kept in
tables keyed by these names, each checked against :data:`TRANSFORMS` at import by
:func:`check_transform_table`. docs/hardware.md, "Adding a transform", lists the files a
new transform touches.
"""

from dataclasses import dataclass
from types import MappingProxyType
from typing import Callable

__all__ = ["REDUCTIONS", "TransformSpec", "TRANSFORM_SPECS", "TRANSFORMS",
           "check_transform_table"]

#: How k per-neighbour values are reduced to one: a popcount of bits, a sum of absolute
#: differences of bytes, or not at all (None).
REDUCTIONS = (None, "popcount", "sad")

#: What ``line_buffer="auto"`` may keep of the rows above (StereoParams.LINE_BUFFERS but
#: "auto").
_STORED_ROWS = ("costs", "transforms", "pixels")


@dataclass(frozen=True)
class TransformSpec:
    """One transform (paper Eq. 1-9; docs/semantics.md, "Transforms" and "Matching costs").

    Attributes
    ----------
    name : str
        As the command line spells it.
    transform_bits : callable
        Width of one transformed pixel, as a function of the k neighbours.
    max_cost : callable
        Largest matching cost of a pixel pair (Cmax), as a function of k.
    compares : bool
        Per neighbour the comparison xi(P, P') of Eq. 1 (one bit); else the absolute
        difference |P - P'| of Eq. 6 (one byte). A comparison with a neighbour outside the
        frame (a 0 pixel) is centre != 0, so the hardware may mask after comparing.
    transform_reduction : str or None
        How the transform reduces its k per-neighbour values (:data:`REDUCTIONS`): a
        popcount (rank), a sum of absolute differences (ext. rank), or None: it keeps
        them (census, ext. census).
    cost_reduction : str or None
        How the matching cost reduces a pair of transformed pixels: the popcount of their
        XOR (census), the sum of the absolute differences of their bytes (ext. census), or
        None: one absolute difference of two numbers (rank, ext. rank).
    auto_stored_rows : str
        What ``line_buffer="auto"`` keeps of the rows above: what is narrow, while what is
        cheap is computed again ("pixels", "transforms" or "costs").
    centre_fanout : int
        Comparisons or differences one copy of the window's centre feeds in hardware.
    golden_weight : int
        Relative run time of the golden model per window pixel, to start the slowest jobs
        first.
    """

    name: str
    transform_bits: Callable[[int], int]
    max_cost: Callable[[int], int]
    compares: bool
    transform_reduction: str | None
    cost_reduction: str | None
    auto_stored_rows: str
    centre_fanout: int
    golden_weight: int

    def __post_init__(self):
        for field in ("transform_reduction", "cost_reduction"):
            if getattr(self, field) not in REDUCTIONS:
                raise ValueError(f"{self.name}: {field} must be one of {REDUCTIONS}, not "
                                 f"{getattr(self, field)!r}")
        if self.auto_stored_rows not in _STORED_ROWS:
            raise ValueError(f"{self.name}: auto_stored_rows must be one of {_STORED_ROWS}, "
                             f"not {self.auto_stored_rows!r}")

    @property
    def sums_differences(self):
        """Whether the transform or its cost is a sum of absolute differences, the logic
        ``StereoParams.lut_inputs`` arranges (ext. rank, ext. census)."""
        return "sad" in (self.transform_reduction, self.cost_reduction)


#: The transforms by name, in the paper's order. Auto line buffers: census keeps pixels
#: (a k-bit word, one comparison per bit to compute again), rank and ext. rank keep their
#: transformed pixels (one number each, but a sum over the window to compute again), ext.
#: census keeps costs (its transform is 8k bits wide and its cost, k byte-wise differences
#: and their sum, too large to compute A times). Centre copies: one per 8 comparisons, but
#: one per 4 differences, each an 8-bit carry chain in a clock of its own with the copy's
#: routing in front (at 8 per copy that routing was ext. rank 9x9's critical path, 6.7 ns,
#: 149.5 MHz on ECP5). Golden run time: ext. census's cost sums k bytes per pair and
#: disparity, about four times the others'.
TRANSFORM_SPECS = MappingProxyType({spec.name: spec for spec in (
    TransformSpec("rank", transform_bits=lambda k: k.bit_length(), max_cost=lambda k: k,
                  compares=True, transform_reduction="popcount", cost_reduction=None,
                  auto_stored_rows="transforms", centre_fanout=8, golden_weight=1),
    TransformSpec("census", transform_bits=lambda k: k, max_cost=lambda k: k,
                  compares=True, transform_reduction=None, cost_reduction="popcount",
                  auto_stored_rows="pixels", centre_fanout=8, golden_weight=1),
    TransformSpec("ext-rank", transform_bits=lambda k: (255 * k).bit_length(),
                  max_cost=lambda k: 255 * k, compares=False, transform_reduction="sad",
                  cost_reduction=None, auto_stored_rows="transforms", centre_fanout=4,
                  golden_weight=1),
    TransformSpec("ext-census", transform_bits=lambda k: 8 * k, max_cost=lambda k: 255 * k,
                  compares=False, transform_reduction=None, cost_reduction="sad",
                  auto_stored_rows="costs", centre_fanout=4, golden_weight=4),
)})

#: Transform names as the command line spells them, in the paper's order.
TRANSFORMS = tuple(TRANSFORM_SPECS)


def check_transform_table(table, what):
    """``table`` itself, once its keys are exactly :data:`TRANSFORMS`; else a one-line
    :class:`LookupError` naming ``what``.

    Every table of per-transform functions (golden model, hardware) passes through here at
    import, so a transform described in :data:`TRANSFORM_SPECS` without its function fails
    at once, not in the middle of a run.
    """
    missing = [name for name in TRANSFORMS if name not in table]
    unknown = [str(name) for name in table if name not in TRANSFORM_SPECS]
    if missing or unknown:
        raise LookupError(f"{what} must have one entry per transform "
                          f"({', '.join(TRANSFORMS)}): missing {', '.join(missing) or 'none'}, "
                          f"unknown {', '.join(unknown) or 'none'}")
    return table
