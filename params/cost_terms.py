"""Terms added to the matching cost (``StereoParams.cost_term``, ``--cost-term``), once.

``ad3`` (issue 28, docs/sgm.md "Quality options"): a 3x3 sum of clipped absolute
differences of the gray pixels, reduced to 0 .. 7 and added to the census Hamming
distance, so that weak texture and noise, where census bits flip, still see the pixels'
difference. docs/semantics.md ("The ad3 cost term") is the exact contract; the golden model
(``golden/cost_term.py``) and the hardware (``hdl/cost_term.py``) take every constant here.
"""

from types import MappingProxyType

from .errors import ParameterError

__all__ = ["COST_TERMS", "AD3_CLIP", "AD3_LIMIT", "AD3_SHIFT", "AD3_MAX", "AD3_DEFAULT_P2",
           "term_max", "check_cost_term"]

#: The cost terms there are (``None``: the transform's cost alone, the default).
COST_TERMS = ("ad3",)
#: Each absolute difference is clipped to this (5 bits): one outlier pixel cannot dominate.
AD3_CLIP = 31
#: The 3x3 sum is clipped to this (8 bits), then shifted right by AD3_SHIFT: 0 .. 7.
AD3_LIMIT = 255
AD3_SHIFT = 5
#: Largest value of the term: Cmax grows by this much (census 7x7: 48 -> 55).
AD3_MAX = AD3_LIMIT >> AD3_SHIFT
#: SGM's default P2 with the term: 72 instead of 79, so that census 7x7's path cost stays
#: 7 bits (55 + 72 = 127), the width the defaults' block-RAM budget is made for; P1 and t
#: keep their defaults. The options study measured the term at 24/72/5 (docs/sgm.md).
AD3_DEFAULT_P2 = 72

#: Per term: (largest value, the transforms it is defined for).
_TERMS = MappingProxyType({"ad3": (AD3_MAX, ("census",))})


def term_max(cost_term):
    """How much ``cost_term`` adds to Cmax (0 without a term)."""
    return 0 if cost_term is None else _TERMS[cost_term][0]


def check_cost_term(cost_term, transform, is_sgm, aggregation):
    """Raise a one-line :class:`ParameterError` unless ``cost_term`` is None or a term of
    :data:`COST_TERMS` on a transform and aggregation it is defined for (census and SGM:
    what the options study measured and the hardware builds)."""
    if cost_term is None:
        return
    if cost_term not in _TERMS:
        raise ParameterError(f"cost term must be one of {', '.join(COST_TERMS)} (or none), "
                             f"not {cost_term!r}")
    transforms = _TERMS[cost_term][1]
    if transform not in transforms:
        raise ParameterError(f"cost term {cost_term} needs the {' or '.join(transforms)} "
                             f"transform, not {transform}")
    if not is_sgm:
        raise ParameterError(f"cost term {cost_term} needs aggregation 'sgm', not a "
                             f"{aggregation}x{aggregation} box")
