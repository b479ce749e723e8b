"""The whole core in Amaranth's simulator against the golden model, every output pixel.

Frames are small (the Python simulator runs a few thousand clocks per second); the matrix
covers all four transforms, block sizes 3/5/7, D in {8, 12, 16}, R in {1, 2, 3, 4}, the
L/R check on and off, aggregation 1/3/5, with random source gaps and sink backpressure of
35 % each. Scenario tests cover back-to-back frames, a reset in mid-frame, mis-framed
input and the throughput; ``test_broken_*`` monkeypatch a deliberately wrong rule into one
stage and prove that the golden comparison catches it.
"""

import dataclasses

import numpy as np
import pytest

from npstereo.hdl import core as core_module
from npstereo.hdl import credits as credits_module
from npstereo.hdl import common, evaluation_stage, input_stage, lr_check, plan_structure, \
    trees, window_centre
from npstereo.hdl.core import NpStereoCore
from npstereo.params import ParameterError, StereoParams

from hdl_helpers import RESET, check_frames, frame_beats, random_contents, record_memories, \
    refused_quietly, run_scenario
from scenes import stereo_pair

GAPS = 0.65  # probability that the source offers / the sink takes: >= 30 % stalls each


MATRIX = [
    # transform, block, D, R, A, lr, image kind (tests/scenes.py)
    ("census", 3, 8, 1, 3, 1, "independent"),
    ("census", 5, 16, 4, 3, 2, "layers"),
    ("census", 7, 8, 2, 3, None, "layers"),
    ("rank", 3, 8, 2, 3, None, "independent"),
    ("rank", 5, 8, 1, 3, 0, "layers"),
    ("rank", 7, 16, 2, 3, 1, "independent"),
    ("ext-rank", 3, 8, 4, 3, 1, "layers"),
    ("ext-rank", 5, 16, 1, 5, None, "independent"),
    ("ext-census", 3, 16, 2, 1, 1, "independent"),
    ("ext-census", 5, 8, 4, 3, None, "layers"),
    ("census", 3, 12, 3, 3, 1, "layers"),  # D not a power of two
    # The other line buffer than "auto" picks: costs of the rows above, or transforms.
    ("census", 5, 8, 2, 3, 1, "layers", "costs"),
    ("rank", 3, 16, 4, 5, None, "independent", "costs"),
    ("ext-census", 3, 8, 2, 3, 1, "layers", "transforms"),
    # The rows above transformed again from pixels.
    ("census", 5, 8, 2, 3, 1, "layers", "pixels"),
    ("rank", 3, 16, 4, 5, None, "independent", "pixels"),
    ("ext-census", 3, 8, 1, 3, 2, "layers", "pixels"),
    ("ext-rank", 5, 12, 3, 3, 0, "independent", "pixels"),
    # Sums of absolute differences arranged for 6-input LUTs.
    ("ext-census", 5, 8, 2, 3, 1, "layers", "costs", 6),
    ("ext-census", 3, 16, 4, 3, None, "independent", "pixels", 6),
    ("ext-rank", 7, 8, 1, 3, 2, "layers", "transforms", 6),
]


@pytest.mark.parametrize(
    "transform,block,disparities,rounds,aggregation,lr,image,line_buffer,lut_inputs",
    [row + ("auto", 4)[len(row) - 7:] for row in MATRIX])
def test_matches_golden(transform, block, disparities, rounds, aggregation, lr, image,
                        line_buffer, lut_inputs):
    width, height = disparities + 12, 8
    params = StereoParams(transform=transform, block=block, disparities=disparities,
                          rounds=rounds, aggregation=aggregation, lr_threshold=lr,
                          width=width, height=height, line_buffer=line_buffer,
                          lut_inputs=lut_inputs)
    pair = stereo_pair(image, height, width, block * 100 + disparities + rounds, disparities)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=GAPS, ready_prob=GAPS,
                 seed=rounds)


