"""The ``ad3`` cost term in hardware (hdl/cost_term.py in the calculation stage): every
matching cost C(x, y, d) that enters the SGM aggregation of the core against the golden
model's cost volume (golden/sgm.py with golden/cost_term.py), at R = 1, 2, 3 and D, with
random input gaps and backpressure and stale memories; the whole map of a core; and the
broken variants the comparison must catch."""

import random

import numpy as np
import pytest
from amaranth.hdl import Const, Shape

from npstereo.golden import sgm as golden_sgm
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import calculation_stage, cost_term
from npstereo.hdl.core import NpStereoCore
from npstereo.params import StereoParams

from hdl_helpers import (check_frames, frame_beats, random_contents, record_memories,
                         simulate)
from scenes import stereo_pair

GAPS = 0.65


def term_params(block, disparities, rounds, width, height, **changes):
    return StereoParams("census", block, disparities, rounds, aggregation="sgm",
                        cost_term="ad3", p1=3, p2=20, p2_adapt=2, width=width,
                        height=height, **changes)


def hardware_costs(params, pair, seed, before_start=None):
    """C(x, y, d) as the core hands it to the SGM aggregation, {(y, x, d): C} over the
    frame, with random input gaps and backpressure."""
    core = NpStereoCore(params)
    aggregation = core.calculation_stage.aggregation
    beats, rng = frame_beats(*pair), random.Random(seed)
    height, width, units = params.height, params.width, params.per_round
    got, words = {}, 0

    async def bench(ctx):
        nonlocal words
        if before_start is not None:
            before_start(ctx)
        index, idle = 0, 0
        while idle < 4 * core.latency * params.rounds + 50:
            offering = index < len(beats) and rng.random() < GAPS
            if offering:
                pixels, first, last = beats[index]
                ctx.set(core.sink.payload, {"data": pixels, "first": first, "last": last})
            ctx.set(core.sink.valid, offering)
            ready = rng.random() < GAPS
            ctx.set(core.source.ready, ready)
            if offering and ctx.get(core.sink.ready):
                index += 1
            words += ready and ctx.get(core.source.valid)
            tag = ctx.get(aggregation.tag)
            if tag.valid and 0 <= tag.y < height:
                base = ctx.get(aggregation.round) * units
                for i in range(units):
                    key = (tag.y, tag.x, base + i)
                    assert key not in got, f"C{key} came twice"
                    got[key] = ctx.get(aggregation.costs[i])
            idle = idle + 1 if index == len(beats) and words == width * height else 0
            await ctx.tick()

    simulate(core, bench)
    return got


def check_costs(params, pair, seed=0, before_start=None):
    expected = golden_sgm.cost_volume(*pair, params)
    got = hardware_costs(params, pair, seed, before_start)
    assert len(got) == expected.size, "not every cost was seen"
    mismatches = [(key, value, int(expected[key])) for key, value in sorted(got.items())
                  if value != expected[key]]
    assert not mismatches, (f"{len(mismatches)} costs differ, first ((y, x, d), got, "
                            f"expected): {mismatches[0]}")


def textured_pair(height, width, disparities, seed):
    """The layers scene with pixel noise and a third of the right pixels replaced: small
    differences (sums below 255) and large ones (both clips), so that every value of the
    term occurs."""
    left, right = stereo_pair("layers", height, width, seed, disparities)
    rng = np.random.default_rng(seed)
    right = np.clip(right.astype(int) + rng.integers(-20, 21, right.shape), 0, 255)
    replaced = rng.random(right.shape) < 0.35
    right[replaced] = rng.integers(0, 256, replaced.sum())
    # Sums of 9 x 31 > 255 at every disparity (row 1, columns W - 3 and W - 2) and of 0
    # at d = 0 (last row, columns 0 .. 2).
    left[:3, -4:], right[:3, -4 - disparities:] = 0, 255
    left[-2:, :4], right[-2:, :4] = 90, 90
    return left, right.astype(np.uint8)


COSTS = [
    # block, D, R, width, height
    (3, 4, 1, 20, 5),       # R = 1, four lanes, skews 0 .. 3
    (3, 16, 1, 28, 5),      # R = 1, sixteen lanes with equal skews
    (5, 6, 2, 24, 5),       # R = 2: the history in LUT RAM
    (3, 8, 8, 18, 5),       # R = D: one lane, x - d >= 2 from its own flag
]


@pytest.mark.parametrize("block,disparities,rounds,width,height", COSTS)
def test_costs_match_golden(block, disparities, rounds, width, height):
    params = term_params(block, disparities, rounds, width, height)
    pair = textured_pair(height, width, disparities, block + disparities + rounds)
    term = golden_sgm.cost_volume(*pair, params).astype(int) - golden_sgm.cost_volume(
        *pair, params.replace(cost_term=None, p2=20)).astype(int)
    # Every value of the term occurs where the pair exists (elsewhere C is Cmax).
    exists = np.arange(disparities)[None, :] <= np.arange(width)[:, None]
    assert set(np.unique(term[:, exists])) == set(range(8))
    check_costs(params, pair, seed=rounds)


def test_stale_history_is_never_used(monkeypatch):
    """Every memory (the histories' LUT RAM among them) starts with random words."""
    made = record_memories(monkeypatch)
    fill = random_contents(made, np.random.default_rng(5), "", lambda ctx, word: None)
    check_costs(term_params(3, 6, 2, 20, 4), textured_pair(4, 20, 6, 1), seed=5,
                before_start=fill)
    histories = [store for store in made if Shape.cast(store.shape).width == 2 * 7]
    assert len(histories) >= 3


