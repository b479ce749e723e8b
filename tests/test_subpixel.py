"""Sub-pixel disparity (``subpixel_bits`` F): the golden fit, the maps, the hardware.

The golden fit (golden/subpixel.py) against exact rational arithmetic on hand-made S
vectors (ties, both edges, negative offsets, both ends of the range |offset| <= 2^(F-1))
and random ones; the box pipeline's neighbours (gathered a disparity at a time) against
the fit of its whole S volume; the maps' whole levels against F = 0. The hardware:
:class:`~npstereo.hdl.subpixel.SubpixelFit` on random vectors, whole frames through the
core in Amaranth's simulator for F = 1, 4, 5 at R = 1 and R > 1, SGM and box, one cocotb
run on Icarus and one on Verilator, the L/R check waiting for left winners that the fit
makes late. ``test_broken_*`` put a wrong rule into the hardware or the model (rounding
down instead of half up, the neighbour across a round's edge from the wrong clock, the
check a clock too early) and show that the same comparison catches it.
"""

import random
from fractions import Fraction
from math import floor

import numpy as np
import pytest
from amaranth.sim import Simulator
from PIL import Image

from npstereo.gen.cli.main import main
from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.ip.generator import gapi_arguments
from npstereo.gen.ip.ports import stream_ports
from npstereo.golden import aggregation as golden_aggregation
from npstereo.golden import subpixel
from npstereo.golden.matching_cost import matching_costs
from npstereo.golden.pipeline import disparity_map
from npstereo.golden.transform import transform
from npstereo.hdl import plan_timing
from npstereo.hdl import subpixel as hdl_subpixel
from npstereo.hdl.plan_memories import memories, memory_bits
from npstereo.hdl.plan_structure import output_width
from npstereo.hdl.plan_timing import core_timing
from npstereo.hdl.subpixel import SubpixelFit
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import ParameterError, StereoParams
from npstereo.sim import cosim

from hdl_helpers import check_frames, frame_beats
from scenes import stereo_pair


def exact(before, centre, after, d, disparities, bits):
    """docs/semantics.md's definition in rationals: d 2^F + round_half_up((S(d-1) - S(d+1))
    2^F / (2 denom)), d 2^F at the edges."""
    if d in (0, disparities - 1):
        return d << bits
    denominator = before + after - 2 * centre
    return (d << bits) + floor(Fraction((before - after) << bits, 2 * denominator)
                               + Fraction(1, 2))


def rounded_down(before, centre, after, d, disparities, bits):
    """The broken fit: the offset rounded down instead of half up."""
    if d in (0, disparities - 1):
        return d << bits
    return (d << bits) + ((before - after) << bits) // (2 * (before + after - 2 * centre))


#: (S(d-1), S(d), S(d+1), d, D, F, expected value)
HAND = [
    (10, 5, 10, 3, 8, 4, 48),          # symmetric: no offset
    (6, 5, 5, 3, 8, 4, 56),            # a tie on the right: +1/2, the top of the range
    (6, 5, 5, 3, 8, 1, 7),             # the same with one bit
    (6, 5, 1000, 3, 8, 4, 40),         # far steeper on the right: -7.98 sixteenths -> -8
    (6, 5, 10**6, 3, 8, 5, 80),        # -2^(F-1) reached: 3 * 32 - 16
    (6, 5, 10**6, 3, 8, 1, 5),         # the same with one bit: 3 * 2 - 1
    (9, 5, 6, 2, 8, 2, 9),             # 2 + 3/10 -> 2.25 (0.3 * 4 = 1.2 -> 1)
    (7, 5, 8, 2, 8, 3, 15),            # a negative offset: -0.8 eighths -> -1
    (7, 5, 6, 2, 8, 2, 9),             # 2/3 quarter -> 1 (rounded down: 0)
    (5 + 3, 5, 5 + 1, 4, 8, 2, 17),    # 1/4 * 4 = 1 exactly -> offset 1
    (7, 5, 12, 0, 8, 4, 0),            # d = 0: no neighbour below, fraction 0
    (1, 5, 7, 7, 8, 4, 112),           # d = D-1: fraction 0 (S(d-1) not even a minimum)
    (8, 5, 7, 1, 3, 3, 8 + 1),         # D = 3, d = 1: 0.8 eighths -> 1 (rounded down: 0)
]


def test_hand_vectors_against_the_definition():
    for before, centre, after, d, disparities, bits, value in HAND:
        expected = exact(before, centre, after, d, disparities, bits)
        got = int(subpixel.fit(before, centre, after, d, disparities, bits))
        assert got == expected, (before, centre, after, d, bits)
        assert value == expected, (before, centre, after, d, bits, expected)
        offset = expected - (d << bits)
        assert abs(offset) <= (1 << bits >> 1)