@pytest.mark.parametrize("line_buffer", ["transforms", "costs", "pixels"])
def test_two_frames_back_to_back(line_buffer):
    """Frames overlap in the pipeline: the first one's last rows are computed while the
    second one's first rows come in."""
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          lr_threshold=1, width=20, height=7, line_buffer=line_buffer)
    pairs = [stereo_pair("layers", 7, 20, 7), stereo_pair("independent", 7, 20, 8)]
    result = check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                          valid_prob=GAPS, ready_prob=GAPS, seed=3)
    assert result["errors"] == 0


@pytest.mark.parametrize("width,height,block", [(3, 1, 3), (4, 1, 3), (3, 2, 3), (3, 1, 5)])
def test_tiny_frames_back_to_back(width, height, block):
    """Frames of three to six pixels back to back at R = 1, without stalls: each start
    comes a few clocks after the one before, where the input stage's switch_pending (a
    clock late behind the decision's register) has not risen yet; with a 5x5 window the
    frames are shorter than its radius, and switch_pending holds the starts longer."""
    params = StereoParams(transform="census", block=block, disparities=2, rounds=1,
                          aggregation=1, lr_threshold=None, width=width, height=height)
    pairs = [stereo_pair("independent", height, width, seed) for seed in range(5)]
    check_frames(params, pairs, [beat for pair in pairs for beat in frame_beats(*pair)],
                 valid_prob=1.0, ready_prob=1.0, seed=1)


def test_cost_bank_choice_in_levels(monkeypatch):
    """A cost line buffer of 20 banks (banks of 2 words, W*R = 40): the bank is chosen in
    three registered levels, and the core's timing takes the two clocks more, across two
    frames back to back with stalls."""
    monkeypatch.setattr(plan_structure, "COST_BANK", 2)
    params = StereoParams(transform="ext-census", block=3, disparities=8, rounds=2,
                          lr_threshold=1, width=20, height=7, line_buffer="costs")
    assert plan_structure.bank_choice_levels(params) == 3
    pairs = [stereo_pair("layers", 7, 20, 9), stereo_pair("independent", 7, 20, 10)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                 valid_prob=GAPS, ready_prob=GAPS, seed=4)


@pytest.mark.parametrize("transform,rounds", [("census", 1), ("census", 2), ("ext-rank", 2)])
def test_large_window_control(monkeypatch, transform, rounds):
    """What large windows do, at block 5: every window's early shift copies fed by copies
    of the core's decision, not by the admission's register, and window masks that run
    free instead of loading with the tag (census masks its comparisons, ext. rank its
    window): same frames, back to back, with stalls."""
    monkeypatch.setattr(input_stage, "EARLY_FANOUT", 1)
    params = StereoParams(transform=transform, block=5, disparities=8, rounds=rounds,
                          lr_threshold=1, width=20, height=7)
    assert input_stage._large_window(params)
    pairs = [stereo_pair("layers", 7, 20, 11), stereo_pair("independent", 7, 20, 12)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                 valid_prob=GAPS, ready_prob=GAPS, seed=rounds)


@pytest.mark.parametrize("rounds", [1, 2])
def test_copied_pair_flags_and_write_enables(monkeypatch, rounds):
    """Many units per round, at D = 8: the pair flags (x - d >= 0) and the L/R check's
    write enable in a copy per 3 units, as D = 64 at R = 1 has them per 12: same frames,
    back to back, with stalls."""
    monkeypatch.setattr(common, "UNITS_PER_CONTROL_COPY", 3)
    params = StereoParams(transform="census", block=3, disparities=8, rounds=rounds,
                          lr_threshold=1, width=20, height=7)
    pairs = [stereo_pair("layers", 7, 20, 15), stereo_pair("independent", 7, 20, 16)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                 valid_prob=GAPS, ready_prob=GAPS, seed=rounds)


def test_broken_pair_flag_copy_is_caught(monkeypatch):
    """Broken variant: the last group's copy of "some pairs" stuck at 0, so that its units
    (d = 6, 7) count as without a partner until x >= D: their costs at the first valid
    column (x = 7) are zeroed, which the comparison with the golden model must see."""
    monkeypatch.setattr(common, "UNITS_PER_CONTROL_COPY", 3)
    original = common.replica

    def stuck(m, value, name, *args, **kwargs):
        return original(m, value & 0 if name == "some_pairs2" else value, name, *args,
                        **kwargs)
    monkeypatch.setattr(common, "replica", stuck)
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          lr_threshold=None, width=20, height=7)
    pairs = [stereo_pair("layers", 7, 20, 15)]
    with pytest.raises(AssertionError):
        check_frames(params, pairs, frame_beats(*pairs[0]), valid_prob=GAPS,
                     ready_prob=GAPS, seed=1)


