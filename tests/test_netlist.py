"""Gate-level co-simulation: the core as synthesised for the ECP5 and the Cyclone V.

Each core goes through the project's flow (:mod:`npstereo.gen.flow.netlist`: synth_ecp5
with the DP16KD output registers packed, or synth_intel_alm), is written back as Verilog
by Yosys and simulated under Icarus with the families' cell models (Yosys's, and the
project's DP16KD). Census on the ECP5 runs under the stress of the RTL co-simulation
(cocotbext-axi: random idle cycles and backpressure, a reset in the middle of a frame,
then a frame that must be exact); the other configurations run one frame through the
Verilog harness with random idle cycles and backpressure (no Python per clock: the
suite's budget). Every output pixel is compared with the golden model. Frames are 16 x 6
(a gate-level core runs a few hundred clocks per second under Icarus); netlists are cached
in ``build/netlist`` and simulation models in ``build/cosim``.

Broken variant: the output-register pass dropping the registers it packs (the DP16KD
left without ``OUTREG`` while its flip-flops are removed) must fail the comparison.
"""

import pytest

from npstereo.gen.cli.main import main
from npstereo.gen.flow import bram_output_register as outreg
from npstereo.gen.flow.block_rams import core_block_rams
from npstereo.gen.flow.netlist import mapped_netlist, netlist_verilog
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import StereoParams
from npstereo.sim import cosim

from scenes import stereo_pair

WIDTH, HEIGHT = 16, 6

#: Traffic, a reset in the middle of a frame, then a frame that must be exact.
PLAN = [
    {"op": "frames", "frames": [0, 1], "idle": 0.3, "backpressure": 0.3},
    {"op": "abort", "frame": 0, "lines": 3},
    {"op": "frames", "frames": [1], "idle": 0.2, "backpressure": 0.2},
]


def config(transform, **changes):
    return StereoParams(transform=transform, block=3, disparities=4, rounds=1,
                        lr_threshold=1).replace(**changes).with_size(WIDTH, HEIGHT)


#: family, configuration, and whether it runs the whole plan (cocotbext-axi) or one frame
#: through the Verilog harness with idle cycles and backpressure (no Python per clock).
CONFIGS = {
    "ecp5-census": ("ecp5", config("census"), True),
    "ecp5-rank": ("ecp5", config("rank"), False),
    "ecp5-ext-census": ("ecp5", config("ext-census"), False),
    "ecp5-ext-rank": ("ecp5", config("ext-rank"), False),
    "ecp5-census-sgm": ("ecp5", config("census", rounds=2, aggregation="sgm", p1=3, p2=20,
                                       p2_adapt=2), False),
    "cyclonev-census": ("cyclonev", config("census"), False),
}


def frames(params):
    return [stereo_pair("layers", HEIGHT, WIDTH, 0, params.disparities),
            stereo_pair("random", HEIGHT, WIDTH, 0, params.disparities)]


def run(params, netlist_text, libraries, plan):
    """The netlist through :data:`PLAN`, or one frame through the harness."""
    if plan:
        return cosim.run_stream("icarus", params, frames(params), PLAN,
                                core_text=netlist_text, libraries=libraries)
    left, right = frames(params)[0]
    return cosim.run_frame("icarus", params, left, right, core_text=netlist_text,
                           idle=0.3, backpressure=0.3, optimize=False, libraries=libraries)


@pytest.mark.parametrize("name", list(CONFIGS))
def test_netlist_bit_exact(name):
    family, params, plan = CONFIGS[name]
    netlist = mapped_netlist(core_verilog(params), family, TOP_NAME)
    result = run(params, netlist.verilog, netlist.libraries, plan)
    # Two frames under traffic and the one after the reset, or the harness's frame.
    assert len(result.frames) == (3 if plan else 1), result.frames
    assert result.ok, result.message()
    if family == "ecp5":
        # The pass under test did something: read ports were given their output register.
        assert netlist.figures["outreg_packed"] >= 1, netlist.figures
        # The DP16KD counted before synthesis (issue 27's refusal) are Yosys's: the L/R
        # check's two in block RAM, the small line buffers in LUT RAM.
        assert netlist.figures["block_rams"] == core_block_rams(params) == 2


def test_register_dropping_pass_fails(tmp_path, monkeypatch):
    """Broken variant: the pass removes the flip-flops behind a read port and connects the
    block RAM's data straight to their loads, without setting ``REGMODE = "OUTREG"``."""
    _, params, _ = CONFIGS["ecp5-census"]
    netlist = mapped_netlist(core_verilog(params), "ecp5", TOP_NAME)
    real = outreg.read_ports
    monkeypatch.setattr(outreg, "read_ports", lambda cell: [
        (name, side, (), outputs) for name, side, _, outputs in real(cell)])
    broken = tmp_path / "broken.json"
    report = outreg.pack_outreg_file(netlist.directory / "synth" / "synth.json", broken)
    assert report["packed"] == netlist.figures["outreg_packed"] >= 1
    result = run(params, netlist_verilog(broken), netlist.libraries, plan=False)
    assert not result.ok and result.mismatches > 0


# npstereo cosim --netlist --------------------------------------------------------------

#: The census configuration of :data:`CONFIGS` (its netlist is cached once built).
SMALL = ["--disparities", "4", "--block", "3", "--rounds", "1", "--lr-threshold", "1",
         "--crop", f"{WIDTH}x{HEIGHT}"]


def test_cli_netlist_bit_exact(tmp_path, capsys, pair_files):
    scene = pair_files[2]
    assert main(["cosim", "--simulator", "icarus", "--netlist", "ecp5", "--dataset",
                 str(scene), *SMALL, "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert f"pixels compared:  {WIDTH * HEIGHT}" in out
    assert "mismatches:       0 (bit-exact)" in out
    assert "netlist:          ecp5: " in out and "DP16KD output registers packed" in out
    assert (tmp_path / "out" / "hardware.png").stat().st_size > 0


@pytest.mark.parametrize("args, message", [
    (["--simulator", "icarus", "--netlist", "xilinx"],
     "argument --netlist: invalid choice: 'xilinx' (choose from 'ecp5', 'cyclonev')"),
    (["--simulator", "amaranth", "--netlist", "ecp5"],
     "--netlist needs --simulator verilator or icarus"),
])
def test_cli_netlist_bad_input(tmp_path, capsys, args, message):
    assert main(["cosim", *args, "--synthetic", *SMALL, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()
