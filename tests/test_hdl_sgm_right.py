"""The fifth path's recursion in hardware (hdl/sgm_right.py) against the golden model.

Rows are fed in mirrored column order, as the row buffer of docs/hardware.md ("The fifth
path") would feed them, with bubbles, an earlier frame's positions first and the memories
full of random words; every L_right of the frame must be golden/sgm.py's
``right_path_costs``. The broken variants feed the row in raster order (the left path) and
take P2 from the left neighbour, and must fail.
"""

import random

import numpy as np
import pytest
from amaranth.hdl import Const

from npstereo.golden import sgm as golden_sgm
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import plan_structure, plan_timing, sgm_right
from npstereo.hdl.sgm_right import RightPathRecursion
from npstereo.params import StereoParams

from hdl_helpers import RESET, check_frames, frame_beats, simulate_and_compare
from scenes import stereo_pair
from test_hdl_plan import measured_flush, measured_period, planned_flush
from test_hdl_sgm import check_stage, drive_slot, random_memories, stage_slots


def right_params(transform, block, disparities, rounds, p1, p2, adapt, width, height):
    return StereoParams(transform=transform, block=block, disparities=disparities,
                        rounds=rounds, aggregation="sgm", p1=p1, p2=p2, p2_adapt=adapt,
                        width=width, height=height)


def check_right(params, monkeypatch, seed, bubbles=0.3, mirrored=True, p2_of=None):
    """Stream a random volume through the recursion, row by row right to left (or, with
    ``mirrored`` false, left to right); compare with the golden fifth path."""
    rng, stream = np.random.default_rng(seed), random.Random(seed)
    width, height, rounds, units = params.width, params.height, params.rounds, \
        params.per_round
    top = params.max_cost
    volume = rng.integers(0, top + 1, (height, width, params.disparities))
    volume[::3, ::2] = top
    volume[1::4, :, :2] = 0
    guide = rng.integers(0, 256, (height, width)).astype(np.uint8)
    adapt = params.p2_adapt or None
    expected = golden_sgm.right_path_costs(volume, params.p1, params.p2, guide, adapt, top)
    penalties = (p2_of or golden_sgm.right_path_p2)(guide, params.p1, params.p2, adapt)

    def column(x):
        return width - 1 - x if mirrored else x

    slots = stage_slots(width, height, stream, bubbles)
    clocks = [(slot, j) for slot in slots for j in range(rounds)]
    # The left path's stores are LUT RAM from R = 3 on (shifting registers at R <= 2,
    # where the recursion has no memory to fill at R = 1).
    fill = random_memories(monkeypatch, seed) if rounds > 1 else (lambda ctx: None)
    dut = RightPathRecursion(params)
    latency, got = dut.latency, {}

    def frame_inputs(ctx, x, y, j):
        for i in range(units):
            ctx.set(dut.costs[i], int(volume[y, column(x), j * units + i]))
        ctx.set(dut.p2, int(penalties[y, column(x)]))

    async def testbench(ctx):
        fill(ctx)
        for t in range(len(clocks) + latency):
            slot, j = clocks[t] if t < len(clocks) else (None, t % rounds)
            drive_slot(ctx, dut, slot, j, stream, width, top, frame_inputs,
                       lambda ctx: ctx.set(dut.p2, stream.randrange(params.p2 + 1)))
            if t >= latency and clocks[t - latency][0] is not None \
                    and clocks[t - latency][0][0] == "frame":
                (_, x, y), j = clocks[t - latency]
                centre = ctx.get(dut.centre)
                assert (centre.x, centre.y, centre.valid) == (x, y, 1)
                for i in range(units):
                    got[(y, column(x), j * units + i)] = ctx.get(dut.lanes[i])
            await ctx.tick()

    simulate_and_compare(dut, testbench, got, expected, "values")


CASES = [
    # transform, block, D, R, P1, P2, t, width, height
    ("census", 3, 4, 1, 3, 20, 2, 22, 2),            # R = 1: one position per clock
    ("census", 5, 8, 1, 16, 96, 4, 20, 2),           # R = 1, eight lanes, W > K
    ("rank", 5, 15, 3, 7, 40, 5, 19, 2),             # R = 3: the two-clock update
    ("census", 3, 8, 4, 3, 20, None, 18, 2),         # R = 4, several rounds, constant P2
]


@pytest.mark.parametrize("transform,block,disparities,rounds,p1,p2,adapt,width,height",
                         CASES)
def test_right_recursion_matches_golden(monkeypatch, transform, block, disparities, rounds,
                                        p1, p2, adapt, width, height):
    params = right_params(transform, block, disparities, rounds, p1, p2, adapt or 0,
                          width, height)
    check_right(params, monkeypatch, seed=disparities + rounds)


BROKEN = right_params("census", 3, 4, 1, 3, 20, 2, 22, 2)