def test_negative_half_rounds_up():
    """An offset of exactly -1/2 of a unit rounds up (towards +infinity), as OpenCV's
    round-half-up: (S(d-1) - S(d+1)) 2^F / (2 denom) = -1/2 -> 0."""
    # (a - b) 2^F / (2 (a + b)) = -1/2 with F = 1: a - b = -(a + b) / 2 -> b = 3a.
    assert int(subpixel.fit(6, 5, 8, 2, 8, 1)) == 4
    assert rounded_down(6, 5, 8, 2, 8, 1) == 3


def test_random_vectors_and_the_range():
    rng = np.random.default_rng(5)
    count, disparities = 4000, 16
    centre = rng.integers(0, 2000, count)
    before = centre + rng.integers(1, 3000, count)
    after = centre + rng.integers(0, 3000, count)
    after[::7] = centre[::7]                 # ties on the right
    after[::11] = centre[::11] + 100000      # steep right side
    d = rng.integers(0, disparities, count)
    for bits in (1, 4, 5):
        got = subpixel.fit(before, centre, after, d, disparities, bits)
        expected = [exact(*v, disparities, bits) for v in zip(before, centre, after, d)]
        assert got.tolist() == expected
        offsets = got - (d << bits)
        assert offsets.min() == -(1 << bits >> 1) and offsets.max() == 1 << bits >> 1


def test_broken_rounding_is_caught_by_the_hand_vectors():
    wrong = [v for v in HAND if rounded_down(*v[:6]) != exact(*v[:6])]
    assert len(wrong) >= 2


def test_not_a_minimum_is_refused():
    with pytest.raises(ValueError, match="minimum"):
        subpixel.fit(5, 5, 9, 3, 8, 4)       # a tie on the left: d - 1 would have won


def test_levels():
    assert subpixel.levels(np.array([-1, 0, 17], np.int16), 0).dtype == np.int16
    got = subpixel.levels(np.array([-1, 0, 17, 40]), 4)
    assert got.dtype == np.float32 and got.tolist() == [-1.0, 0.0, 1.0625, 2.5]


def _box_volume(left, right, params):
    """S(x, y, d) of the box pipeline as one (H, W, D) volume."""
    tl, tr = transform(left, params), transform(right, params)
    volume = [golden_aggregation.aggregate(matching_costs(tl, tr, d, params).astype(np.int64),
                                           params.aggregation)
              for d in range(params.disparities)]
    return np.stack(volume, axis=-1)


@pytest.mark.parametrize("aggregation", [3, "sgm"])
def test_maps_keep_their_levels(aggregation):
    """The fraction moves a kept disparity by at most half a level and keeps every
    invalid pixel invalid; the box pipeline's fit equals the fit of its whole S volume."""
    left, right = stereo_pair("layers", 24, 60, 4, 16)
    extra = {"p1": 3, "p2": 20} if aggregation == "sgm" else {}
    plain = StereoParams(transform="census", block=3, disparities=16, rounds=4,
                         aggregation=aggregation, **extra)
    whole = disparity_map(left, right, plain)
    for bits in (1, 4, 5):
        fine = disparity_map(left, right, plain.replace(subpixel_bits=bits))
        kept = whole.disparity >= 0
        assert np.array_equal(fine.disparity >= 0, kept)
        assert np.abs(fine.disparity[kept] - (whole.disparity[kept] << bits)).max() \
            <= 1 << bits >> 1
        if aggregation == 3:
            expected = subpixel.fit_volume(_box_volume(left, right, plain), whole.left, bits)
            assert np.array_equal(fine.disparity[kept], expected[kept])


def test_out_of_range_bits_are_refused():
    for bits in (-1, 6, 2.0, True):
        with pytest.raises(ParameterError, match="subpixel bits must be an integer 0 .. 5"):
            StereoParams(subpixel_bits=bits)


def test_repr_without_the_fraction_is_unchanged():
    """repr() keys the report cache: configurations without the fraction keep theirs."""
    assert "subpixel" not in repr(StereoParams())
    assert "subpixel_bits=4" in repr(StereoParams(subpixel_bits=4))


def test_output_word_grows_by_f_bits():
    base = StereoParams(disparities=64, width=200, height=4)
    assert output_width(base) == 8
    assert output_width(base.replace(subpixel_bits=1)) == 8
    assert output_width(base.replace(subpixel_bits=4)) == 16


# The hardware ------------------------------------------------------------------------------