def test_core_map_matches_golden():
    """The whole core with the term, every output pixel: a map the term changes."""
    params = term_params(3, 8, 1, 24, 6)
    pair = textured_pair(6, 24, 8, 3)
    plain = disparity_map(*pair, params.replace(cost_term=None, p2=20)).disparity
    assert not np.array_equal(disparity_map(*pair, params).disparity, plain)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=GAPS, ready_prob=GAPS,
                 seed=1)


# Broken variants: each must be caught by the costs' comparison ---------------------------

BROKEN = term_params(3, 4, 1, 20, 5)


def assert_caught(params=BROKEN):
    with pytest.raises(AssertionError, match="costs differ"):
        check_costs(params, textured_pair(params.height, params.width, params.disparities,
                                          2), seed=2)


def broken_term(monkeypatch, **forced):
    real = calculation_stage.Ad3Term

    def term(m, slots, params, unit, left, right, at, older, oldest, write):
        values = dict(older=older, oldest=oldest, write=write)
        values.update({name: Const(1) for name in forced})
        return real(m, slots, params, unit, left, right, at, **values)
    monkeypatch.setattr(calculation_stage, "Ad3Term", term)


def test_broken_variant_baseline_matches():
    check_costs(BROKEN, textured_pair(5, 20, 4, 2), seed=2)


def test_broken_history_gates_are_caught(monkeypatch):
    """The older column sums always counted: x - d = 0 takes a column without a pair (and
    x = 0 the previous row's)."""
    broken_term(monkeypatch, older=True, oldest=True)
    assert_caught()


def test_broken_history_write_is_caught(monkeypatch):
    """The history written in every slot, not only those with a position: the gaps
    shift it."""
    broken_term(monkeypatch, write=True)
    assert_caught()


def test_broken_history_write_is_caught_at_r2(monkeypatch):
    broken_term(monkeypatch, write=True)
    assert_caught(term_params(3, 4, 2, 20, 5))


def test_broken_pixel_column_is_caught(monkeypatch):
    """The window's centre column instead of the one right of it."""
    def centre(window, block):
        r = (block - 1) // 2
        return cost_term.Cat(window[(r + dy) * block + r] for dy in (-1, 0, 1))
    monkeypatch.setattr(calculation_stage, "right_column", centre)
    assert_caught()


def test_broken_clip_is_caught(monkeypatch):
    """Absolute differences clipped at 63 instead of 31."""
    monkeypatch.setattr(cost_term, "AD3_CLIP", 63)
    assert_caught()


# The generated Verilog under cocotb (Icarus) ----------------------------------------------

def test_icarus_stream_with_the_term():
    """test_cocotb's traffic plan (two frames back to back under idle cycles and
    backpressure) with the term on, R = 1: both bit-exact (its full plan, with a reset,
    misframed lines and an aborted frame, passes too but takes twice as long: docs/sgm.md);
    the same core with the history's gates always on is reported mismatching."""
    from npstereo.hdl.verilog import core_verilog
    from npstereo.sim import cosim
    from test_cocotb import TRAFFIC_PLAN, assert_bit_exact, config, frames

    params = config("census", 3, 8, 1, 1).replace(aggregation="sgm", cost_term="ad3", p1=3,
                                                  p2=20, p2_adapt=2)
    pairs = frames(params)
    assert_bit_exact(cosim.run_stream("icarus", params, pairs, TRAFFIC_PLAN))
    with pytest.MonkeyPatch.context() as patch:
        broken_term(patch, older=True, oldest=True)
        broken = core_verilog(params)
    result = cosim.run_stream("icarus", params, pairs[:1], [{"op": "frames", "frames": [0]}],
                              core_text=broken)
    assert result.frames and not result.ok


# What the report counts -------------------------------------------------------------------

def test_memory_formula_counts_the_term(monkeypatch):
    """The right stores' wider words and the histories' LUT RAM (R = 2) in the memory
    formula that ``npstereo report`` compares with Yosys: it holds the bits of the memories
    the elaborated core makes (Yosys found the same, 4212 bits, docs/sgm.md, when the left
    path's two stores were LUT RAM at R = 2; shifting registers now, 80 bits fewer; 4402 with
    the SGM stage's delay lines in LUT RAM; 4722 since the L/R check's exit register
    lengthened the pipeline by a clock and the output queue doubled to 64 words), and a
    formula without the term's store bits does not."""
    from npstereo.hdl import plan_memories
    from npstereo.hdl.verilog import core_verilog

    params = term_params(3, 6, 2, 20, 4)
    made = record_memories(monkeypatch)
    core_verilog(params)
    elaborated = sum(Shape.cast(memory.shape).width * memory.depth for memory in made)
    assert elaborated == plan_memories.memory_bits(params) == 4722
    kinds = {memory.name: memory for memory in plan_memories.memories(params)}
    assert kinds["cost term histories"].bits == 3 * 2 * 2 * 7
    assert kinds["right-transform stores"].width == params.transform_bits + 24
    monkeypatch.setattr(plan_memories, "term_word_bits", lambda p: 0)
    assert plan_memories.memory_bits(params) != elaborated
