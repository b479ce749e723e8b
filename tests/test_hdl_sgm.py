"""Semi-global aggregation in hardware (hdl/sgm.py) against the golden model (golden/sgm.py).

The stage alone: :class:`SemiGlobalAggregation` is fed random cost volumes and gray images
position by position -- a partial frame and rows above the frame first, slots without a
position in between (random inputs in them), every memory full of random words -- and every
S(x, y, d) of the frame is compared with ``golden.sgm.aggregate``; R = 1 (D lanes, a loop of
one clock), R = 2, R >= 3 (the two-clock lane update), R = D and odd splits, rows longer than
K so that the tracked reference comes from the history, constant and adaptive P2, P1 = P2 = 0
and P2 at its largest.
The core: whole frames through :class:`~npstereo.hdl.core.NpStereoCore` in Amaranth's simulator against
``golden.pipeline.disparity_map`` (which dispatches to golden.sgm), all four transforms,
random source gaps and sink backpressure, frames back to back, a reset in mid-frame,
mis-framed input. ``test_broken_*`` monkeypatch a wrong rule into the hardware and prove
that the same comparison catches it.
"""

import random
import re

import numpy as np
import pytest
from amaranth.hdl import Value

from npstereo.golden import sgm as golden_sgm
from npstereo.hdl import banks, calculation_stage, plan, plan_memories, plan_structure, \
    plan_timing
from npstereo.hdl import sgm as hdl_sgm
from npstereo.hdl import sgm_left, sgm_left_pairs, sgm_left_reference
from npstereo.hdl.sgm import GUIDE, SemiGlobalAggregation
from npstereo.params import ParameterError, StereoParams

from hdl_helpers import RESET, check_frames, choose_bank_early, frame_beats, record_memories, \
    simulate_and_compare
from scenes import stereo_pair

GAPS = 0.65  # probability that the source offers / the sink takes: >= 30 % stalls each


def sgm_params(transform, block, disparities, rounds, p1=None, p2=None, adapt=None, **size):
    return StereoParams(transform=transform, block=block, disparities=disparities,
                        rounds=rounds, aggregation="sgm", p1=p1, p2=p2, p2_adapt=adapt,
                        **size)


# The stage alone ---------------------------------------------------------------------------

def random_memories(monkeypatch, seed):
    """Record every Memory made from now on; returns a function filling them with random
    words (nothing may rely on what a memory holds before it is written)."""
    made = record_memories(monkeypatch)
    rng = random.Random(seed)

    def fill(ctx):
        assert made, "no memory was found to fill"
        for store in made:
            for row in range(store.depth):
                word = Value.cast(store.data[row])
                ctx.set(word, rng.getrandbits(len(word)))
    return fill