def test_fit_unit_matches_golden():
    params = StereoParams(transform="census", block=3, disparities=8, aggregation=3,
                          subpixel_bits=5)
    dut = SubpixelFit(params)
    rng = random.Random(2)
    top = (1 << params.aggregated_cost_bits) - 1
    vectors = []
    for _ in range(150):
        centre = rng.randrange(top // 2)
        before = rng.randrange(centre + 1, top + 1)
        after = rng.choice([centre, top, rng.randrange(centre, top + 1)])
        vectors.append((rng.randrange(8), before, centre, after))
    got = []

    async def bench(ctx):
        for d, before, centre, after in vectors + [vectors[0]] * dut.latency:
            ctx.set(dut.disparity, d)
            ctx.set(dut.before, before)
            ctx.set(dut.centre, centre)
            ctx.set(dut.after, after)
            await ctx.tick()
            got.append(ctx.get(dut.value))
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    d, before, centre, after = np.array(vectors).T
    expected = subpixel.fit(before, centre, after, d, 8, 5)
    assert got[dut.latency - 1:dut.latency - 1 + len(vectors)] == expected.tolist()


def _core(aggregation, rounds, bits, disparities=8, lr=2):
    extra = {"p1": 3, "p2": 20, "p2_adapt": 2} if aggregation == "sgm" else {}
    return StereoParams(transform="census", block=3, disparities=disparities, rounds=rounds,
                        aggregation=aggregation, lr_threshold=lr, width=20, height=5,
                        subpixel_bits=bits, **extra)


CORES = [("sgm", 1, 4), ("sgm", 2, 5), ("sgm", 4, 1), ("sgm", 8, 4), (3, 1, 5), (3, 4, 4),
         (1, 2, 1)]


@pytest.mark.parametrize("aggregation,rounds,bits", CORES)
def test_core_matches_golden(aggregation, rounds, bits):
    params = _core(aggregation, rounds, bits)
    pair = stereo_pair("layers", params.height, params.width, rounds + bits, 8)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=0.7, ready_prob=0.7,
                 seed=bits)


def test_core_with_median_matches_golden():
    """The 3x3 median after the fraction: it takes the output values, F bits wider."""
    params = _core("sgm", 2, 4).replace(height=6, median=True)
    pair = stereo_pair("layers", params.height, params.width, 5, 8)
    check_frames(params, [pair], frame_beats(*pair), valid_prob=0.7, ready_prob=0.7, seed=1)


def test_broken_rounding_is_caught(monkeypatch):
    """The fit's numerator without its + (a + b): the quotient rounds down."""
    monkeypatch.setattr(hdl_subpixel, "numerator", lambda a, denominator, bits:
                        a << (bits + 1))
    params = _core("sgm", 2, 4)
    pair = stereo_pair("layers", params.height, params.width, 6, 8)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], frame_beats(*pair))


def test_broken_round_edge_is_caught(monkeypatch):
    """The neighbours across a round's edge from the leaves' own clock (the same round)
    instead of the previous and the next round."""
    monkeypatch.setattr(hdl_subpixel, "round_neighbours",
                        lambda m, current, sums: (current[-1], current[0]))
    params = _core("sgm", 4, 4)
    pair = stereo_pair("layers", params.height, params.width, 6, 8)
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], frame_beats(*pair))


def _late_winners():
    """D = 3, R = 1, F = 5: the left winners come after the right chain's exit, and
    without gaps every position follows the one before at once."""
    params = StereoParams(transform="census", block=3, disparities=3, rounds=1, aggregation=1,
                          lr_threshold=0, width=20, height=4, subpixel_bits=5)
    assert plan_timing.lr_exit_delay(params, core_timing(params).left
                                     - core_timing(params).sums) > plan_timing.LR_EXIT_REGISTERS
    return params, stereo_pair("independent", 4, 20, 3, 3)


def test_late_left_winners_are_waited_for():
    params, pair = _late_winners()
    check_frames(params, [pair], frame_beats(*pair))


def test_broken_lr_wait_is_caught(monkeypatch):
    """The final dR a clock too early: the check reads a left winner not yet written."""
    delay = plan_timing.lr_exit_delay
    monkeypatch.setattr(plan_timing, "lr_exit_delay",
                        lambda params, left: max(0, delay(params, left) - 1))
    params, pair = _late_winners()
    with pytest.raises(AssertionError, match="pixels differ"):
        check_frames(params, [pair], frame_beats(*pair))


# cocotb ------------------------------------------------------------------------------------

#: Small, so that the Verilator model builds fast; R = 2 takes d + 1 of d = 1 from the
#: next round.
COCOTB = StereoParams(transform="census", block=3, disparities=4, rounds=2, aggregation="sgm",
                      p1=3, p2=20, p2_adapt=2, lr_threshold=1, width=16, height=4,
                      subpixel_bits=4)
PLAN = [{"op": "frames", "frames": [0, 1], "idle": 0.3, "backpressure": 0.3}]


def _frames():
    return [stereo_pair("layers", COCOTB.height, COCOTB.width, 1, 4),
            stereo_pair("random", COCOTB.height, COCOTB.width, 2)]


