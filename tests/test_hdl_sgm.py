"""Semi-global aggregation in hardware (hdl/sgm.py) against the golden model (golden/sgm.py).

The stage alone: :class:`SemiGlobalAggregation` is fed random cost volumes and gray images
position by position -- a partial frame and rows above the frame first, slots without a
position in between (random inputs in them), every memory full of random words -- and every
S(x, y, d) of the frame is compared with ``golden.sgm.aggregate``; D/R from 1 to 4 lanes, R
at its minimum and above, constant and adaptive P2, P1 = P2 = 0 and P2 at its largest.
The core: whole frames through :class:`NpStereoCore` in Amaranth's simulator against
``golden.pipeline.disparity_map`` (which dispatches to golden.sgm), all four transforms,
random source gaps and sink backpressure, frames back to back, a reset in mid-frame,
mis-framed input. ``test_broken_*`` monkeypatch a wrong rule into the hardware and prove
that the same comparison catches it.
"""

import random

import numpy as np
import pytest
from amaranth.hdl import Value
from amaranth.lib import memory
from amaranth.sim import Simulator

from npstereo.golden import sgm as golden_sgm
from npstereo.hdl import calculation_stage, plan, plan_memories, plan_timing
from npstereo.hdl import sgm as hdl_sgm
from npstereo.hdl.core import NpStereoCore
from npstereo.hdl.sgm import GUIDE, SemiGlobalAggregation
from npstereo.params import ParameterError, StereoParams

from hdl_helpers import RESET, check_frames, frame_beats
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
    made = []
    create = memory.Memory.__init__

    def recording(self, *args, **kwargs):
        create(self, *args, **kwargs)
        made.append(self)

    monkeypatch.setattr(memory.Memory, "__init__", recording)
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


def check_stage(params, monkeypatch, seed, bubbles=0.3):
    """Stream a random volume through the stage alone; every S of the frame must be the
    golden model's."""
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
                                    max_cost=top)
    padded = np.pad(guide, 1)

    slots = stage_slots(width, height, stream, bubbles)
    clocks = [(slot, j) for slot in slots for j in range(rounds)]
    fill = random_memories(monkeypatch, seed)
    dut = SemiGlobalAggregation(params)
    assert dut.latency == plan_timing.aggregation_latency(params)
    latency, got = dut.latency, {}

    async def testbench(ctx):
        fill(ctx)
        for t in range(len(clocks) + latency):
            slot, j = clocks[t] if t < len(clocks) else (None, t % rounds)
            ctx.set(dut.first, j == 0)
            ctx.set(dut.round, j)
            if slot is None or slot[0] != "frame":
                x, y = (stream.randrange(width), 0) if slot is None else slot[1:]
                ctx.set(dut.tag, {"x": x, "y": y, "valid": slot is not None, "live": 1})
                for i in range(units):
                    ctx.set(dut.costs[i], stream.randrange(top + 1))
                for k in range(len(GUIDE)):
                    ctx.set(dut.guide[k], stream.randrange(256))
            else:
                _, x, y = slot
                ctx.set(dut.tag, {"x": x, "y": y, "valid": 1, "live": 1})
                for i in range(units):
                    ctx.set(dut.costs[i], int(volume[y, x, j * units + i]))
                for k, (dy, dx) in enumerate(GUIDE):
                    ctx.set(dut.guide[k], int(padded[y + dy + 1, x + dx + 1]))
            if t >= latency and clocks[t - latency][0] is not None \
                    and clocks[t - latency][0][0] == "frame":
                (_, x, y), j = clocks[t - latency]
                centre = ctx.get(dut.centre)
                assert (centre.x, centre.y, centre.valid) == (x, y, 1)
                for i in range(units):
                    got[(y, x, j * units + i)] = ctx.get(dut.sums[i])
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    assert len(got) == expected.size, "not every sum was compared"
    mismatches = [(key, value, int(expected[key])) for key, value in sorted(got.items())
                  if value != expected[key]]
    assert not mismatches, (f"{len(mismatches)} sums differ, first ((y, x, d), got, "
                            f"expected): {mismatches[0]}")


STAGES = [
    # transform, block, D, R, P1, P2, t, width, height
    ("census", 3, 8, 8, 3, 20, 2, 10, 5),            # one lane, R at its minimum
    ("census", 5, 16, 8, 16, 96, 4, 18, 4),          # two lanes, the minimum R for D = 16
    ("census", 3, 24, 8, 4, 20, None, 26, 3),        # three lanes, constant P2
    ("rank", 5, 32, 8, 7, 40, 5, 34, 2),             # four lanes (T = 2), the minimum R
    ("ext-rank", 3, 12, 12, 0, 0, None, 14, 4),      # P1 = P2 = 0, 11-bit path costs
    ("ext-census", 3, 6, 6, 2000, 6151, 1, 8, 5),    # P2 = P2max, t = 1
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


def test_broken_left_normalisation_is_caught(monkeypatch):
    """The left path's L formed without subtracting m(x - 1)."""
    real = hdl_sgm._materialise
    monkeypatch.setattr(hdl_sgm, "_materialise", lambda ca, e, cp, cpp, minimum, minimum_p1:
                        real(ca, e, cp, cpp, 0, minimum_p1))
    assert_stage_caught(monkeypatch)


def test_broken_left_minimum_is_caught(monkeypatch):
    """m(x) taken as min(U, Cmin + P2), forgetting that U carries m(x - 1)."""
    real = hdl_sgm._next_minimum
    monkeypatch.setattr(hdl_sgm, "_next_minimum",
                        lambda total, bound, previous, previous_p1, capped, capped_p1, fresh:
                        real(total, bound, 0, previous_p1, capped, capped_p1, fresh))
    assert_stage_caught(monkeypatch)


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
                        lambda centre, lower, upper: hdl_sgm.Mux(lower < centre, lower, centre))
    assert_stage_caught(monkeypatch)