def test_spaced_popcount(monkeypatch):
    """The census cost's popcount with a register every second adder level (what census
    does from 17x17 on), at block 5: same frames, back to back, with stalls."""
    monkeypatch.setattr(plan_structure, "SPACED_POPCOUNT_ABOVE", 8)
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          lr_threshold=1, width=20, height=7)
    assert not all(plan_structure.cost_plan(params))
    pairs = [stereo_pair("layers", 7, 20, 13), stereo_pair("independent", 7, 20, 14)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                 valid_prob=GAPS, ready_prob=GAPS, seed=5)


def test_popcount_spacing_by_block():
    """Census up to 15x15 registers every adder level of its popcount; 17x17 and 19x19
    every second one."""
    def spaced(block):
        params = StereoParams(transform="census", block=block, disparities=100, rounds=10,
                              width=450, height=375)
        return not all(plan_structure.cost_plan(params))
    assert [spaced(block) for block in (7, 9, 11, 13, 15, 17, 19)] == [False] * 5 + [True] * 2


def test_spaced_sum_of_differences(monkeypatch):
    """Ext. census's sum of absolute differences with its first register one adder level
    later (what ext. census does from 13x13 on), at block 3: same frames with stalls."""
    monkeypatch.setattr(plan_structure, "SPACED_SAD_ABOVE", 4)
    params = StereoParams(transform="ext-census", block=3, disparities=8, rounds=2,
                          lr_threshold=1, width=20, height=7)
    assert plan_structure.cost_plan(params)[:3] == [False, False, True]
    pairs = [stereo_pair("layers", 7, 20, 17), stereo_pair("independent", 7, 20, 18)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]),
                 valid_prob=GAPS, ready_prob=GAPS, seed=7)


def test_sum_of_differences_spacing_by_block():
    """Ext. census up to 11x11 registers its sum of differences after the first adder
    level; from 13x13 on after the second, at the same latency."""
    for block in (7, 9, 11, 13, 15, 17, 19):
        params = StereoParams(transform="ext-census", block=block, disparities=100,
                              rounds=10, width=450, height=375)
        cost = plan_structure.cost_plan(params)
        assert cost[:3] == ([False, True, False] if block <= 11 else [False, False, True])
        assert sum(cost) == sum(trees.sad_plan(params.neighbours, 2, 0, True))


def test_small_windows_keep_the_admission_register():
    """Up to 11x11 a window's shift and masks take the admission's register itself (their
    netlists, and the results measured on them, stay as they were)."""
    for transform in ("rank", "census", "ext-rank", "ext-census"):
        params = StereoParams(transform=transform, block=11, disparities=100, rounds=10,
                              width=450, height=375)
        assert not input_stage._large_window(params)
        assert input_stage._large_window(dataclasses.replace(params, block=13))


@pytest.mark.parametrize("line_buffer", ["transforms", "pixels"])
def test_second_frame_at_full_rate_sees_only_its_own_rows(line_buffer):
    """A random pair right after a layered one, at full rate: the second frame's first rows
    overlap the first one's last. Its first L/R-checked pixel depends on the right map near
    column 0, whose cost words entered the stores before the aggregation centre reached the
    new frame: with the rows above transformed from pixels, windows masked in the frame of
    the aggregation centre instead of their own centre's made that pixel invalid (found by
    cocotb under Verilator)."""
    params = StereoParams(transform="census", block=5, disparities=8, rounds=2,
                          lr_threshold=1, width=40, height=12, line_buffer=line_buffer)
    pairs = [stereo_pair("random", 12, 40, 0), stereo_pair("layers", 12, 40, 0, 8)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + frame_beats(*pairs[1]))