@pytest.mark.parametrize("simulator", ["icarus", "verilator"])
def test_cocotb_stream(simulator):
    result = cosim.run_stream(simulator, COCOTB, _frames(), PLAN)
    assert result.frames and result.ok, result.message()


@pytest.mark.parametrize("simulator", ["icarus", "verilator"])
def test_broken_cocotb_rounding_is_caught(simulator, monkeypatch):
    monkeypatch.setattr(hdl_subpixel, "numerator", lambda a, denominator, bits:
                        a << (bits + 1))
    result = cosim.run_stream(simulator, COCOTB, _frames(), PLAN)
    assert not result.ok and result.mismatches > 0


# The commands ------------------------------------------------------------------------------

def _pair_files(tmp_path):
    left, right = stereo_pair("layers", 12, 40, 3, 8)
    paths = tmp_path / "left.png", tmp_path / "right.png"
    for path, image in zip(paths, (left, right)):
        Image.fromarray(image).save(path)
    return [str(path) for path in paths], (left, right)


@pytest.mark.parametrize("command", ["match", "eval", "verilog", "cosim", "report", "ip"])
@pytest.mark.parametrize("bits", ["6", "-1"])
def test_out_of_range_bits_are_one_line_errors(capsys, tmp_path, command, bits):
    (left, right), _ = _pair_files(tmp_path)
    small = ["--block", "3", "--disparities", "8", "--subpixel-bits", bits]
    size = ["--width", "16", "--height", "4"]
    argv = {"match": ["match", left, right, *small, "--out", str(tmp_path / "m.png")],
            "eval": ["eval", "--synthetic", *small],
            "verilog": ["verilog", *small, *size, "--out", str(tmp_path / "c.v")],
            "cosim": ["cosim", "--simulator", "amaranth", "--synthetic", *small, "--crop",
                      "16x4", "--out", str(tmp_path / "cosim")],
            "report": ["report", *small, *size],
            "ip": ["ip", *small, *size, "--out", str(tmp_path / "ip")]}[command]
    before = sorted(tmp_path.rglob("*"))
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert lines == [f"npstereo: error: subpixel bits must be an integer 0 .. 5, not {bits}"]
    assert "Traceback" not in captured.err + captured.out
    assert sorted(tmp_path.rglob("*")) == before


def test_match_raw_is_float_levels(capsys, tmp_path):
    (left, right), pair = _pair_files(tmp_path)
    base = ["match", left, right, "--block", "3", "--disparities", "8", "--aggregation", "sgm",
            "--p1", "3", "--p2", "20"]
    for bits in (0, 4):
        raw = tmp_path / f"raw{bits}.npy"
        assert main([*base, "--subpixel-bits", str(bits), "--out", str(tmp_path / "m.png"),
                     "--raw", str(raw)]) == 0
    whole, fine = np.load(tmp_path / "raw0.npy"), np.load(tmp_path / "raw4.npy")
    assert whole.dtype == np.int16 and fine.dtype == np.float32
    expected = disparity_map(*pair, StereoParams(transform="census", block=3, disparities=8,
                                                 aggregation="sgm", p1=3, p2=20,
                                                 subpixel_bits=4)).disparity
    assert np.array_equal(fine, np.where(expected >= 0, expected / 16, -1))
    assert np.array_equal(fine < 0, whole < 0) and np.abs(fine - whole).max() <= 0.5
    assert (fine != np.round(fine)).any()


def test_verilog_and_ip_widths(tmp_path):
    argv = ["--block", "3", "--disparities", "64", "--subpixel-bits", "4", "--width", "80",
            "--height", "4"]
    assert main(["verilog", *argv, "--out", str(tmp_path / "core.v")]) == 0
    text = (tmp_path / "core.v").read_text()
    assert "m_axis_tdata[15:0] = {valid, 0..., disparity[9:0]}" in text
    assert "output [15:0] m_axis_tdata" in text
    ports = {port.name: port.width for port in stream_ports(
        StereoParams(disparities=64, subpixel_bits=4, width=80, height=4), "m_axis")}
    assert ports["m_axis_tdata"] == 16


def test_memory_formula_matches_yosys():
    """The left winners' store keeps the value beside the level: ``npstereo report``'s
    architecture bits are what Yosys finds; without the value's bits they are not."""
    params = COCOTB
    result = synthesise(core_verilog(params), "cyclonev", TOP_NAME)
    assert result["status"] == "ok", result
    assert result["memory_bits"] == memory_bits(params)
    history = next(m for m in memories(params) if m.name == "left winners").depth
    assert result["memory_bits"] != memory_bits(params) - history * params.output_disparity_bits


def test_fusesoc_generator_takes_the_bits():
    argv = gapi_arguments({"vlnv": "a:b:c:0", "parameters": {"subpixel_bits": 4}})
    assert argv[-2:] == ["--subpixel-bits", "4"]