def test_broken_adaptive_p2_is_caught(monkeypatch):
    """Adaptive P2 halved one doubling of the step too early."""
    real = hdl_sgm._adaptive_p2
    monkeypatch.setattr(hdl_sgm, "_adaptive_p2", lambda step, p1, p2, adapt:
                        real(step, p1, p2, adapt - 1))
    assert_stage_caught(monkeypatch)


def test_broken_row_normalisation_is_caught(monkeypatch):
    """The paths from above capped at P2 without the normalisation (best - m)."""
    monkeypatch.setattr(hdl_sgm, "_normalised", lambda best, minimum, bound, p2, fresh:
                        hdl_sgm.Mux(fresh, 0, hdl_sgm.Mux(best <= p2, best, p2)))
    assert_stage_caught(monkeypatch)


# The core ----------------------------------------------------------------------------------

CORES = [
    # transform, block, D, R, P1, P2, t (None: the default), L/R threshold, image kind, W, H
    ("census", 3, 8, 8, 3, 20, 2, 1, "layers", 20, 6),
    ("rank", 5, 16, 8, 8, 30, 0, None, "independent", 24, 5),     # two lanes, R minimal
    ("ext-rank", 3, 24, 8, None, None, None, 1, "random", 30, 4),  # three lanes, R minimal
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


def test_core_reset_misframing_and_frames_back_to_back():
    """A reset in mid-frame, a frame whose second line ends early (a framing error, the
    rest filled), then two frames that overlap in the pipeline (the second's first rows
    come in while the first's last rows are computed): both bit-exact."""
    first, second = stereo_pair("layers", 5, 14, 7), stereo_pair("independent", 5, 14, 8)
    misframed = frame_beats(*second)
    data, user, _ = misframed[14 + 5]
    misframed[14 + 5] = (data, user, True)
    beats = frame_beats(*first)[:30] + [RESET] + misframed + frame_beats(*first) \
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

@pytest.mark.parametrize("disparities,rounds", [(8, 8), (16, 8), (24, 8), (12, 12),
                                                (40, 10), (64, 16), (100, 10), (256, 16),
                                                (7, 7), (5, None)])
def test_minimum_rounds(disparities, rounds):
    """R >= ceil(log2(D/R)) + 6: the smallest divisor of D that fits."""
    assert plan_timing.sgm_min_rounds(disparities) == rounds


@pytest.mark.parametrize("disparities,rounds,message", [
    (8, 4, "aggregation sgm needs rounds >= 8 for 8 disparities (the left path's loop "
           "takes 7 clocks at 2 per round), not 4"),
    (100, 5, "aggregation sgm needs rounds >= 10 for 100 disparities (the left path's loop "
             "takes 11 clocks at 20 per round), not 5"),
    (4, 4, "aggregation sgm needs rounds >= 6 (the left path's loop), so disparities >= 6, "
           "not 4"),
])
def test_too_few_rounds_are_refused(disparities, rounds, message):
    params = sgm_params("census", 5, disparities, rounds, width=disparities + 4, height=4)
    with pytest.raises(ParameterError) as error:
        plan.check_buildable(params)
    assert str(error.value) == message
    with pytest.raises(ParameterError, match="needs rounds"):
        NpStereoCore(params)
    # The smallest R that fits is built.
    enough = plan_timing.sgm_min_rounds(disparities)
    if enough is not None:
        plan.check_buildable(params.replace(rounds=enough))


def test_sgm_memories_within_the_budget():
    """At 450 x 375, D = 100, R = 10 with the defaults: 3 x 450 x 100 x 7 bits of path
    costs, 3 x 450 x 7 of minima, two stores of 10 words, and all of SGM's memory beside
    the box configuration's under 1 Mibit."""
    params = sgm_params("census", 7, 100, 10, width=450, height=375)
    kinds = {memory.name: memory.bits for memory in plan_memories.sgm_memories(params)}
    assert kinds == {"path rows (top, top-left)": 630_000, "path rows (top-right)": 315_000,
                     "path minima": 9_450, "left path store": 700, "top-left store": 700}
    box = params.replace(aggregation=3, p1=None, p2=None, p2_adapt=None)
    assert plan_memories.memory_bits(params) - plan_memories.memory_bits(box) < 1 << 20
    # Counterpart: one more step of P2 makes the path cost 8 bits, and the rows of path
    # costs with their minima alone would hold more than 1 Mibit.
    wider = plan_memories.sgm_memories(params.replace(p2=params.p2 + 1))
    assert sum(memory.bits for memory in wider if memory.name.startswith("path")) > 1 << 20
