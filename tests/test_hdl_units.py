"""The HDL datapath units and the aggregation against the golden model, in Amaranth's simulator.

Every unit gets a stream of random inputs with ``en`` toggling randomly (garbage on the
inputs while ``en`` is low, which the pipeline must ignore) and every output is compared,
``latency`` ``en``-high clocks later, with the golden model. The ``test_broken_*`` cases
monkeypatch a deliberately wrong primitive into the hardware and assert that the same check
catches it.
"""

import random

import numpy as np
import pytest
from amaranth.hdl import Const, Fragment
from amaranth.sim import Simulator

from npstereo.golden import aggregation as golden_aggregation
from npstereo.golden import matching_cost as golden_cost
from npstereo.golden import transform as golden_transform
from npstereo.hdl import aggregation as hdl_aggregation
from npstereo.hdl import matching_cost as hdl_cost
from npstereo.hdl import plan_structure, plan_timing
from npstereo.hdl import transform as hdl_transform
from npstereo.hdl import trees
from npstereo.hdl.aggregation import Aggregation
from npstereo.hdl.matching_cost import MatchingCost
from npstereo.hdl.transform import Transform
from npstereo.params import TRANSFORMS, StereoParams

from hdl_helpers import choose_bank_early
from hdl_trees import AdderTree, MinTree, PopCount


def run_stream(dut, inputs, apply, read, expected, seed, en_probability=0.6, garbage=None):
    """Drive ``inputs`` through ``dut`` with a random ``en``; return the mismatches.

    Parameters
    ----------
    dut : Component
        Has ``en`` and ``latency``.
    inputs : list
        One item per ``en``-high clock.
    apply : callable
        ``apply(ctx, item)`` sets the input ports.
    read : callable
        ``read(ctx)`` returns the output as a comparable value.
    expected : list
        Golden output of each item.
    seed : int
    en_probability : float
        Chance of ``en`` being high in a clock.
    garbage : callable, optional
        ``garbage(rng)`` makes an input presented while ``en`` is low.

    Returns
    -------
    (int, list)
        Number of comparisons made and the (input index, got, expected) mismatches.
    """
    latency = dut.latency
    result = {"checks": 0, "mismatches": []}

    def check(ctx, index):
        got = read(ctx)
        result["checks"] += 1
        if got != expected[index]:
            result["mismatches"].append((index, got, expected[index]))

    async def testbench(ctx):
        rng = random.Random(seed)
        taken = 0
        while taken < len(inputs) + latency:
            en = rng.random() < en_probability
            if en and taken < len(inputs):
                apply(ctx, inputs[taken])
            elif garbage is not None:
                apply(ctx, garbage(rng))
            ctx.set(dut.en, en)
            if latency == 0 and en and taken < len(inputs):
                check(ctx, taken)
            await advance(ctx)
            taken += en
            if latency > 0 and latency <= taken < len(inputs) + latency:
                check(ctx, taken - latency)

    sim = Simulator(dut)
    if latency > 0:
        sim.add_clock(1e-6)
        advance = ctx_tick
    else:
        # A combinational unit (every = 0) has no clock domain to tick.
        advance = ctx_delay
    sim.add_testbench(testbench)
    sim.run()
    return result["checks"], result["mismatches"]


async def ctx_tick(ctx):
    await ctx.tick()


async def ctx_delay(ctx):
    await ctx.delay(1e-6)


def assert_stream_matches(*args, **kwargs):
    checks, mismatches = run_stream(*args, **kwargs)
    assert checks >= len(args[1]), "the testbench compared fewer outputs than it sent inputs"
    assert not mismatches, (f"{len(mismatches)} of {checks} outputs differ, first "
                            f"(input, got, expected): {mismatches[0]}")


# Transforms ------------------------------------------------------------------------------

