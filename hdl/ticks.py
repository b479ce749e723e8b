"""The ports of a stage of output words between the L/R check and the output queue.

Such a stage (:class:`~.median.Median3`, :class:`~.mirror.RowTurn`) takes one word per
*tick* (a retire pulse of the L/R check: every slot with a position, in the frame or not)
and gives one per tick, so the core's credits (one per position) balance whatever it
delays.
"""

from dataclasses import dataclass

from amaranth.hdl import Value
from amaranth.lib.wiring import In, Out

from .common import tag_layout

__all__ = ["tick_ports", "TickWords", "ticked"]


def tick_ports(params, bits):
    """A tick, a word of the frame with it (``produce``), the word (``valid``, a
    ``bits``-wide disparity) and its position in; the same out (``*_out``) with the output
    position's framing flags."""
    layout = tag_layout(params)
    return {
        "retire": In(1), "produce": In(1), "valid": In(1), "disparity": In(bits),
        "x": In(layout["x"].shape), "y": In(layout["y"].shape),
        "retire_out": Out(1), "produce_out": Out(1), "valid_out": Out(1),
        "disparity_out": Out(bits),
        "frame_start": Out(1), "line_end": Out(1), "frame_end": Out(1),
    }


@dataclass(frozen=True)
class TickWords:
    """The words a stage gives per tick: what the next tick stage, or the output queue and
    the credits, take. ``x`` and ``y`` are None where no stage follows that needs them."""
    retire: Value
    produce: Value
    valid: Value
    disparity: Value
    x: Value | None
    y: Value | None
    frame_start: Value
    line_end: Value
    frame_end: Value


def ticked(m, stage, words):
    """``words`` into the tick stage ``stage`` (a submodule of ``m``): its words."""
    m.d.comb += [stage.retire.eq(words.retire), stage.produce.eq(words.produce),
                 stage.valid.eq(words.valid), stage.disparity.eq(words.disparity),
                 stage.x.eq(words.x), stage.y.eq(words.y)]
    return TickWords(stage.retire_out, stage.produce_out, stage.valid_out, stage.disparity_out,
                     getattr(stage, "x_out", None), getattr(stage, "y_out", None),
                     stage.frame_start, stage.line_end, stage.frame_end)
