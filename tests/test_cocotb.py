"""Co-simulation of the generated Verilog under cocotb on Verilator and Icarus Verilog.

Every output pixel is compared with the golden model inside the cocotb test (see
``sim/cocotb_tests.py``); a failure names the first differing pixel and the count.
Builds are cached per configuration under ``build/cosim/<hash>/`` and shared by the tests
of one configuration, so each Verilator model is compiled once (without C++ optimisation:
the frames are tiny). Frames are 40 x 12; a core generated with a broken transform
comparison must be reported as mismatching on both simulators, and a Verilog top level that
swaps the pixels of ``s_axis_tdata`` on Icarus.
"""

import numpy as np
import pytest

from npstereo.gen.cli.main import main
from npstereo.hdl import transform as hdl_transform
from npstereo.hdl import trees, verilog
from npstereo.params import StereoParams
from npstereo.sim import cosim
from npstereo.sim.frames import compare_frame

from scenes import stereo_pair

WIDTH, HEIGHT = 40, 12


def frames(params, count=2, seed=0):
    """Layered scenes with tie areas, then a random pair (shifted texture with noise)."""
    pairs = [stereo_pair("layers", HEIGHT, WIDTH, seed + index, params.disparities)
             for index in range(count - 1)]
    return pairs + [stereo_pair("random", HEIGHT, WIDTH, seed)]


def config(transform, block, disparities, rounds, lr):
    return StereoParams(transform=transform, block=block, disparities=disparities,
                        rounds=rounds, lr_threshold=lr).with_size(WIDTH, HEIGHT)


def assert_bit_exact(result):
    assert result.frames, "the run compared no frame"
    assert result.ok, result.message()


#: Back to back with 30 % idle cycles and 30 % backpressure, reset, a line 3 pixels short,
#: a reset in the middle of a frame, a line 4 pixels long; every good frame bit-exact.
FULL_PLAN = [
    {"op": "frames", "frames": [0, 1], "idle": 0.3, "backpressure": 0.3},
    {"op": "reset"},
    {"op": "misframed", "frame": 0, "line": 3, "delta": -3, "good": 1},
    {"op": "abort", "frame": 0, "lines": 5},
    {"op": "frames", "frames": [1, 0]},
    {"op": "misframed", "frame": 1, "line": 7, "delta": 4, "good": 0, "idle": 0.2},
]

#: Traffic only: two frames back to back under random idle cycles and backpressure.
TRAFFIC_PLAN = [{"op": "frames", "frames": [0, 1], "idle": 0.3, "backpressure": 0.3}]

CONFIGS = {
    "census-5-D8-R2-lr1": (config("census", 5, 8, 2, 1), FULL_PLAN),
    "ext-rank-3-D4-R1-nolr": (config("ext-rank", 3, 4, 1, None), TRAFFIC_PLAN),
    "rank-7-D8-R4-lr0": (config("rank", 7, 8, 4, 0), TRAFFIC_PLAN),
    "ext-census-3-D6-R3-lr2": (config("ext-census", 3, 6, 3, 2), TRAFFIC_PLAN),
    # Sums of absolute differences arranged for 6-input LUTs (compressors as gates).
    "ext-census-5-D8-R2-lr1-lut6": (config("ext-census", 5, 8, 2, 1).replace(lut_inputs=6),
                                    TRAFFIC_PLAN),
    "census-3-D8-R8-sgm": (config("census", 3, 8, 8, 1).replace(
        aggregation="sgm", p1=3, p2=20, p2_adapt=2), FULL_PLAN),
}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_verilator_stream(name):
    params, plan = CONFIGS[name]
    assert_bit_exact(cosim.run_stream("verilator", params, frames(params), plan))


#: Run with traffic only on Icarus, their full plan on Verilator: the box core's full plan
#: was the suite's longest test under Icarus (94.7 s beside a placement, 24.4 s with traffic
#: only). The control scenarios still meet four-state simulation (X until reset) in the SGM
#: core's.
ICARUS_TRAFFIC_ONLY = {"census-5-D8-R2-lr1"}


@pytest.mark.parametrize("name", list(CONFIGS))
def test_icarus_stream(name):
    params, plan = CONFIGS[name]
    if name in ICARUS_TRAFFIC_ONLY:
        plan = TRAFFIC_PLAN
    assert_bit_exact(cosim.run_stream("icarus", params, frames(params), plan))


@pytest.mark.parametrize("simulator", ["verilator", "icarus"])
def test_harness_frame(simulator):
    """The fast path (the self-clocking Verilog harness) with idle cycles and backpressure."""
    params = config("census", 5, 8, 2, 1)
    left, right = frames(params, 1)[0]
    result = cosim.run_frame(simulator, params, left, right, idle=0.3, backpressure=0.3,
                             optimize=False)
    assert_bit_exact(result)
    assert result.cycles >= WIDTH * HEIGHT * params.rounds
    assert result.disparity.shape == (HEIGHT, WIDTH)