def stage_slots(width, height, stream, bubbles):
    """Positions in the order the core feeds them, with bubbles (None) between them: one
    and a half rows of an earlier frame, then the rows above the frame that a window
    centre passes (from a column near the end), then the frame."""
    positions = ([("old", x, y) for y in range(2) for x in range(width)][:3 * width // 2]
                 + [("above", x, -2) for x in range(width - 3, width)]
                 + [("above", x, -1) for x in range(width)]
                 + [("frame", x, y) for y in range(height) for x in range(width)])
    slots = []
    for position in positions:
        while stream.random() < bubbles:
            slots.append(None)
        slots.append(position)
    return slots


def drive_slot(ctx, dut, slot, j, stream, width, top, frame_inputs, random_inputs):
    """Round ``j`` of ``slot`` at a stage's inputs: the slot clock, the tag and the round's
    costs; a bubble or a position outside the frame gets random costs (and
    ``random_inputs(ctx)``), a frame position ``frame_inputs(ctx, x, y, j)``."""
    ctx.set(dut.first, j == 0)
    ctx.set(dut.round, j)
    if slot is not None and slot[0] == "frame":
        _, x, y = slot
        ctx.set(dut.tag, {"x": x, "y": y, "valid": 1, "live": 1})
        frame_inputs(ctx, x, y, j)
        return
    x, y = (stream.randrange(width), 0) if slot is None else slot[1:]
    ctx.set(dut.tag, {"x": x, "y": y, "valid": slot is not None, "live": 1})
    for cost in dut.costs:
        ctx.set(cost, stream.randrange(top + 1))
    random_inputs(ctx)


def check_stage(params, monkeypatch, seed, bubbles=0.3):
    """Stream a random volume through the stage alone; every S of the frame must be the
    golden model's. With the fifth path the sums of row y leave while row y + 1 streams in,
    mirrored: slot x carries column W - 1 - x (a row below the frame closes it)."""
    rng, stream = np.random.default_rng(seed), random.Random(seed)
    width, height, rounds, units = params.width, params.height, params.rounds, \
        params.per_round
    top = params.max_cost
    volume = rng.integers(0, top + 1, (height, width, params.disparities))
    volume[::3, ::2] = top                     # the largest path costs
    volume[1::4, :, :2] = 0
    guide = rng.integers(0, 256, (height, width)).astype(np.uint8)
    guide[height // 2, :] = guide[height // 2 - 1, :]      # steps of 0 as well
    adapt = params.p2_adapt or None
    expected = golden_sgm.aggregate(volume, params.p1, params.p2, guide=guide, adapt=adapt,
                                    max_cost=top, fifth_path=params.fifth_path)
    late = 1 if params.fifth_path else 0

    def column(x):
        return width - 1 - x if params.fifth_path else x
    padded = np.pad(guide, 1)

    slots = stage_slots(width, height, stream, bubbles)
    slots += [("below", x, y) for y in range(height, height + late) for x in range(width)]
    clocks = [(slot, j) for slot in slots for j in range(rounds)]
    fill = random_memories(monkeypatch, seed)
    dut = SemiGlobalAggregation(params)
    assert dut.latency == plan_timing.aggregation_latency(params)
    latency, got = dut.latency, {}

    def frame_inputs(ctx, x, y, j):
        for i in range(units):
            ctx.set(dut.costs[i], int(volume[y, x, j * units + i]))
        for k, (dy, dx) in enumerate(GUIDE):
            ctx.set(dut.guide[k], int(padded[y + dy + 1, x + dx + 1]))

    def random_inputs(ctx):
        for pixel in dut.guide:
            ctx.set(pixel, stream.randrange(256))

    async def testbench(ctx):
        fill(ctx)
        for t in range(len(clocks) + latency):
            slot, j = clocks[t] if t < len(clocks) else (None, t % rounds)
            drive_slot(ctx, dut, slot, j, stream, width, top, frame_inputs, random_inputs)
            if t >= latency and clocks[t - latency][0] is not None:
                (kind, x, y), j = clocks[t - latency]
                if kind in ("frame", "below") and 0 <= y - late < height:
                    centre = ctx.get(dut.centre)
                    assert (centre.x, centre.y, centre.valid) == (x, y - late, 1)
                    for i in range(units):
                        got[(y - late, column(x), j * units + i)] = ctx.get(dut.sums[i])
            await ctx.tick()

    simulate_and_compare(dut, testbench, got, expected, "sums")


STAGES = [
    # transform, block, D, R, P1, P2, t, width, height
    ("census", 3, 8, 8, 3, 20, 2, 10, 5),            # one lane, R = D
    # Odd widths: the row's last column and the next row's first are both even, back to
    # back when no slot comes between (at R = 1 the last column's S and Q - C were
    # overwritten by the next row's before its choice until the eleventh session).
    ("census", 3, 4, 1, 3, 20, 2, 41, 3),            # R = 1: four lanes, one clock a position
    ("census", 5, 8, 1, 16, 96, 4, 38, 3),           # R = 1, eight lanes (T = 3)
    ("census", 5, 64, 1, 16, 96, 4, 80, 3),          # R = 1, 64 lanes: the history's readers
    ("census", 5, 16, 2, 16, 96, 4, 37, 3),          # R = 2, eight lanes, shifting stores
    ("census", 3, 24, 8, 4, 20, None, 26, 3),        # three lanes, constant P2
    ("rank", 5, 15, 3, 7, 40, 5, 36, 3),             # R = 3: two-clock update, store read early
    ("census", 3, 8, 4, 3, 20, 2, 35, 3),            # R = 4: the three-clock update
    ("rank", 3, 10, 5, 7, 40, 5, 14, 3),             # R = 5: the first lanes' read registered
    ("ext-rank", 3, 12, 12, 0, 0, None, 14, 4),      # P1 = P2 = 0, 11-bit path costs
    ("ext-census", 3, 6, 2, 2000, 6151, 1, 21, 3),   # P2 = P2max, t = 1, wide Lu
]


@pytest.mark.parametrize("transform,block,disparities,rounds,p1,p2,adapt,width,height",
                         STAGES)
def test_stage_matches_golden(monkeypatch, transform, block, disparities, rounds, p1, p2,
                              adapt, width, height):
    params = sgm_params(transform, block, disparities, rounds, p1, p2, adapt or 0,
                        width=width, height=height)
    check_stage(params, monkeypatch, seed=disparities + rounds)


#: A small stage for the broken variants: one lane, adaptive P2 with a low threshold.
BROKEN = sgm_params("census", 3, 8, 8, 3, 20, 2, width=10, height=5)


def assert_stage_caught(monkeypatch, params=BROKEN):
    with pytest.raises(AssertionError, match="sums differ"):
        check_stage(params, monkeypatch, seed=7)


def test_broken_variant_baseline_matches(monkeypatch):
    check_stage(BROKEN, monkeypatch, seed=7)


def test_broken_left_reference_is_caught(monkeypatch):
    """The left path's large step left out of its minimum (ref + P2 never taken)."""
    real = sgm_left.minimum
    monkeypatch.setattr(sgm_left, "minimum", lambda candidates, bits, small=None:
                        real(candidates[:3], bits, small))
    assert_stage_caught(monkeypatch)


def test_broken_left_parity_is_caught(monkeypatch):
    """The left path's small step into every column (the parity flag ignored)."""
    real = sgm_left.minimum
    monkeypatch.setattr(sgm_left, "minimum", lambda candidates, bits, small=None:
                        real(candidates, bits))
    assert_stage_caught(monkeypatch)


#: The loop over two positions (R = 1).
PAIRS = sgm_params("census", 3, 4, 1, 3, 20, 2, width=40, height=3)


def test_broken_left_pairs_gap_is_caught(monkeypatch):
    """R = 1, the loop over two positions: C(x - 1) taken from the slot before x instead of
    the last position (a gap between x - 1 and x breaks it)."""
    check_stage(PAIRS, monkeypatch, seed=7)
    monkeypatch.setattr(sgm_left_pairs, "_last_position", lambda m, value, valid, name:
                        sgm_left_pairs.register(m, value, len(value), name))
    assert_stage_caught(monkeypatch, PAIRS)


def test_broken_left_pairs_odd_choice_is_caught(monkeypatch):
    """R = 1: an odd column's choice also obeying the even column's fifth comparison
    (Q(x + 1) - C(x) against its four candidates)."""
    params = PAIRS
    real = sgm_left_pairs.minimum
    monkeypatch.setattr(sgm_left_pairs, "minimum", lambda candidates, bits, small=None:
                        real(candidates + [candidates[-1]] * (len(candidates) == 4), bits,
                             small))
    assert_stage_caught(monkeypatch, params)


#: Rows longer than K: at R = 1, D = 64 the history's readers, at R = 2 its chain.
HISTORY_CASES = [sgm_params("census", 5, 64, 1, 16, 96, 4, width=80, height=3),
                 sgm_params("census", 5, 16, 2, 16, 96, 4, width=40, height=3)]


@pytest.mark.parametrize("params", HISTORY_CASES, ids=["readers", "chain"])
def test_broken_left_history_is_caught(monkeypatch, params):
    """b(x) from the history one position too new (argmin of x - K + 1): rows longer than
    K catch it."""
    assert plan_timing.sgm_timing(params).left_chain == (8 if params.rounds == 1 else 1)
    real = sgm_left._picks

    def shifted(owner, m, column, fresh_at, history, b0, lu, chosen, sums):
        def later(offset):
            return column(offset) + 1
        return real(owner, m, later, fresh_at, history, b0, lu, chosen, sums)
    monkeypatch.setattr(sgm_left, "_picks", shifted)
    assert_stage_caught(monkeypatch, params)


def test_broken_history_pairs_reader_is_caught(monkeypatch):
    """The chain's history reader in levels of 4:1 (four clocks at R = 1, D = 64): read a
    clock short (its two-level multiplexer behind the four clocks' index), or with the
    higher bits of the index not delayed beside the levels."""
    params = HISTORY_CASES[0]
    assert plan_timing.sgm_timing(params).left_chain_history == \
        plan_timing.SGM_HISTORY_PAIRS_CLOCKS == 4
    check_stage(params, monkeypatch, seed=7)
    monkeypatch.setattr(sgm_left_reference, "SGM_HISTORY_PAIRS_CLOCKS", 3)
    assert_stage_caught(monkeypatch, params)
    monkeypatch.undo()
    real = sgm_left_reference.register

    def high_undelayed(m, value, shape, name, enable=None):
        # Only the four-clock reader's levels (the readers before the chain, at R = 1,
        # have a "sgm_left_history{k}_high" of their own).
        if re.fullmatch(r"sgm_left_history\d+_l\d+_high", name):
            return value
        return real(m, value, shape, name, enable)
    monkeypatch.setattr(sgm_left_reference, "register", high_undelayed)
    assert_stage_caught(monkeypatch, params)


def test_broken_left_chain_gaps_are_caught(monkeypatch):
    """The history's chain shifted in every slot, not only in those with a position (the
    gaps between positions then shift it too far)."""
    params = HISTORY_CASES[1]
    check_stage(params, monkeypatch, seed=7)
    monkeypatch.setattr(sgm_left_reference, "_chain_shift",
                        lambda owner, at: owner._slots.first(at))
    assert_stage_caught(monkeypatch, params)


#: R = 4: the picked costs' files read in two clocks (``timing.left_read_split``).
SPLIT_READ = sgm_params("census", 3, 8, 4, 3, 20, 2, width=35, height=3)


@pytest.mark.parametrize("mutation", ["index a clock late", "entry off by one"])
def test_broken_split_file_read_is_caught(monkeypatch, mutation):
    """The picked costs' two-clock file read given the column of a clock later, or the
    neighbouring entry."""
    assert plan.sgm_timing(SPLIT_READ).left_read_split
    real = sgm_left_reference._read_file

    def broken(m, entries, index, name, split=False):
        if split:
            index = (sgm_left_reference.register(m, index, len(index), f"{name}_late")
                     if mutation == "index a clock late" else index ^ 1)
        return real(m, entries, index, name, split)
    monkeypatch.setattr(sgm_left_reference, "_read_file", broken)
    assert_stage_caught(monkeypatch, SPLIT_READ)


def test_broken_top_left_border_is_caught(monkeypatch):
    """Top-left not starting fresh in the first column (it would read the last column of
    the row two above)."""
    real = hdl_sgm._fresh
    monkeypatch.setattr(hdl_sgm, "_fresh", lambda path, x, y, width:
                        real("top" if path == "top-left" else path, x, y, width))
    assert_stage_caught(monkeypatch)


def test_broken_round_edge_is_caught(monkeypatch):
    """The neighbour d + 1 left out of the minimum (it crosses into the next round for the
    last lane)."""
    monkeypatch.setattr(hdl_sgm, "_minimum3",
                        lambda centre, lower, upper: (lower < centre, hdl_sgm.Const(0)))
    assert_stage_caught(monkeypatch)


def test_broken_adaptive_p2_is_caught(monkeypatch):
    """Adaptive P2 halved one doubling of the step too early."""
    real = hdl_sgm._adaptive_p2
    monkeypatch.setattr(hdl_sgm, "_adaptive_p2", lambda step, p1, p2, adapt:
                        real(step, p1, p2, adapt - 1))
    assert_stage_caught(monkeypatch)


def test_broken_row_normalisation_is_caught(monkeypatch):
    """The paths from above not capped at P2 (best - m where m + P2 is smaller)."""
    monkeypatch.setattr(hdl_sgm, "_normalised", lambda below, over, p2, fresh:
                        hdl_sgm.Mux(fresh, 0, over))
    assert_stage_caught(monkeypatch)


def test_broken_row_minima_a_clock_early_is_caught(monkeypatch):
    """The row above's minima word taken a clock before its read is out (the copied
    column's address a clock behind)."""
    monkeypatch.setattr(hdl_sgm, "_MINIMA_WORD", hdl_sgm._MINIMA_WORD - 1)
    assert_stage_caught(monkeypatch)


@pytest.mark.parametrize("shallowest, deepest, banks, levels", [(8, 1 << 14, 3, 1),
                                                                  (8, 8, 10, 2)])
def test_path_rows_in_banks_match_golden(monkeypatch, shallowest, deepest, banks, levels):
    """Path rows of W R = 80 words: from banks of 8 words deepened to 32 (3 banks, one level
    of choice), or kept at 8 (10 banks, two registered levels), L a clock later for the
    register behind the banks' and per level."""
    monkeypatch.setattr(plan_structure, "ROW_BANK", shallowest)
    monkeypatch.setattr(plan_structure, "ROW_BANK_DEEPEST", deepest)
    assert len(plan_structure.row_banks(BROKEN)) == banks
    assert plan_structure.choice_levels(banks) == levels
    assert plan_timing.sgm_row_clocks(BROKEN) == plan_timing.SGM_ROW_CLOCKS + 1 + levels
    check_stage(BROKEN, monkeypatch, seed=banks)


def _address_slices(monkeypatch):
    """Path rows in 10 banks of 8 words, each bank's word (14 and 7 bits) in slices of 5
    bits with copies of the addresses of their own."""
    monkeypatch.setattr(banks, "ADDRESS_SLICE_BITS", 5)
    monkeypatch.setattr(plan_structure, "ROW_BANK", 8)
    monkeypatch.setattr(plan_structure, "ROW_BANK_DEEPEST", 8)


def test_path_rows_in_address_slices_match_golden(monkeypatch):
    _address_slices(monkeypatch)
    check_stage(BROKEN, monkeypatch, seed=5)


def test_broken_address_slice_is_caught(monkeypatch):
    """The read address of every bank's second slice a clock late."""
    _address_slices(monkeypatch)
    real = banks.replica

    def late(m, value, name, shape=None, enable=None, reset_less=False):
        copy = real(m, value, name, shape, enable, reset_less)
        if name.endswith("_1_read_address"):
            copy = real(m, copy, f"{name}_late", shape, enable, reset_less)
        return copy
    monkeypatch.setattr(banks, "replica", late)
    assert_stage_caught(monkeypatch)


def test_broken_path_rows_bank_choice_is_caught(monkeypatch):
    """The bank chosen a clock early: words from the bank of the next address."""
    monkeypatch.setattr(plan_structure, "ROW_BANK", 32)
    choose_bank_early(monkeypatch, "_bank", clocks=0)
    assert_stage_caught(monkeypatch)


def test_broken_path_rows_bank_register_is_caught(monkeypatch):
    """The bank's index without the clock of the registers behind the banks' output
    registers: words from the bank of the next address."""
    monkeypatch.setattr(plan_structure, "ROW_BANK", 32)
    choose_bank_early(monkeypatch, "_read_bank")
    assert_stage_caught(monkeypatch)


# The core ----------------------------------------------------------------------------------

CORES = [
    # transform, block, D, R, P1, P2, t (None: the default), L/R threshold, image kind, W, H
    ("census", 3, 8, 8, 3, 20, 2, 1, "layers", 20, 6),
    ("rank", 5, 4, 1, 8, 30, 0, None, "independent", 24, 5),      # R = 1, four lanes
    ("ext-rank", 3, 6, 2, None, None, None, 1, "random", 26, 4),   # R = 2, three lanes
    ("ext-census", 3, 12, 12, 300, 2000, 3, 0, "independent", 18, 5),
    ("census", 7, 8, 8, None, None, None, 3, "layers", 16, 6),     # the SGM defaults
]


@pytest.mark.parametrize("transform,block,disparities,rounds,p1,p2,adapt,lr,image,width,"
                         "height", CORES)
def test_core_matches_golden(transform, block, disparities, rounds, p1, p2, adapt, lr,
                             image, width, height):
    params = sgm_params(transform, block, disparities, rounds, p1, p2, adapt,
                        width=width, height=height).replace(lr_threshold=lr)
    pair = stereo_pair(image, height, width, block * 100 + disparities, disparities)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=GAPS, ready_prob=GAPS,
                 seed=rounds)


#: The scenarios' core: census 3x3, D = 8, R = 8, adaptive P2, the L/R check.
SCENARIO = sgm_params("census", 3, 8, 8, 3, 20, 2, width=14, height=5)


@pytest.mark.parametrize("reset_at", [30, 75], ids=["before the stage's first row",
                                                    "in the stage's fourth row"])
def test_core_reset_misframing_and_frames_back_to_back(reset_at):
    """A reset in mid-frame (before the SGM stage has a row, or in the middle of one: its
    row bases must restart at the next frame's first column), a frame whose second line
    ends early (a framing error, the rest filled), then two frames that overlap in the
    pipeline (the second's first rows come in while the first's last rows are computed):
    both bit-exact."""
    first, second = stereo_pair("layers", 5, 14, 7), stereo_pair("independent", 5, 14, 8)
    misframed = frame_beats(*second)
    data, user, _ = misframed[14 + 5]
    misframed[14 + 5] = (data, user, True)
    beats = frame_beats(*first)[:reset_at] + [RESET] + misframed + frame_beats(*first) \
        + frame_beats(*second)
    result = check_frames(SCENARIO, [first, second], beats, valid_prob=GAPS,
                          ready_prob=GAPS, seed=3)
    assert result["errors"] >= 1


def test_broken_missing_pair_cost_is_caught(monkeypatch):
    """The box pipeline's 0 instead of Cmax where x - d < 0: the paths crossing the left
    columns are drawn to large disparities."""
    monkeypatch.setattr(calculation_stage, "_missing_cost", lambda params: 0)
    pair = stereo_pair("layers", 5, 14, 3)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(SCENARIO.replace(lr_threshold=None), [pair], frame_beats(*pair))


# The plan ----------------------------------------------------------------------------------

@pytest.mark.parametrize("disparities,rounds", [(4, 1), (64, 1), (256, 1), (100, 5),
                                                (7, 7), (256, 2), (9, 3)])
def test_any_rounds_dividing_d_are_built(disparities, rounds):
    """No rounds restriction: the timing's margins hold for every R that divides D <= 256
    (plan_timing asserts them), and the plan accepts it."""
    params = sgm_params("census", 5, disparities, rounds, width=disparities + 16, height=4)
    plan.check_buildable(params)
    timing = plan_timing.sgm_timing(params)
    # R = 1: the loop over two positions, Lu three clocks after its read.
    assert timing.left_stages == (3 if rounds == 1 else 1 if rounds == 2 else
                                  2 if rounds == 3 else 3)
    # (argmin tree split, history clocks, sum clocks, C(x - 1, b) joining the sum last,
    # start early, its file read early): each as long as the margins allow; J = 8 leaves
    # them all at R = 1 but the late term and the early start (m(0) is stored at the clock
    # that loads the reference) and so its early read, one lane (D = R, T = 0) two clocks
    # for the sum and no late term (P2 is not there early enough).
    expected = {(4, 1): (True, 2, 3, False, False, False),
                (64, 1): (True, 2, 3, False, False, False),
                (256, 1): (True, 2, 3, False, False, False),
                (100, 5): (True, 2, 3, True, True, True),
                (7, 7): (True, 2, 2, False, True, True),
                (256, 2): (True, 2, 3, True, True, True),
                (9, 3): (True, 2, 3, True, True, True)}
    assert (timing.left_argmin_split, timing.left_history, timing.left_sum_clocks,
            timing.left_sum_late,
            timing.left_start_early, timing.left_start_read) == expected[(disparities, rounds)]


def test_narrow_sgm_frames_are_refused():
    """(W - 1) R clocks must cover the write-back of a position's minima (census 5x5,
    D = 8, R = 1: 17 clocks, W >= 18): a narrower frame read the rows above before they
    were written (found by tests/test_random_configs.py at 9 x 5)."""
    params = sgm_params("census", 5, 8, 1, width=18, height=4)
    assert plan.sgm_min_width(params) == 18
    plan.check_buildable(params)
    with pytest.raises(ParameterError) as refused:
        plan.check_buildable(params.replace(width=17))
    assert str(refused.value) == (
        "image width must be >= 18 for semi-global aggregation at D = 8, R = 1 (the rows "
        "above are written back too late for a narrower frame), not 17")


@pytest.mark.parametrize("width, seed", [(12, 0), (15, 0)])
def test_too_narrow_sgm_frame_differs(monkeypatch, width, seed):
    """The broken variant of the limit: built anyway, a frame narrower than
    ``sgm_min_width`` differs from the golden model (at W = 15 only where a position's
    minimum is needed). The formula keeps a clock to spare since the row above's minima
    are read a clock later (``sgm._MINIMA_WORD``): W = 16 matched at seed 0, W = 17 at
    seeds 0-5 before."""
    params = sgm_params("rank", 5, 8, 1, 3, 20, 0, width=width, height=5)
    with pytest.raises(AssertionError, match="sums differ"):
        check_stage(params, monkeypatch, seed=seed)


def test_rounds_not_dividing_d_are_refused():
    with pytest.raises(ParameterError, match="rounds must divide disparities"):
        sgm_params("census", 5, 100, 3, width=104, height=4)


def test_sgm_memories_within_the_budget():
    """At 450 x 375, D = 100, R = 10 with the defaults: 3 x 450 x 100 x 7 bits of path
    costs, 3 x 450 x 7 of minima, the left path's store of 10 words of 10 x 12 bits (Lu)
    and 10 x 12 (Lu + P1) and its first lanes, the delay lines of LUT RAM (the three paths'
    sum, 10 x 9 bits, 8 clocks; Lu, 10 x 12 bits, 16 clocks), the top-left store, and all of SGM's memory beside the box
    configuration's under 1 Mibit."""
    params = sgm_params("census", 7, 100, 10, width=450, height=375)
    kinds = {}
    for memory in plan_memories.sgm_memories(params):    # the stores: a memory per few lanes
        kinds[memory.name] = kinds.get(memory.name, 0) + memory.bits
    assert kinds == {"path rows (top, top-left)": 630_000, "path rows (top-right)": 315_000,
                     "path minima": 9_450, "left path store": 2_400,
                     "left path first lanes": 120, "delay line (above)": 720,
                     "delay line (lu)": 1_920, "top-left store": 700}
    box = params.replace(aggregation=3, p1=None, p2=None, p2_adapt=None)
    assert plan_memories.memory_bits(params) - plan_memories.memory_bits(box) < 1 << 20
    # Counterpart: one more step of P2 makes the path cost 8 bits, and the rows of path
    # costs with their minima alone would hold more than 1 Mibit.
    wider = plan_memories.sgm_memories(params.replace(p2=params.p2 + 1))
    assert sum(memory.bits for memory in wider if memory.name.startswith("path")) > 1 << 20