def test_broken_baseline_matches(monkeypatch):
    check_right(BROKEN, monkeypatch, seed=3)


def test_broken_raster_order_is_caught(monkeypatch):
    # The row fed left to right: the left path, not the fifth.
    with pytest.raises(AssertionError, match="values differ"):
        check_right(BROKEN, monkeypatch, seed=3, mirrored=False)


def test_broken_p2_from_the_left_neighbour_is_caught(monkeypatch):
    with pytest.raises(AssertionError, match="values differ"):
        check_right(BROKEN, monkeypatch, seed=3, p2_of=lambda guide, p1, p2, adapt:
                    golden_sgm.path_p2(guide, "left", p1, p2, adapt))


# The SGM stage with the fifth path -----------------------------------------------------------


@pytest.mark.parametrize("transform,block,disparities,rounds,p1,p2,adapt,width,height",
                         CASES)
def test_stage_with_the_fifth_path_matches_golden(monkeypatch, transform, block,
                                                  disparities, rounds, p1, p2, adapt,
                                                  width, height):
    params = right_params(transform, block, disparities, rounds, p1, p2, adapt or 0,
                          width, height + 1).replace(fifth_path=True)
    check_stage(params, monkeypatch, seed=disparities + rounds)


FIFTH_BROKEN = right_params("census", 3, 4, 1, 3, 20, 2, 22, 3).replace(fifth_path=True)


def test_broken_stage_baseline_matches(monkeypatch):
    check_stage(FIFTH_BROKEN, monkeypatch, seed=5, bubbles=0)


def test_broken_forwarding_is_caught(monkeypatch):
    # Without the word forwarded, a row's first position reads its column a clock too
    # early (R = 1, rows back to back): the previous row's last S4 and costs are stale.
    monkeypatch.setattr(sgm_right, "_forwarded", _unforwarded)
    with pytest.raises(AssertionError, match="sums differ"):
        check_stage(FIFTH_BROKEN, monkeypatch, seed=5, bubbles=0)


def _unforwarded(m, name, address, ahead, enable, data, read_data, rounds):
    return read_data


def _small_banks(monkeypatch, deepest):
    """The rows (and the path rows) in banks of 8 words: 3 banks of W R = 22 words (one
    level of choice, the read 5 clocks ahead), or 6 of 44 at ``deepest`` 8 (two levels, 6
    clocks ahead)."""
    monkeypatch.setattr(plan_structure, "ROW_BANK", 8)
    monkeypatch.setattr(plan_structure, "ROW_BANK_DEEPEST", deepest)


@pytest.mark.parametrize("rounds, deepest, ahead", [(1, 16384, 5), (2, 8, 6)])
def test_stage_with_the_rows_in_banks_matches_golden(monkeypatch, rounds, deepest, ahead):
    """Words written up to 4 (R = 1) or 5 clocks (R = 2, forwarded at k = 2 and 4) before
    the row's first positions read them, with and without bubbles."""
    _small_banks(monkeypatch, deepest)
    params = FIFTH_BROKEN.replace(disparities=4 * rounds, rounds=rounds)
    assert plan_structure.banked_read_clocks(len(plan_structure.row_banks(params))) == ahead
    check_stage(params, monkeypatch, seed=rounds, bubbles=0)
    check_stage(params, monkeypatch, seed=rounds + 1)


def test_broken_forwarding_of_the_last_clock_only_is_caught(monkeypatch):
    """Only the word written a clock before forwarded (as with a row in one memory read a
    clock ahead): the words written 2 to 4 clocks before the read are stale."""
    _small_banks(monkeypatch, 16384)
    real = sgm_right._forwarded
    monkeypatch.setattr(sgm_right, "_forwarded",
                        lambda m, name, address, ahead, enable, data, read_data, rounds:
                        real(m, name, address, 2, enable, data, read_data, rounds))
    with pytest.raises(AssertionError, match="sums differ"):
        check_stage(FIFTH_BROKEN, monkeypatch, seed=1, bubbles=0)


def test_broken_fixed_direction_is_caught(monkeypatch):
    # Addresses left to right in every row: the reverse pass reads the row in raster order.
    real = sgm_right.turning_rows
    monkeypatch.setattr(sgm_right, "turning_rows", lambda m, params, name, starts, y:
                        (Const(0), real(m, params, name, starts, y)[1]))
    with pytest.raises(AssertionError, match="sums differ"):
        check_stage(FIFTH_BROKEN, monkeypatch, seed=5)


# The core with the fifth path --------------------------------------------------------------