@pytest.mark.parametrize("simulator", ["verilator", "icarus"])
def test_broken_core_fails(simulator, monkeypatch):
    """A core generated with ``>=`` instead of ``>`` in the transform must be caught."""
    monkeypatch.setattr(hdl_transform, "xi", lambda centre, neighbour: centre >= neighbour)
    params, _ = CONFIGS["census-5-D8-R2-lr1"]
    result = cosim.run_stream(simulator, params, frames(params), TRAFFIC_PLAN)
    assert not result.ok
    assert result.mismatches > 0
    label, comparison = next((label, c) for label, c in result.frames if not c.ok)
    x, y, expected, got = comparison.first
    assert expected != got
    assert f"first at x={x} y={y}" in result.message()


def test_broken_axi_mapping_fails(monkeypatch):
    """A Verilog top level that takes the left pixel from the upper byte of
    ``s_axis_tdata`` must be caught: the AXI4-Stream ports are checked, not only the core."""
    original = verilog.AxiTop.elaborate

    def swapped(self, platform):
        m = original(self, platform)
        pixels = self.core.sink.payload.data
        m.d.comb += [pixels.left.eq(self.s_axis_tdata[8:]),
                     pixels.right.eq(self.s_axis_tdata[:8])]
        return m

    monkeypatch.setattr(verilog.AxiTop, "elaborate", swapped)
    params, _ = CONFIGS["ext-rank-3-D4-R1-nolr"]
    result = cosim.run_stream("icarus", params, frames(params), TRAFFIC_PLAN)
    assert not result.ok and result.mismatches > 0


def test_compare_reports_first_pixel_and_count():
    params = config("census", 3, 4, 1, None)
    expected = np.zeros(WIDTH * HEIGHT, dtype=np.int64)
    got = expected.copy()
    got[WIDTH * 2 + 5] = 0x83
    got[WIDTH * 4] = 0x81
    tuser = np.arange(got.size) == 0
    tlast = np.arange(got.size) % WIDTH == WIDTH - 1
    comparison = compare_frame(expected, got, tuser, tlast, params)
    assert (comparison.mismatches, comparison.first) == (2, (5, 2, -1, 3))
    short = compare_frame(expected, got[:-WIDTH], tuser, tlast, params)
    assert short.mismatches == 2 + WIDTH and not short.ok
    assert "received 440 output pixels, expected 480" in short.message()
    tlast[WIDTH - 1] = False
    assert "m_axis_tlast wrong on 1 beats, first at x=39 y=0" in \
        compare_frame(expected, expected, tuser, tlast, params).message()


# npstereo cosim --------------------------------------------------------------------------

SMALL = ["--synthetic", "--disparities", "8", "--block", "5", "--rounds", "2",
         "--crop", "40x12"]


def test_cli_amaranth_bit_exact(tmp_path, capsys):
    assert main(["cosim", "--simulator", "amaranth", *SMALL, "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "pixels compared:  480" in out and "mismatches:       0 (bit-exact)" in out
    assert "frames/s at 100 MHz" in out
    assert (tmp_path / "hardware.png").stat().st_size > 0
    assert (tmp_path / "golden.png").stat().st_size > 0


def test_cli_mismatch_exits_1(tmp_path, capsys, monkeypatch):
    # Adders that drop their carry: popcounts and aggregated costs wrap around.
    monkeypatch.setattr(trees, "_add", lambda lower, upper: (
        (lower[0] + upper[0])[:max(len(lower[0]), len(upper[0]))],))
    assert main(["cosim", "--simulator", "amaranth", *SMALL, "--out", str(tmp_path)]) == 1
    assert "pixels differ; first at x=" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["--crop", "40by12"], "--crop must be WIDTHxHEIGHT"),
    (["--crop", "4000x12"], "must lie within"),
    (["--crop", "8x8"], "image width must be an integer >"),
    (["--rounds", "3"], "rounds must divide disparities"),
    (["--clock-mhz", "0"], "--clock-mhz must be > 0"),
    (["--block", "4"], "block size must be an odd integer"),
    (["--block", "33"], "block size must be <= 31 for the hardware"),
])
def test_cli_bad_input(tmp_path, capsys, args, message):
    base = ["cosim", "--simulator", "amaranth", "--synthetic", "--disparities", "8",
            "--crop", "40x12", "--out", str(tmp_path / "out")]
    assert main(base + args) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_cli_bad_dataset_and_out(tmp_path, capsys):
    out = tmp_path / "file"
    out.write_text("x")
    assert main(["cosim", "--simulator", "icarus", "--synthetic", "--out", str(out)]) == 2
    assert "is not a directory" in capsys.readouterr().err
    assert main(["cosim", "--simulator", "icarus", "--dataset", str(tmp_path / "none"),
                 "--out", str(tmp_path / "o")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["cosim", "--simulator", "modelsim", "--synthetic", "--out", "o"]) == 2
    assert not (tmp_path / "o").exists()
