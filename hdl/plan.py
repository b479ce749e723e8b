"""What the hardware is generated for: the limits, checked before anything is built.

The hardware facts are pure functions of the parameters, in three modules by job:
:mod:`.plan_structure` (what the components build: register plans, window rows, copies,
slices, widths), :mod:`.plan_timing` (clock offsets, latency, cycles per frame) and
:mod:`.plan_memories` (the memories and their bits). Nothing there constructs or
elaborates a component, so a caller can ask for a number without building the design; and
since the components read their plans from there, the numbers cannot drift from what they
build (``tests/test_hdl_plan.py`` also measures them on the elaborated hardware, and
``tests/test_report.py`` checks the memories against Yosys).

This module holds the limits the hardware is generated within (:func:`check_buildable`);
callers import each fact from the module that defines it.
"""

from ..params import ParameterError
from .plan_timing import sgm_timing

__all__ = ["MAX_WIDTH", "MAX_BLOCK", "MAX_DISPARITIES", "sgm_min_width", "check_buildable"]


#: Widest frame the hardware is generated for. 8192 covers 8K video (7680); the line
#: buffers are W deep (the costs line buffer W * R), so a wider frame only grows memories
#: no FPGA of the paper's class holds next to the logic, while generation time grows with
#: the depth of every memory.
MAX_WIDTH = 8192


#: Largest transform window. The paper sweeps 7 .. 19; at 31 x 31 an extended census word
#: is 7,680 bits and the stores of the right transforms hold D of them; generation time
#: grows with B^2 per cost unit.
MAX_BLOCK = 31


#: Largest disparity range: 256 is the most an 8-bit disparity word holds.
MAX_DISPARITIES = 256


def sgm_min_width(params):
    """Narrowest frame the SGM stage is built for: a position's path costs and minima go
    back to memory ``timing.minima`` clocks after its slot (the minima last), and position
    x - 1 of the next row reads them (W - 1) R clocks after it, so (W - 1) R must reach
    that (census 5x5, D = 8, R = 1: W >= 18; it only binds for small D at R = 1 or 2,
    whose frames are wider than D anyway)."""
    return 1 + -(-sgm_timing(params).minima // params.rounds)


def check_buildable(params):
    """Raise :class:`ParameterError` unless the hardware can be generated for ``params``.

    The golden model runs any size; the hardware needs the frame size and stays within
    :data:`MAX_WIDTH`, :data:`MAX_BLOCK` and :data:`MAX_DISPARITIES`, checked before
    anything is built so that an oversized request fails at once instead of elaborating
    for minutes. Semi-global aggregation takes any number of rounds that divides D.
    """
    if params.width is None or params.height is None:
        raise ParameterError("the hardware needs the image size: give width and height "
                             "(--width and --height)")
    if params.width > MAX_WIDTH:
        raise ParameterError(f"image width must be <= {MAX_WIDTH} for the hardware, "
                             f"not {params.width}")
    if params.block > MAX_BLOCK:
        raise ParameterError(f"block size must be <= {MAX_BLOCK} for the hardware, "
                             f"not {params.block}")
    if params.disparities > MAX_DISPARITIES:
        raise ParameterError(f"disparities must be <= {MAX_DISPARITIES} for the hardware, "
                             f"not {params.disparities}")
    if params.is_sgm and params.width < sgm_min_width(params):
        raise ParameterError(f"image width must be >= {sgm_min_width(params)} for semi-global "
                             f"aggregation at D = {params.disparities}, R = {params.rounds} "
                             f"(the rows above are written back too late for a narrower "
                             f"frame), not {params.width}")
