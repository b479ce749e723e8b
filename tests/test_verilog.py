"""``npstereo verilog``: generated text, lint, and the command line's error handling.

``make test`` lints six configurations covering every transform, R = 1 and R = D, a
disparity range that is not a power of two and semi-global aggregation; the full sweep of 25 configurations (block
sizes 3..19, D in {16, 64, 100}, R in {1, 2, 4, 10}) runs in ``tests/bench_hdl.py``, which
prints one line per configuration (generation time, lint result).
"""

import re
import subprocess
import sys
import time

import pytest

from npstereo.gen.cli import main as cli
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import ParameterError, StereoParams
from npstereo.sim.lint import lint

from hdl_helpers import refused_quietly

QUICK = [
    StereoParams(transform="census", block=3, disparities=16, rounds=1, width=24, height=8),
    StereoParams(transform="rank", block=5, disparities=16, rounds=4, lr_threshold=None,
                 width=24, height=8),
    StereoParams(transform="ext-rank", block=3, disparities=16, rounds=2, aggregation=5,
                 width=24, height=8),
    StereoParams(transform="census", block=3, disparities=12, rounds=3, width=24, height=8),
    StereoParams(transform="ext-census", block=3, disparities=16, rounds=16,
                 aggregation=1, width=24, height=8),
    StereoParams(transform="census", block=5, disparities=24, rounds=8, aggregation="sgm",
                 width=28, height=8),
    StereoParams(transform="ext-census", block=5, disparities=16, rounds=4, width=24,
                 height=8, lut_inputs=6),
]


@pytest.mark.parametrize("params", QUICK, ids=lambda p: p.describe().replace(" ", "_"))
def test_generated_verilog_lints_clean(params, tmp_path):
    path = tmp_path / "core.v"
    path.write_text(core_verilog(params))
    ok, messages = lint(path)
    assert ok, messages[:2000]


def test_header_records_parameters():
    params = QUICK[1]
    text = core_verilog(params)
    head = text[:text.index("module")]
    for fragment in ("transform=rank", "block=5", "disparities=16", "rounds=4",
                     "aggregation=3", "lr_threshold=off", "width=24", "height=8",
                     "lut_inputs=4", "Amaranth"):
        assert fragment in head
    assert f"module {TOP_NAME}(" in text


def top_ports(text):
    """{name: (direction, width)} of the generated top module's port declarations."""
    body = text[text.index(f"module {TOP_NAME}("):text.index("endmodule")]
    return {name: (direction, int(high or 0) + 1) for direction, high, name in re.findall(
        r"^\s*(input|output) (?:\[(\d+):0\] )?(\w+);", body, re.M)}


def test_ports_are_the_documented_axi4_stream_ports():
    """docs/semantics.md, "Hardware interface": D = 16 gives a 4-bit disparity and an
    8-bit m_axis_tdata."""
    assert top_ports(core_verilog(QUICK[1])) == {
        "clk": ("input", 1), "rst": ("input", 1),
        "s_axis_tdata": ("input", 16), "s_axis_tvalid": ("input", 1),
        "s_axis_tready": ("output", 1), "s_axis_tuser": ("input", 1),
        "s_axis_tlast": ("input", 1),
        "m_axis_tdata": ("output", 8), "m_axis_tvalid": ("output", 1),
        "m_axis_tready": ("input", 1), "m_axis_tuser": ("output", 1),
        "m_axis_tlast": ("output", 1), "framing_error": ("output", 1)}


def test_lint_catches_broken_verilog(tmp_path):
    """The lint check itself can fail: a width mismatch in a module is reported."""
    path = tmp_path / "broken.v"
    path.write_text(f"module {TOP_NAME}(input clk, output [3:0] y);\n"
                    "  reg [3:0] r;\n  always @(posedge clk) r <= r + undeclared;\n"
                    "  assign y = r;\nendmodule\n")
    ok, _ = lint(path)
    assert not ok


def test_command_writes_file(tmp_path, capsys):
    out = tmp_path / "core.v"
    code = cli.main(["verilog", "--transform", "census", "--block", "3", "--disparities",
                     "8", "--rounds", "2", "--width", "16", "--height", "4",
                     "--out", str(out)])
    assert code == 0
    assert out.read_text().startswith("// npstereo_core")
    assert [p.name for p in tmp_path.iterdir()] == ["core.v"]  # no temporary left


@pytest.mark.parametrize("args,message", [
    (["--block", "4"], "block size"),
    (["--disparities", "10", "--rounds", "3"], "rounds must divide"),
    (["--disparities", "16", "--width", "16"], "image width"),
    (["--height", "0"], "image height"),
    (["--aggregation", "2"], "aggregation"),
    (["--lr-threshold", "-1"], "lr threshold"),
    (["--transform", "sad"], "invalid choice"),
    (["--lut-inputs", "5"], "--lut-inputs: invalid choice: 5"),
    # Beyond what the hardware is generated for: refused at once, not elaborated.
    (["--width", "100000"], "image width must be <= 8192 for the hardware, not 100000"),
    (["--block", "99"], "block size must be <= 31 for the hardware, not 99"),
    (["--disparities", "1000", "--width", "1200"],
     "disparities must be <= 256 for the hardware, not 1000"),
])
def test_bad_parameters_exit_2_one_line(args, message, tmp_path):
    out = tmp_path / "core.v"
    base = {"--transform": "census", "--block": "3", "--disparities": "8",
            "--width": "16", "--height": "4"}
    for key, value in zip(args[::2], args[1::2]):
        base[key] = value
    argv = [sys.executable, "-m", "npstereo.gen.cli", "verilog", "--out", str(out)]
    for key, value in base.items():
        argv += [key, value]
    started = time.perf_counter()
    result = subprocess.run(argv, capture_output=True, text=True, timeout=120)
    # A whole process (interpreter, numpy, Amaranth) but no elaboration: seconds at most.
    assert time.perf_counter() - started < 30
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and message in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_missing_size_is_rejected(tmp_path):
    result = subprocess.run([sys.executable, "-m", "npstereo.gen.cli", "verilog", "--out",
                             str(tmp_path / "c.v")], capture_output=True, text=True)
    assert result.returncode == 2 and "--width" in result.stderr
    # Refused before a core exists: nothing is left for Amaranth to report as unused.
    refused_quietly(lambda: core_verilog(StereoParams(transform="census", block=3,
                                                      disparities=8)),
                    ParameterError, "--width and --height")


def test_limits_are_named_in_the_help(capsys):
    with pytest.raises(SystemExit):
        cli.main(["verilog", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "at most 8192" in text and "at most 31" in text and "at most 256" in text



def test_out_is_a_directory(tmp_path, capsys):
    code = cli.main(["verilog", "--block", "3", "--disparities", "8", "--width", "16",
                     "--height", "4", "--out", str(tmp_path)])
    assert code == 2
    assert "is a directory" in capsys.readouterr().err