def test_rows_saturate_below_the_frame_in_a_flush():
    """In the flush after a frame of a small core the window centre's row counts on past
    the frame to y_range's highest, H + a + 1, and stays there: it never wraps round into
    the rows above the frame (where a longer flush would bring it back into the frame).
    Broken variant: the saturation left out (``y_room`` ignored), the row wraps to -8."""
    params = StereoParams(transform="census", block=3, disparities=4, rounds=1, width=5,
                          height=4)
    pair = stereo_pair("random", 4, 5, seed=2)
    result = run_scenario(params, frame_beats(*pair) + [300],
                          watch=lambda dut: [dut.input_stage.tag.y])
    rows = [y for y, in result["watched"]]
    lowest, highest = common.y_range(params)
    assert max(rows) == highest and rows[-1] == highest
    assert min(rows) >= lowest


@pytest.mark.parametrize("lr,aggregation", [(1, 1), (None, 3), (1, 3)])
def test_frame_after_an_idle_gap(lr, aggregation):
    """A gap long enough for the flush to finish (the core goes idle): the next frame
    starts afresh at any column, not in step with the previous one."""
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          aggregation=aggregation, lr_threshold=lr, width=18, height=6)
    pairs = [stereo_pair("independent", 6, 18, 13), stereo_pair("layers", 6, 18, 14)]
    check_frames(params, pairs, frame_beats(*pairs[0]) + [200] + frame_beats(*pairs[1]))


def test_stale_memory_contents_never_reach_a_result(monkeypatch):
    """Every memory of the core starts full of random words (no reset or power-up value
    is relied on: synthesis for Cyclone V drops the initial contents), and a frame comes
    out exact: every stage masks by its tags, never by what its memories held."""
    made = record_memories(monkeypatch)
    rng = np.random.default_rng(5)
    for line_buffer, lr in (("transforms", 1), ("costs", 0), ("pixels", 1)):
        made.clear()
        params = StereoParams(transform="census", block=3, disparities=8, rounds=2,
                              lr_threshold=lr, width=20, height=6, line_buffer=line_buffer)

        def live(ctx, word):
            # Words that name a live, in-frame position: the most harmful stale contents
            # there can be.
            ctx.set(word.tag.live, 1)
            ctx.set(word.tag.y, int(rng.integers(0, 6)))
        fill = random_contents(made, rng, "tag", live)

        pair = stereo_pair("layers", 6, 20, 21)
        result = check_frames(params, [pair], frame_beats(*pair), before_start=fill)
        assert made, "no memory was found to fill"
        assert len(result["words"]) == 20 * 6, "words of positions that never were came out"


def test_broken_store_guard_is_caught(monkeypatch):
    """The L/R check reading its store of left winners before they were written (no guard
    after reset): with random memory contents, words of positions that never were come
    out."""
    monkeypatch.setattr(lr_check, "_primed", lambda seen, depth: 1)
    with pytest.raises(AssertionError, match="never were"):
        test_stale_memory_contents_never_reach_a_result(monkeypatch)


def test_reset_mid_frame_then_clean_frame():
    params = StereoParams(transform="rank", block=3, disparities=8, rounds=2,
                          lr_threshold=1, width=18, height=6)
    first, second = stereo_pair("independent", 6, 18, 11), stereo_pair("layers", 6, 18, 12)
    beats = frame_beats(*first)[:50] + [RESET] + frame_beats(*second)
    check_frames(params, [second], beats, valid_prob=GAPS, ready_prob=GAPS, seed=5)


@pytest.mark.parametrize("transform", ["rank", "census"])
def test_reset_mid_frame_with_large_window_control(monkeypatch, transform):
    """The same with the large windows' control (free-running masks): after the reset the
    masks hold whatever the flags' reset values make of them until the first position."""
    monkeypatch.setattr(input_stage, "EARLY_FANOUT", 1)
    params = StereoParams(transform=transform, block=5, disparities=8, rounds=2,
                          lr_threshold=1, width=18, height=6)
    assert input_stage._large_window(params)
    first, second = stereo_pair("independent", 6, 18, 15), stereo_pair("layers", 6, 18, 16)
    beats = frame_beats(*first)[:70] + [RESET] + frame_beats(*second)
    check_frames(params, [second], beats, valid_prob=GAPS, ready_prob=GAPS, seed=6)


