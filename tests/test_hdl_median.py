"""Median3 alone and in the core: the 3x3 median of the output words against the golden
model (golden/median.py), and the broken variants that must be caught.

The stage alone gets streams as the L/R check makes them: words of random maps (invalid
pixels in runs and alone, so that every count of valid neighbours occurs), positions
outside the frame before a frame and after the last one, frames back to back, one tick
every R clocks and bubbles between them.
"""

import itertools

import numpy as np
import pytest
from amaranth.sim import Simulator

from npstereo.golden.median import median3
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl import median as hdl_median
from npstereo.hdl.median import NETWORK, Median3, sorting_network
from npstereo.params import StereoParams

from scenes import stereo_pair

BITS = 3


def random_map(rng, height, width, invalid):
    values = rng.integers(0, 1 << BITS, (height, width))
    holes = rng.random((height, width)) < invalid
    # A few blocks of invalid pixels: centres with every count of valid neighbours.
    for _ in range(2):
        y, x = rng.integers(0, height), rng.integers(0, width)
        holes[y:y + 2, x:x + 3] = True
    return np.where(holes, -1, values).astype(np.int16)


def run_stage(width, height, maps, rounds, gaps, before, seed=0):
    """Feed ``maps`` (frames) to one Median3; returns the frames it produced and the
    number of ticks in and out."""
    params = StereoParams(transform="census", block=3, disparities=2, aggregation=1,
                          width=width, height=height)
    rng = np.random.default_rng(seed)
    ticks = []
    for n, disparity in enumerate(maps):
        # Positions above the frame (the pipeline's fill, or the next frame's first rows
        # while the previous one finishes); none at all before some frames.
        for k in range(before[n] * width):
            ticks.append((k % width, k // width - before[n], 0, 0, 0))
        for y, x in itertools.product(range(height), range(width)):
            value = int(disparity[y, x])
            ticks.append((x, y, 1, value >= 0, max(value, 0)))
    ticks += [(k % width, height + k // width, 0, 0, 0) for k in range(width + 3)]
    clocks = []
    for tick in ticks:
        clocks.append(tick)
        clocks += [None] * (rounds - 1)
        while rng.random() < gaps:
            clocks.append(None)
    clocks += [None] * (hdl_median.MEDIAN_LATENCY + 2)
    stage = Median3(params, BITS)
    words, counts = [], [0, 0]

    async def bench(ctx):
        for clock in clocks:
            if clock is None:
                ctx.set(stage.retire, 0)
                ctx.set(stage.produce, 0)
            else:
                x, y, word, valid, value = clock
                ctx.set(stage.retire, 1)
                ctx.set(stage.produce, word)
                ctx.set(stage.valid, valid)
                # An invalid word's disparity is whatever the check left there.
                ctx.set(stage.disparity, value if valid else int(rng.integers(0, 1 << BITS)))
                ctx.set(stage.x, x)
                ctx.set(stage.y, y)
                counts[0] += 1
            await ctx.tick()
            if ctx.get(stage.retire_out):
                counts[1] += 1
                if ctx.get(stage.produce_out):
                    words.append((ctx.get(stage.disparity_out) if ctx.get(stage.valid_out)
                                  else -1, ctx.get(stage.frame_start), ctx.get(stage.line_end),
                                  ctx.get(stage.frame_end)))

    sim = Simulator(stage)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return words, counts


def expected_words(maps):
    words = []
    for disparity in maps:
        height, width = disparity.shape
        filtered = median3(disparity)
        for y, x in itertools.product(range(height), range(width)):
            words.append((int(filtered[y, x]), int(x == 0 and y == 0), int(x == width - 1),
                          int(x == width - 1 and y == height - 1)))
    return words


def mismatches(width, height, frames, rounds, gaps, seed):
    rng = np.random.default_rng(seed)
    maps = [random_map(rng, height, width, 0.3) for _ in range(frames)]
    before = [2] + [int(rng.integers(0, 3)) for _ in range(frames - 1)]
    words, counts = run_stage(width, height, maps, rounds, gaps, before, seed)
    assert counts[0] == counts[1], "one tick out for every tick in"
    expected = expected_words(maps)
    assert len(words) == len(expected)
    return sum(got != want for got, want in zip(words, expected))


@pytest.mark.parametrize("width, height, frames, rounds, gaps", [
    (7, 5, 3, 1, 0.0), (5, 4, 2, 2, 0.3), (9, 3, 2, 3, 0.2), (3, 6, 2, 1, 0.4),
    (6, 1, 3, 1, 0.1)])
def test_median_stage_bit_exact(width, height, frames, rounds, gaps):
    assert mismatches(width, height, frames, rounds, gaps, seed=width * height) == 0


def test_sorting_network_sorts():
    """The 0-1 principle: a comparator network sorts every input iff it sorts every
    sequence of zeros and ones."""
    pairs = [pair for layer in NETWORK for pair in layer]
    assert sorted(pairs) == sorted(sorting_network(9))
    for bits in itertools.product((0, 1), repeat=9):
        values = list(bits)
        for i, j in pairs:
            if values[j] < values[i]:
                values[i], values[j] = values[j], values[i]
        assert values == sorted(values)


@pytest.mark.parametrize("broken", ["fill at 4", "upper median", "comparator missing",
                                    "no edge masks"])
def test_broken_stage_is_caught(monkeypatch, broken):
    if broken == "fill at 4":
        monkeypatch.setattr(hdl_median, "MEDIAN_FILL", 4)
    elif broken == "upper median":
        monkeypatch.setattr(hdl_median, "_rank_choice", lambda n: (9 + 9 - n) // 2 if n > 1
                            else 8)
    elif broken == "comparator missing":
        # The comparator of the median's index 4 with the largest key.
        assert any((4, 8) in layer for layer in NETWORK)
        monkeypatch.setattr(hdl_median, "NETWORK", [[pair for pair in layer if pair != (4, 8)]
                                                    for layer in NETWORK])
    else:
        monkeypatch.setattr(hdl_median, "_outside", lambda centre, r, k: 0)
    assert mismatches(7, 5, 2, 1, 0.1, seed=35) > 0


def reference_median(disparity):
    """docs/semantics.md's "3x3 median" in plain Python loops."""
    height, width = disparity.shape
    out = np.full((height, width), -1, np.int16)
    for y, x in itertools.product(range(height), range(width)):
        values = sorted(int(disparity[y + j, x + i]) for j in (-1, 0, 1) for i in (-1, 0, 1)
                        if 0 <= y + j < height and 0 <= x + i < width
                        and disparity[y + j, x + i] >= 0)
        if values and (disparity[y, x] >= 0 or len(values) >= 5):
            out[y, x] = values[(len(values) + 1) // 2 - 1]
    return out


@pytest.mark.parametrize("seed", range(4))
def test_golden_median_is_the_reference(seed):
    rng = np.random.default_rng(seed)
    disparity = random_map(rng, 9, 13, 0.1 + 0.2 * seed)
    assert np.array_equal(median3(disparity), reference_median(disparity))


def test_golden_median_rules():
    """golden/median.py on hand-made windows: the lower median of the valid values, an
    invalid centre filled from five valid values and not from four, the frame's outside
    invalid."""
    disparity = np.array([[-1, 3, 3, 4],
                          [5, -1, 3, 3],
                          [2, 2, 2, -1]], np.int16)
    assert median3(disparity).tolist() == [[-1, 3, 3, 3],
                                           [2, 3, 3, 3],
                                           [2, 2, 2, -1]]
    alone = np.full((3, 3), -1, np.int16)
    alone[1, 1] = 7
    assert median3(alone)[1, 1] == 7                # a valid centre keeps a value of its own
    assert (median3(alone)[alone < 0] == -1).all()   # one valid neighbour fills nothing
    four = np.array([[1, 2, -1], [3, -1, -1], [4, -1, -1]], np.int16)
    assert median3(four)[1, 1] == -1
    four[0, 2] = 9
    assert median3(four)[1, 1] == 3                  # five valid: 1 2 3 4 9


# The core with the median: every output pixel against golden/pipeline.py ----------------

from hdl_helpers import check_frames, frame_beats, random_contents, record_memories  # noqa: E402

from npstereo.hdl import plan_timing  # noqa: E402

GAPS = 0.65


def core_params(**changes):
    fields = dict(transform="census", block=3, disparities=8, rounds=1, lr_threshold=1,
                  width=20, height=7, median=True)
    fields.update(changes)
    return StereoParams(**fields)


@pytest.mark.parametrize("changes, image", [
    ({}, "independent"),
    (dict(rounds=2, aggregation=1, lr_threshold=None), "layers"),
    (dict(rounds=4, lr_threshold=0), "layers"),
    (dict(aggregation="sgm", rounds=1, block=5), "layers"),
    (dict(aggregation="sgm", rounds=2, p1=4, p2=20, lr_threshold=2), "independent"),
])
def test_core_with_median_matches_golden(changes, image):
    params = core_params(**changes)
    pair = stereo_pair(image, params.height, params.width, 17, params.disparities)
    assert (median3(disparity_map(*pair, params.replace(median=False)).disparity)
            == disparity_map(*pair, params).disparity).all()
    check_frames(params, [pair], frame_beats(*pair), valid_prob=GAPS, ready_prob=GAPS,
                 seed=params.rounds)


def test_core_with_median_frames_back_to_back_and_after_a_gap():
    """Frames back to back (the next frame's positions push the last row out of the
    median), then a gap long enough for the flush to finish."""
    params = core_params(rounds=2)
    pairs = [stereo_pair("layers", 7, 20, 7, 8), stereo_pair("independent", 7, 20, 8),
             stereo_pair("layers", 7, 20, 9, 8)]
    beats = frame_beats(*pairs[0]) + frame_beats(*pairs[1]) + [300] + frame_beats(*pairs[2])
    check_frames(params, pairs, beats, valid_prob=GAPS, ready_prob=GAPS, seed=4)


def test_core_with_median_ignores_stale_memories(monkeypatch):
    """Every memory (the median's line buffers too) full of random words before the first
    frame, the median's entries marked as words: none of them reaches a result, and no
    word of a position that never was comes out."""
    made = record_memories(monkeypatch)
    rng = np.random.default_rng(3)

    fill = random_contents(made, rng, "word", lambda ctx, word: ctx.set(word.word, 1))

    params = core_params()
    pair = stereo_pair("layers", 7, 20, 21, 8)
    result = check_frames(params, [pair], frame_beats(*pair), before_start=fill)
    assert any("word" in getattr(store.shape, "members", {}) for store in made)
    assert len(result["words"]) == 20 * 7, "words of positions that never were came out"


def test_broken_median_guard_is_caught(monkeypatch):
    """Primed after the first tick instead of W + 1: the stale entries of the line buffer
    come out as words."""
    monkeypatch.setattr(hdl_median, "_priming_ticks", lambda width: 0)
    with pytest.raises(AssertionError, match="never were"):
        test_core_with_median_ignores_stale_memories(monkeypatch)


def test_latency_is_the_measured_flush_with_median():
    """After a frame's last pixel its last word leaves ``plan_timing.latency`` positions
    (W + 1 more than without the median) and the output offset later, as measured; the
    formula without the median's W + 1 fails the same measurement."""
    from test_hdl_plan import measured_flush, planned_flush
    params = core_params(width=24, height=6)
    flush, output = measured_flush(params)
    assert flush == planned_flush(params, output)
    assert output == plan_timing.core_timing(params.replace(median=False)).output \
        + hdl_median.MEDIAN_LATENCY
    plain = plan_timing.latency(params.replace(median=False))
    assert plan_timing.latency(params) == plain + params.width + 1
    assert flush != plain * params.rounds + output


# The generated Verilog under cocotb (Icarus) ----------------------------------------------

def test_icarus_stream_with_median():
    """Frames back to back under idle cycles and backpressure, a reset, misframed lines and
    an aborted frame (test_cocotb's full plan), the median on: every good frame bit-exact;
    the same core with the upper median instead of the lower is reported mismatching."""
    from npstereo.hdl.verilog import core_verilog
    from npstereo.sim import cosim
    from test_cocotb import FULL_PLAN, assert_bit_exact, config, frames

    params = config("census", 3, 8, 1, 1).replace(median=True)
    pairs = frames(params)
    assert_bit_exact(cosim.run_stream("icarus", params, pairs, FULL_PLAN))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hdl_median, "_rank_choice", lambda n: (9 + 9 - n) // 2 if n > 1 else 8)
        broken = core_verilog(params)
    result = cosim.run_stream("icarus", params, pairs, FULL_PLAN[:1], core_text=broken)
    assert result.frames and not result.ok