def random_windows(block, count, rng):
    """Windows that stress the strict comparison: equal pixels, 0 and 255, ramps."""
    size = block * block
    windows = []
    for i in range(count):
        kind = i % 5
        if kind == 0:
            window = rng.integers(0, 256, size)
        elif kind == 1:
            # Few distinct levels around the centre: many ties with it.
            levels = rng.integers(0, 256, 3)
            window = rng.choice(levels, size)
        elif kind == 2:
            window = rng.choice(np.array([0, 1, 254, 255]), size)
        elif kind == 3:
            window = np.full(size, rng.choice([0, 255, int(rng.integers(0, 256))]))
            window[rng.integers(0, size, 2)] = rng.integers(0, 256, 2)
        else:
            window = rng.integers(0, 256, size)
            window[size // 2] = rng.choice([0, 255])
        windows.append(window.astype(np.uint8))
    return windows


def golden_window_value(window, params):
    """The golden transform of the window's centre pixel, packed as the hardware packs it."""
    block, r = params.block, params.radius
    image = window.reshape(block, block)
    out = golden_transform.transform(image, params)
    if params.transform == "census":
        return sum(int(word) << (64 * w) for w, word in enumerate(out[:, r, r]))
    if params.transform == "ext-census":
        return sum(int(byte) << (8 * n) for n, byte in enumerate(out[:, r, r]))
    return int(out[r, r])


def pack_window(window):
    return sum(int(p) << (8 * i) for i, p in enumerate(window))


def check_transform(params, every, seed, count=100, en_probability=0.6):
    rng = np.random.default_rng(seed)
    windows = random_windows(params.block, count, rng)
    expected = [golden_window_value(w, params) for w in windows]
    dut = Transform(params, every)
    assert_stream_matches(
        dut, windows,
        lambda ctx, w: ctx.set(dut.window.as_value(), pack_window(w)),
        lambda ctx: ctx.get(dut.value),
        expected, seed, en_probability,
        garbage=lambda r: np.array([r.randrange(256) for _ in range(params.block ** 2)]))


@pytest.mark.parametrize("en_probability", [1.0, 0.1])
def test_transform_with_enable_always_or_rarely_high(en_probability):
    # Back-to-back windows (every register loads each clock) and long stalls.
    for transform in ("rank", "ext-census"):
        check_transform(StereoParams(transform=transform, block=5), 1, seed=11, count=40,
                        en_probability=en_probability)


# (block, register spacing): every spacing, including combinational, and one large block.
TRANSFORM_CASES = [(3, 2), (5, 1), (7, 0), (7, 3), (11, 2), (19, 2)]


@pytest.mark.parametrize("transform", TRANSFORMS)
@pytest.mark.parametrize("block,every", TRANSFORM_CASES)
def test_transform_matches_golden(transform, block, every):
    check_transform(StereoParams(transform=transform, block=block), every,
                    seed=block * 10 + every)


@pytest.mark.parametrize("transform", ["census", "rank"])
@pytest.mark.parametrize("block,every", [(3, 2), (5, 0), (7, 2)])
def test_transform_masking_after_compare_matches_golden(transform, block, every):
    # The window arrives unmasked with a flag per pixel; the golden transform sees the
    # pixels outside the frame as 0 (the centre is never masked).
    params = StereoParams(transform=transform, block=block)
    rng = np.random.default_rng(block * 7 + every)
    size, centre = block * block, block * block // 2
    windows = random_windows(block, 100, rng)
    keeps = [rng.random(size) < rng.choice([0.0, 0.5, 0.9, 1.0]) for _ in windows]
    inputs = list(zip(windows, keeps))
    masked = [np.where(keep | (np.arange(size) == centre), window, 0).astype(np.uint8)
              for window, keep in inputs]
    dut = Transform(params, every, mask_after=True)

    def apply(ctx, item):
        window, keep = item
        ctx.set(dut.window.as_value(), pack_window(window))
        ctx.set(dut.keep, sum(int(bit) << i for i, bit in enumerate(keep)))

    assert_stream_matches(
        dut, inputs, apply, lambda ctx: ctx.get(dut.value),
        [golden_window_value(w, params) for w in masked], 5, 0.6,
        garbage=lambda r: (np.array([r.randrange(256) for _ in range(size)]),
                           np.array([r.random() < 0.5 for _ in range(size)])))


@pytest.mark.parametrize("transform", ["ext-rank", "ext-census"])
def test_transform_masking_after_compare_is_for_bitwise_transforms(transform):
    with pytest.raises(ValueError, match=rf"mask_after is for the transforms of comparisons "
                                         rf"\(rank, census\), not {transform}"):
        Transform(StereoParams(transform=transform, block=3), mask_after=True)


def test_transform_latency_grows_logarithmically():
    units = [Transform(StereoParams(transform="rank", block=b)) for b in (3, 7, 19)]
    for unit in units:
        Fragment.get(unit, None)  # elaborates: the tree really has that many stages
    latencies = [unit.latency for unit in units]
    assert latencies == sorted(latencies) and latencies[-1] <= 6, latencies


# Matching costs --------------------------------------------------------------------------

def random_transformed(params, count, rng):
    """Random transformed pixels in the legal range, with extremes and equal pairs."""
    k = params.neighbours
    top = {"rank": k, "ext-rank": 255 * k}.get(params.transform)
    pairs = []
    for i in range(count):
        if params.transform in ("rank", "ext-rank"):
            left, right = (int(v) for v in rng.integers(0, top + 1, 2))
            if i % 4 == 1:
                left, right = rng.permutation([0, top])
            elif i % 4 == 2:
                right = left
        else:
            if params.transform == "census":
                bits = rng.integers(0, 2, (2, k))
            else:
                bits = rng.integers(0, 256, (2, k))
                if i % 4 == 1:
                    bits = np.stack([rng.choice([0, 255], k), rng.choice([0, 255], k)])
            if i % 4 == 2:
                bits[1] = bits[0]
            if i % 4 == 3:
                bits[1] = (255 if params.transform == "ext-census" else 1) - bits[0]
            step = 1 if params.transform == "census" else 8
            left, right = (sum(int(v) << (step * n) for n, v in enumerate(row)) for row in bits)
        pairs.append((int(left), int(right)))
    return pairs


def golden_array(value, params):
    """A transformed pixel as the golden model stores it, for a 1 x 1 image."""
    k = params.neighbours
    if params.transform == "census":
        words = [(value >> (64 * w)) & (2 ** 64 - 1) for w in range((k + 63) // 64)]
        return np.array(words, dtype=np.uint64).reshape(-1, 1, 1)
    if params.transform == "ext-census":
        return np.array([(value >> (8 * n)) & 255 for n in range(k)],
                        dtype=np.uint8).reshape(-1, 1, 1)
    return np.array([[value]], dtype=np.int64)


def check_matching_cost(params, every, seed, count=100):
    rng = np.random.default_rng(seed)
    pairs = random_transformed(params, count, rng)
    expected = [int(golden_cost.matching_costs(golden_array(a, params),
                                               golden_array(b, params), 0, params)[0, 0])
                for a, b in pairs]
    dut = MatchingCost(params, every)

    def apply(ctx, pair):
        ctx.set(dut.left, pair[0])
        ctx.set(dut.right, pair[1])

    assert_stream_matches(
        dut, pairs, apply, lambda ctx: ctx.get(dut.cost), expected, seed,
        garbage=lambda r: (r.getrandbits(params.transform_bits),
                           r.getrandbits(params.transform_bits)))


@pytest.mark.parametrize("transform", TRANSFORMS)
@pytest.mark.parametrize("block,every", TRANSFORM_CASES)
def test_matching_cost_matches_golden(transform, block, every):
    check_matching_cost(StereoParams(transform=transform, block=block), every,
                        seed=block * 10 + every + 1)


# Sums of absolute differences arranged for 6-input LUTs (compressors in front of the
# adders): the ext. rank transform and the ext. census cost, every spacing and large blocks.
@pytest.mark.parametrize("block,every", TRANSFORM_CASES)
def test_sums_of_differences_for_six_input_luts_match_golden(block, every):
    check_transform(StereoParams(transform="ext-rank", block=block, lut_inputs=6), every,
                    seed=block * 10 + every + 2)
    check_matching_cost(StereoParams(transform="ext-census", block=block, lut_inputs=6),
                        every, seed=block * 10 + every + 3)


def test_broken_compressor_is_caught(monkeypatch):
    """The compressors' carries at their own place instead of one place up."""
    real = trees.compress_three

    def carries_in_place(values):
        # Each group of three gives (sum, carries a place up): drop that place.
        carries = 2 * (len(values) // 3)
        return [v[1:] if i < carries and i % 2 else v for i, v in enumerate(real(values))]

    monkeypatch.setattr(trees, "compress_three", carries_in_place)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_transform(StereoParams(transform="ext-rank", block=3, lut_inputs=6), 2, seed=2)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_matching_cost(StereoParams(transform="ext-census", block=3, lut_inputs=6), 2,
                            seed=3)


# Trees -----------------------------------------------------------------------------------

def check_min_tree(count, width, every, seed, samples=40, split=False):
    rng = np.random.default_rng(seed)
    top = 2 ** width - 1
    vectors = []
    for i in range(samples):
        if i % 3 == 0:
            vector = rng.integers(0, 3, count)  # many ties
        elif i % 3 == 1:
            vector = rng.choice([0, top], count)
        else:
            vector = rng.integers(0, top + 1, count)
        vectors.append([int(v) for v in vector])
    expected = [(min(v), int(np.argmin(v))) for v in vectors]  # argmin: first minimum
    dut = MinTree(count, width, every, split)

    def apply(ctx, vector):
        for i, v in enumerate(vector):
            ctx.set(dut.values[i], v)

    assert_stream_matches(
        dut, vectors, apply, lambda ctx: (ctx.get(dut.min), ctx.get(dut.index)), expected,
        seed, garbage=lambda r: [r.randrange(top + 1) for _ in range(count)])


@pytest.mark.parametrize("count,width,every",
                         [(1, 4, 2), (2, 3, 0), (3, 5, 1), (8, 6, 2), (13, 4, 3), (33, 12, 2)])
def test_min_tree_matches_numpy_argmin(count, width, every):
    check_min_tree(count, width, every, seed=count)


@pytest.mark.parametrize("count,width", [(1, 4), (2, 3), (5, 5), (10, 10), (13, 4)])
def test_split_min_tree_matches_numpy_argmin(count, width):
    """The core's minimum trees: comparison and choice in separate clocks."""
    check_min_tree(count, width, 0, seed=count, split=True)


def check_adder_tree(count, width, every, seed, samples=30):
    rng = np.random.default_rng(seed)
    top = 2 ** width - 1
    vectors = [[int(v) for v in (rng.integers(0, top + 1, count) if i % 2
                                 else np.full(count, top))] for i in range(samples)]
    dut = AdderTree(count, width, every)

    def apply(ctx, vector):
        for i, v in enumerate(vector):
            ctx.set(dut.inputs[i], v)

    assert_stream_matches(dut, vectors, apply, lambda ctx: ctx.get(dut.sum),
                          [sum(v) for v in vectors], seed,
                          garbage=lambda r: [r.randrange(top + 1) for _ in range(count)])


@pytest.mark.parametrize("count,width,every", [(1, 8, 1), (5, 8, 0), (17, 8, 2), (40, 3, 3)])
def test_adder_tree_sums(count, width, every):
    check_adder_tree(count, width, every, seed=count)


def check_popcount(width, every, seed, samples=30):
    rng = random.Random(seed)
    vectors = [(2 ** width - 1) if i % 3 == 0 else rng.getrandbits(width)
               for i in range(samples)]
    dut = PopCount(width, every)
    assert_stream_matches(dut, vectors, lambda ctx, v: ctx.set(dut.bits, v),
                          lambda ctx: ctx.get(dut.count), [v.bit_count() for v in vectors],
                          seed, garbage=lambda r: r.getrandbits(width))


@pytest.mark.parametrize("width,every", [(1, 2), (2, 0), (4, 1), (24, 2), (80, 3), (360, 2)])
def test_popcount_counts(width, every):
    check_popcount(width, every, seed=width)


# Deliberately broken variants must fail the same checks --------------------------------

def test_broken_comparison_is_caught(monkeypatch):
    monkeypatch.setattr(hdl_transform, "xi", lambda centre, neighbour: centre >= neighbour)
    for transform in ("rank", "census"):
        with pytest.raises(AssertionError, match="outputs differ"):
            check_transform(StereoParams(transform=transform, block=3), 2, seed=1)


def test_broken_absolute_difference_is_caught(monkeypatch):
    def wrapping(a, b):
        return (a - b)[:max(len(a), len(b))]

    monkeypatch.setattr(hdl_transform, "absolute_difference", wrapping)
    monkeypatch.setattr(hdl_cost, "absolute_difference", wrapping)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_transform(StereoParams(transform="ext-census", block=3), 2, seed=2)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_matching_cost(StereoParams(transform="rank", block=3), 2, seed=3)


def test_broken_sum_of_absolute_differences_is_caught(monkeypatch):
    """The increments of the inverted negative differences left out of the sum."""
    def without_borrows(pairs, lut_inputs=4):
        leaves = []
        for a, b in pairs:
            width = max(len(a), len(b))
            difference = a - b
            leaves.append(difference[:width] ^ difference[width].replicate(width))
        return leaves + [Const(0, 2)] * ((len(pairs) + 2) // 3)

    monkeypatch.setattr(trees, "sad_leaves", without_borrows)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_transform(StereoParams(transform="ext-rank", block=3), 2, seed=2)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_matching_cost(StereoParams(transform="ext-census", block=3), 2, seed=3)


def test_broken_min_tie_rule_is_caught(monkeypatch):
    monkeypatch.setattr(trees, "better", lambda candidate, best: candidate <= best)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_min_tree(8, 4, 2, seed=4)


def test_broken_popcount_compressor_is_caught(monkeypatch):
    real = trees.full_adder_compress

    def no_carry(bits):
        return [c[0] for c in real(bits)]

    monkeypatch.setattr(trees, "full_adder_compress", no_carry)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_popcount(24, 2, seed=5)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_matching_cost(StereoParams(transform="census", block=3), 2, seed=6)


def test_broken_adder_width_is_caught(monkeypatch):
    monkeypatch.setattr(trees, "_add", lambda lower, upper: (
        (lower[0] + upper[0])[:max(len(lower[0]), len(upper[0]))],))
    with pytest.raises(AssertionError, match="outputs differ"):
        check_adder_tree(5, 8, 2, seed=7)


def test_ignoring_enable_is_caught(monkeypatch):
    def free_running(m, en, items, level):
        regs = []
        for item in items:
            item_regs = tuple(trees.Signal(trees.Value.cast(v).shape()) for v in item)
            m.d.sync += [r.eq(v) for r, v in zip(item_regs, item)]
            regs.append(item_regs)
        return regs

    monkeypatch.setattr(trees, "_register", free_running)
    with pytest.raises(AssertionError, match="outputs differ"):
        check_transform(StereoParams(transform="rank", block=5), 2, seed=8)


# Aggregation -----------------------------------------------------------------------------

def check_aggregation(params, seed, bubbles=0.3):
    """Stream positions of random costs through ``Aggregation``; compare the sums.

    A partial first frame (three rows, as after a reset in mid-frame) leaves its costs in
    the stored rows; then the second frame, and a rows and a columns of positions below
    it (zero costs) that push its last sums out. Slots without a position (bubbles) are
    mixed in; in them the inputs are random and must be ignored. Every sum of the second
    frame must come out, at the centre its tag names.
    """
    rng = np.random.default_rng(seed)
    stream = random.Random(seed)
    width, height, a = params.width, params.height, params.agg_radius
    rounds, units, D = params.rounds, params.per_round, params.disparities
    frames = [rng.integers(0, params.max_cost + 1, (D, height, width)) for _ in range(2)]
    frames[1][:, ::3, ::2] = params.max_cost          # the widest sums
    expected = np.stack([golden_aggregation.aggregate(frames[1][d], params.aggregation)
                         for d in range(D)])
    from_costs = params.stored_rows == "costs"

    def inputs(frame, x, y, d):
        """The costs variant gets the row's cost, the transforms variant the vertical sum
        of the rows y - A + 1 .. y inside the frame (as the cost stage masks them)."""
        if from_costs:   # as computed: the aggregation masks the rows
            return int(frames[frame][d, y, x]) if y < height else stream.randrange(9)
        return int(sum(frames[frame][d, y - k, x] for k in range(params.aggregation)
                       if 0 <= y - k < height))

    positions = ([(0, x, y) for y in range(3) for x in range(width)]
                 + [(1, x, y) for y in range(height + a) for x in range(width)]
                 + [(1, x, height + a) for x in range(a + 1)])
    slots = []
    for position in positions:
        while stream.random() < bubbles:
            slots.append(None)
        slots.append(position)
    clocks = [(slot, j) for slot in slots for j in range(rounds)]
    dut = Aggregation(params)
    latency = dut.latency
    skews = plan_timing.unit_skews(params)
    assert latency == plan_timing.aggregation_latency(params) + skews[-1]
    got = {}
    # The units' costs of each clock; unit i takes its own s_i clocks late (the skew of the
    # cost units, :func:`npstereo.hdl.plan_timing.unit_skews`).
    given = []
    total = len(clocks) + latency + rounds

    def slot_at(t):
        return clocks[t] if t < len(clocks) else (None, t % rounds)
    # Each clock's tag (a bubble's is random), and a clock ahead for R = 1's masks.
    tags = [{"x": stream.randrange(width), "y": stream.randrange(height), "valid": 0,
             "live": 1} if slot_at(t)[0] is None else
            {"x": slot_at(t)[0][1], "y": slot_at(t)[0][2], "valid": 1, "live": 1}
            for t in range(total + 1)]

    async def testbench(ctx):
        for t in range(total):
            slot, j = slot_at(t)
            ctx.set(dut.first, j == 0)
            ctx.set(dut.round, j)
            ctx.set(dut.tag, tags[t])
            if dut.masks_ahead:
                ctx.set(dut.tag_ahead, tags[t + 1])
            if slot is None:
                given.append([stream.randrange(params.max_cost + 1) for i in range(units)])
            else:
                frame, x, y = slot
                given.append([inputs(frame, x, y, j * units + i) for i in range(units)])
            for i in range(units):
                ctx.set(dut.costs[i], given[t - skews[i]][i] if t >= skews[i]
                        else stream.randrange(params.max_cost + 1))
            if t >= latency:
                centre = ctx.get(dut.centre)
                out_round = clocks[t - latency][1] if t - latency < len(clocks) else None
                out_slot = clocks[t - latency][0] if t - latency < len(clocks) else None
                if out_slot is not None and out_slot[0] == 1 and centre.valid \
                        and 0 <= centre.y < height:
                    for i in range(units):
                        got[(centre.y, centre.x, out_round * units + i)] = \
                            ctx.get(dut.sums[i])
            await ctx.tick()

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(testbench)
    sim.run()
    assert len(got) == width * height * D, "not every sum was compared"
    mismatches = [(key, value, int(expected[key[2], key[0], key[1]]))
                  for key, value in got.items() if value != expected[key[2], key[0], key[1]]]
    assert not mismatches, (f"{len(mismatches)} sums differ, first ((y, x, d), got, "
                            f"expected): {mismatches[0]}")


@pytest.mark.parametrize("transform,aggregation,disparities,rounds", [
    ("census", 3, 6, 1), ("rank", 3, 6, 3), ("ext-census", 5, 6, 2), ("ext-rank", 5, 4, 4)])
@pytest.mark.parametrize("line_buffer", ["costs", "transforms", "pixels"])
def test_aggregation_matches_golden(transform, aggregation, disparities, rounds, line_buffer):
    params = StereoParams(transform=transform, block=3, disparities=disparities,
                          rounds=rounds, aggregation=aggregation, width=9, height=6,
                          line_buffer=line_buffer)
    check_aggregation(params, seed=aggregation * 10 + rounds)


def test_broken_aggregation_row_mask_is_caught(monkeypatch):
    """Rows above the frame not masked: the previous frame's rows leak into the sums."""
    monkeypatch.setattr(hdl_aggregation, "row_bounds",
                        lambda y, above, height: (Const(1), Const(1)))
    with pytest.raises(AssertionError, match="sums differ"):
        check_aggregation(StereoParams(transform="census", block=3, disparities=6, rounds=2,
                                       width=9, height=6, line_buffer="costs"), seed=1)


def test_broken_aggregation_column_mask_is_caught(monkeypatch):
    """Columns beyond the frame's edges not masked: the sums wrap around to the next row."""
    monkeypatch.setattr(hdl_aggregation, "_tap_inside", lambda newest_x, k, a: Const(1))
    with pytest.raises(AssertionError, match="sums differ"):
        check_aggregation(StereoParams(transform="census", block=3, disparities=6, rounds=2,
                                       width=9, height=6, line_buffer="transforms"), seed=1)


@pytest.mark.parametrize("rounds", [2, 3])
def test_aggregation_cost_banks_match_golden(monkeypatch, rounds):
    """A cost line buffer of several banks (W*R = 18 or 27 words in banks of 8): every
    bank's words, the shorter last bank's too, come back from the bank they were written
    to."""
    monkeypatch.setattr(plan_structure, "COST_BANK", 8)
    params = StereoParams(transform="census", block=3, disparities=6, rounds=rounds,
                          width=9, height=6, line_buffer="costs")
    assert len(plan_structure.cost_banks(params)) == (3 if rounds == 2 else 4)
    check_aggregation(params, seed=rounds)


@pytest.mark.parametrize("bank, levels", [(2, 2), (1, 3)])
def test_aggregation_bank_choice_in_levels_matches_golden(monkeypatch, bank, levels):
    """More banks than one clock's choice (W*R = 18 words in banks of 2 or 1: 9 or 18
    banks): the choice in registered levels, the word a clock later per level."""
    monkeypatch.setattr(plan_structure, "COST_BANK", bank)
    params = StereoParams(transform="census", block=3, disparities=6, rounds=2, width=9,
                          height=6, line_buffer="costs")
    assert plan_structure.bank_choice_levels(params) == levels
    assert plan_timing.vertical_read(params) == plan_timing.VERTICAL_READ + levels - 1
    check_aggregation(params, seed=levels)


def test_broken_aggregation_bank_choice_level_is_caught(monkeypatch):
    """The second level's digit a clock early: words from the group of the next address."""
    monkeypatch.setattr(plan_structure, "COST_BANK", 2)
    choose_bank_early(monkeypatch, "_bank1")
    with pytest.raises(AssertionError, match="sums differ"):
        check_aggregation(StereoParams(transform="census", block=3, disparities=6, rounds=2,
                                       width=9, height=6, line_buffer="costs"), seed=1)


def test_broken_aggregation_bank_choice_is_caught(monkeypatch):
    """The bank chosen a clock early: words come from the bank of the next address."""
    monkeypatch.setattr(plan_structure, "COST_BANK", 8)
    choose_bank_early(monkeypatch, "_bank", clocks=0)
    with pytest.raises(AssertionError, match="sums differ"):
        check_aggregation(StereoParams(transform="census", block=3, disparities=6, rounds=2,
                                       width=9, height=6, line_buffer="costs"), seed=1)