@pytest.mark.parametrize("fault", ["long line", "short line", "no start of frame",
                                   "early start of frame"])
def test_misframed_input_then_clean_frame(fault):
    width, height = 18, 6
    params = StereoParams(transform="census", block=3, disparities=8, rounds=1,
                          lr_threshold=1, width=width, height=height)
    bad, good = stereo_pair("independent", height, width, 13), stereo_pair("layers", height,
                                                                            width, 14)
    if fault == "long line":
        broken = frame_beats(*bad, drop_last_at=2)
    elif fault == "short line":
        broken = frame_beats(*bad)
        data, user, _ = broken[width + 5]
        broken[width + 5] = (data, user, True)
    elif fault == "no start of frame":
        broken = frame_beats(*bad)[1:]
    else:
        broken = frame_beats(*bad)[:40]  # the next frame starts inside this one
    result = check_frames(params, [good], broken + frame_beats(*good),
                          valid_prob=GAPS, ready_prob=GAPS, seed=2)
    assert result["errors"] >= 1


@pytest.mark.parametrize("line_buffer", ["transforms", "costs", "pixels"])
@pytest.mark.parametrize("rounds", [1, 2])
def test_no_error_on_clean_input(line_buffer, rounds):
    """Two frames at full rate: the second one overlaps the first one's last rows (with
    the rows above transformed again from pixels, the windows above the newest must be
    masked in the finishing frame)."""
    params = StereoParams(transform="census", block=3, disparities=8, rounds=rounds,
                          width=12, height=4, line_buffer=line_buffer)
    pair = stereo_pair("independent", 4, 12, 1)
    result = check_frames(params, [pair, pair], frame_beats(*pair) * 2)
    assert result["errors"] == 0


@pytest.mark.parametrize("rounds", [1, 4])
def test_throughput(rounds):
    """Frames back to back without stalls: exactly W*H*R clocks each (no flush between
    them), far below the bound of W*H*R plus 4 lines of rounds."""
    width, height = 32, 16
    params = StereoParams(transform="census", block=3, disparities=8, rounds=rounds,
                          lr_threshold=1, width=width, height=height)
    pair = stereo_pair("independent", height, width, 2)
    result = check_frames(params, [pair, pair, pair], frame_beats(*pair) * 3)
    periods = [b - a for a, b in zip(result["frame_starts"], result["frame_starts"][1:])]
    print(f"R={rounds}: {periods} clocks per {width}x{height} frame, flush latency "
          f"{result['latency']} pixels")
    assert periods == [width * height * rounds] * 2


def test_missing_size_is_a_parameter_error():
    """Refused before a core exists: nothing is left for Amaranth to report as unused."""
    refused_quietly(lambda: NpStereoCore(StereoParams(transform="census", block=3,
                                                      disparities=8)),
                    ParameterError, "width and height")


# Deliberately broken variants must fail the golden comparison ---------------------------

#: A scene with large tie areas (the flat band), where every tie rule shows.
TIES = stereo_pair("layers", 8, 20, 3)
#: Unrelated images: many inconsistent pixels, some at |dL - dR| = T exactly, and texture
#: up to the frame's edges for the border masks.
NOISE = stereo_pair("independent", 8, 20, 4)
#: Three rows of a frame, then a reset: the line buffers keep those rows (a finished frame
#: would have flushed zeros through them), which only the masks keep out of the next one.
ABORTED = frame_beats(*TIES)[:60] + [RESET]


def assert_caught(params, pair=TIES, before=(), **traffic):
    """The comparison with the golden model reports differing pixels in ``pair``'s frame
    (sent after the beats ``before``)."""
    beats = list(before) + frame_beats(*pair)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], beats, **traffic)


def test_broken_variant_baseline_matches():
    """The unbroken core passes the cases the broken variants below must fail."""
    for rounds, lr, pair, before in ((2, None, TIES, ()), (4, None, TIES, ()),
                                     (2, 0, TIES, ()), (1, 2, NOISE, ()),
                                     (1, None, NOISE, ABORTED)):
        check_frames(StereoParams(transform="census", block=3, disparities=8, rounds=rounds,
                                  lr_threshold=lr, width=20, height=8),
                     [pair], list(before) + frame_beats(*pair))