#: transform, block, D, R, P1, P2, t, L/R threshold, image, width, height
CORES = [
    ("census", 3, 4, 1, 3, 20, 2, 1, "layers", 22, 5),             # R = 1
    ("census", 3, 8, 8, 3, 20, 2, 3, "independent", 14, 5),        # R = 8, several rounds
    ("rank", 3, 6, 3, 8, 30, 0, None, "independent", 18, 4),       # R = 3, no check
    # The check at T = 0 on mirrored rows: every dR must be exact (rounds reversed, R = 4).
    ("census", 3, 8, 4, 3, 20, 2, 0, "independent", 16, 4),
    ("census", 3, 4, 1, 3, 20, 2, 0, "flat", 18, 5),             # R = 1, ties
    ("census", 3, 4, 2, 3, 20, 2, 0, "levels", 12, 5),            # R = 2, ties
]


def fifth_core(transform, block, disparities, rounds, p1, p2, adapt, lr, width, height):
    return right_params(transform, block, disparities, rounds, p1, p2, adapt, width,
                        height).replace(lr_threshold=lr, fifth_path=True)


@pytest.mark.parametrize("transform,block,disparities,rounds,p1,p2,adapt,lr,image,width,"
                         "height", CORES)
def test_core_with_the_fifth_path_matches_golden(transform, block, disparities, rounds, p1,
                                                 p2, adapt, lr, image, width, height):
    params = fifth_core(transform, block, disparities, rounds, p1, p2, adapt, lr, width,
                        height)
    pair = stereo_pair(image, height, width, block * 100 + disparities, disparities)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=0.7, ready_prob=0.7,
                 seed=rounds)
    # Counterpart: the four paths' map differs, so the comparison sees the fifth path.
    assert not np.array_equal(disparity_map(*pair, params).disparity,
                              disparity_map(*pair, params.replace(fifth_path=False)).disparity)


def test_core_with_every_quality_option_matches_golden():
    """The README's recommended SGM configuration in small: the fifth path, the ad3 term,
    the median, and F = 2 fractional bits besides, with gaps and stalls."""
    params = StereoParams(transform="census", block=3, disparities=8, rounds=4,
                          aggregation="sgm", p1=8, p2=40, cost_term="ad3", fifth_path=True,
                          median=True, subpixel_bits=2, width=24, height=6)
    pair = stereo_pair("layers", params.height, params.width, 5)
    result = check_frames(params, [pair], frame_beats(*pair), valid_prob=0.8, ready_prob=0.8,
                          seed=1)
    assert result["errors"] == 0


def test_core_with_the_fifth_path_reset_misframing_and_frames_back_to_back():
    """A reset in mid-frame, a misframed frame, then two frames back to back (the first's
    last two rows leave while the second's first rows come in): both bit-exact."""
    params = fifth_core("census", 3, 8, 8, 3, 20, 2, 3, 14, 5)
    first, second = stereo_pair("layers", 5, 14, 7), stereo_pair("independent", 5, 14, 8)
    misframed = frame_beats(*second)
    data, user, _ = misframed[14 + 5]
    misframed[14 + 5] = (data, user, True)
    beats = frame_beats(*first)[:30] + [RESET] + misframed + frame_beats(*first) \
        + frame_beats(*second)
    result = check_frames(params, [first, second], beats, valid_prob=0.7, ready_prob=0.7,
                          seed=3)
    assert result["errors"] >= 1


@pytest.mark.parametrize("rounds", [1])
def test_fifth_path_flush_and_period_are_measured(rounds):
    """The flush is two rows longer (``plan_timing.latency``), frames back to back still
    take W H R clocks; the formula without the two rows fails the same check."""
    params = fifth_core("census", 3, 8, rounds, 3, 20, 2, 2, 24, 6)
    flush, output = measured_flush(params)
    assert flush == planned_flush(params, output)
    assert measured_period(params) == plan_timing.cycles_per_frame(params)
    four = plan_timing.latency(params.replace(fifth_path=False))
    assert flush != four * params.rounds + output


def test_icarus_stream_with_the_fifth_path():
    """The generated Verilog under cocotb on Icarus with test_cocotb's full plan (frames
    back to back under idle cycles and backpressure, a reset, misframed lines, an aborted
    frame): every good frame bit-exact; the core without the row seam's forwarding is
    reported mismatching."""
    from npstereo.hdl.verilog import core_verilog
    from npstereo.sim import cosim
    from test_cocotb import FULL_PLAN, assert_bit_exact, config, frames

    params = config("census", 3, 4, 1, 1).replace(aggregation="sgm", p1=3, p2=20,
                                                   p2_adapt=2, fifth_path=True)
    pairs = frames(params)
    assert_bit_exact(cosim.run_stream("icarus", params, pairs, FULL_PLAN))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(sgm_right, "_forwarded", _unforwarded)
        broken = core_verilog(params)
    result = cosim.run_stream("icarus", params, pairs, FULL_PLAN[:1], core_text=broken)
    assert result.frames and not result.ok
