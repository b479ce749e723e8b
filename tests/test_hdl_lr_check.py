"""LRCheck alone: aggregated costs of a few rows in, output words out, against the golden
right-referenced WTA and consistency check.

The costs are random and drawn from a narrow range, so that ties are everywhere and the tie
rule shows; slots without a position (bubbles) are mixed in, as the core does when its
input or output stalls.
"""

import numpy as np
import pytest
from amaranth.sim import Simulator

from npstereo.golden.lr_check import invalidate_border, lr_check
from npstereo.params import StereoParams
from npstereo.golden.wta import RightWTA
from npstereo.hdl import lr_check as hdl_lr_check
from npstereo.hdl.lr_check import LRCheck

#: Clocks between the costs of a position and its left winner at the stage's inputs.
LEFT_OFFSET = 3


def check(disparities, rounds, threshold, gaps, seed=1, height=3):
    """Run one LRCheck; returns the number of output pixels that differ from the golden."""
    width = disparities + 8
    params = StereoParams(transform="census", block=3, disparities=disparities, rounds=rounds,
                          aggregation=1, lr_threshold=threshold, width=width, height=height)
    rng = np.random.default_rng(seed)
    costs = rng.integers(0, 9, (disparities, height, width))
    right = RightWTA((height, width), np.int64)
    for d in range(disparities):
        right.update(costs[d], d)
    left = np.argmin(costs, axis=0).astype(np.int16)
    expected = invalidate_border(left if threshold is None else
                                 lr_check(left, right.best_disparity, threshold), params)
    # One entry per clock: (x, y, valid, round); positions below the frame flush the stage.
    slots = []
    for position in [(x, y) for y in range(height) for x in range(width)] + \
            [(0, height + 2)] * (disparities + 4):
        slots.append((*position, True))
        while rng.random() < gaps:
            slots.append((0, 0, False))
    clocks = [(x, y, valid, j) for x, y, valid in slots for j in range(rounds)]
    clocks += [(0, 0, False, j) for _ in range(20) for j in range(rounds)]
    stage = LRCheck(params, LEFT_OFFSET)
    units = params.per_round
    words = {}

    def inside(y):
        return 0 <= y < height

    async def bench(ctx):
        for t, (x, y, valid, j) in enumerate(clocks):
            ctx.set(stage.first, j == 0)
            ctx.set(stage.round, j)
            ctx.set(stage.tag, {"x": x, "y": y, "valid": valid, "live": 1})
            for i in range(units):
                ctx.set(stage.sums[i], int(costs[j * units + i, y, x]) if valid and inside(y)
                        else 0)
            if t >= LEFT_OFFSET:
                x2, y2, valid2, _ = clocks[t - LEFT_OFFSET]
                ctx.set(stage.left_tag, {"x": x2, "y": y2, "valid": valid2, "live": 1})
                ctx.set(stage.disparity, int(left[y2, x2]) if valid2 and inside(y2) else 0)
            await ctx.tick()
            if ctx.get(stage.produce):
                words[(ctx.get(stage.y), ctx.get(stage.x))] = (
                    ctx.get(stage.disparity_out) if ctx.get(stage.valid) else -1)

    sim = Simulator(stage)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    got = np.full((height, width), -2, np.int16)
    for (y, x), value in words.items():
        got[y, x] = value
    return int(np.count_nonzero(got != expected))


# 26 units at R = 1 and 2 x 13 at R = 2: three and two copies of the write enable.
@pytest.mark.parametrize("disparities, rounds", [(4, 1), (8, 1), (8, 2), (12, 3), (16, 4),
                                                 (6, 6), (26, 1), (26, 2)])
@pytest.mark.parametrize("threshold", [0, 1, None])
def test_matches_golden(disparities, rounds, threshold):
    assert check(disparities, rounds, threshold, gaps=0.3) == 0


def test_broken_right_tie_rule_is_caught(monkeypatch):
    """``<=`` in the right-referenced WTA: equal costs going to the higher disparity."""
    monkeypatch.setattr(hdl_lr_check, "better", lambda candidate, held: candidate <= held)
    assert check(8, 2, 0, gaps=0.3) > 0


def test_broken_write_enable_copy_is_caught(monkeypatch):
    """One copy of the right winners' write enable a clock late: its units keep a stale
    winner for a clock."""
    original = hdl_lr_check._write_enables

    def late_last_copy(slots, valid, stage_b, units):
        copies = original(slots, valid, stage_b, units)
        return copies[:-1] + [slots.delay(copies[-1], stage_b, 1, "late_copy")]
    monkeypatch.setattr(hdl_lr_check, "_write_enables", late_last_copy)
    assert check(26, 1, 0, gaps=0.3) > 0


def test_broken_consistency_test_is_caught(monkeypatch):
    """``<`` instead of ``<=`` in |dL - dR| <= T."""
    monkeypatch.setattr(hdl_lr_check, "_consistent",
                        lambda partner, low, high: (partner > low) & (partner < high))
    assert check(8, 2, 0, gaps=0.3) > 0