def test_broken_tie_rule_is_caught(monkeypatch):
    """Ties to the highest disparity in the partition WTA must be detected."""
    monkeypatch.setattr(trees, "better", lambda candidate, best: candidate <= best)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=2,
                               lr_threshold=None, width=20, height=8))


def test_broken_evaluation_comparison_is_caught(monkeypatch):
    """``<=`` instead of ``<`` across partitions (later partition wins ties) is detected."""
    monkeypatch.setattr(evaluation_stage, "better", lambda candidate, best: candidate <= best)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=4,
                               lr_threshold=None, width=20, height=8))


def test_broken_lr_tie_rule_is_caught(monkeypatch):
    """The right-referenced WTA of the L/R check keeping ties at the highest disparity."""
    monkeypatch.setattr(lr_check, "better", lambda candidate, best: candidate <= best)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=2,
                               lr_threshold=0, width=20, height=8))


def test_broken_lr_threshold_is_caught(monkeypatch):
    """|dL - dR| < T instead of <= T in the consistency test."""
    monkeypatch.setattr(lr_check, "_consistent",
                        lambda partner, low, high: (partner > low) & (partner < high))
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=1,
                               lr_threshold=2, width=20, height=8), NOISE)


def test_broken_window_row_mask_is_caught(monkeypatch):
    """Window rows outside the frame left unmasked: the rows an aborted frame left in the
    line buffers leak into the top rows."""
    monkeypatch.setattr(window_centre, "_offset_row_inside", lambda y, offset, height: 1)
    monkeypatch.setattr(window_centre, "_offset_row_inside_at", lambda y, offset, height: 1)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=1,
                               lr_threshold=None, width=20, height=8), NOISE, ABORTED)


def test_broken_window_column_mask_is_caught(monkeypatch):
    """Window columns outside the frame left unmasked: the previous row's end leaks in."""
    monkeypatch.setattr(window_centre, "column_inside", lambda x, offset, width: 1)
    monkeypatch.setattr(window_centre, "_column_inside_at", lambda x, offset, width: 1)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=1,
                               lr_threshold=None, width=20, height=8), NOISE, ABORTED)


@pytest.mark.parametrize("rounds", [1, 2, 3, 4])
def test_credits_hold_under_slow_sink(rounds):
    """The credits are taken a clock after the decision (and at R = 1 reach it through
    two registers): a sink far slower than the core (a word per R clocks against 0.1
    taken per clock) fills the output queue, and no word may be lost."""
    check_frames(StereoParams(transform="census", block=3, disparities=4 * rounds,
                              rounds=rounds, lr_threshold=None, width=20, height=8),
                 [TIES], frame_beats(*TIES), ready_prob=0.1)


def test_late_credit_is_caught(monkeypatch):
    """Credits taken five clocks after the decision instead of one: decisions the
    admission cannot see yet overfill the output queue under a slow sink."""
    real_pipe = core_module.pipe

    def later(m, value, steps, name, reset=False):
        return real_pipe(m, value, steps + 4 if name == "credit_taken" else steps, name,
                         reset)
    monkeypatch.setattr(core_module, "pipe", later)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=2,
                               lr_threshold=None, width=20, height=8), ready_prob=0.1)


def test_broken_credit_is_caught(monkeypatch):
    """Admission that ignores the output queue's room loses words under backpressure."""
    monkeypatch.setattr(credits_module, "_has_room", lambda credits, unseen: 1)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=1,
                               lr_threshold=None, width=20, height=8),
                  ready_prob=0.3)


def test_broken_unseen_decisions_are_caught(monkeypatch):
    """At R = 1 three decisions are on their way to the credit flag: a flag that counts
    one, as at R >= 2, lets the queue overflow under backpressure."""
    monkeypatch.setattr(credits_module, "_unseen_decisions", lambda rounds: 1)
    assert_caught(StereoParams(transform="census", block=3, disparities=8, rounds=1,
                               lr_threshold=None, width=20, height=8),
                  ready_prob=0.1)
