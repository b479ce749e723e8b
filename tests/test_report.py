"""``npstereo report``: the Yosys/nextpnr flow, its parsed numbers and its command line.

The memory-bit count is checked on a design of our own whose memory size is known exactly
(a line buffer in an Amaranth ``Memory``) and on a small core against the architecture's
formula; a design with a different memory size must give a different count.
"""

import json
import re

import pytest
from amaranth.back import verilog
from amaranth.hdl import Cat, Module, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from npstereo.gen import cmd_report
from npstereo.gen.cli import main
from npstereo.gen.synth import synthesise
from npstereo.golden.params import StereoParams

#: M10K capacity in bits (Cyclone V block RAM).
M10K_BITS = 10240


class LineBuffer(wiring.Component):
    """Two lines of 8-bit pixels in one memory word per column, as the input stage does."""

    def __init__(self, width, lines):
        self.width, self.lines = width, lines
        super().__init__({"pixel": In(8), "column": In(range(width)),
                          "oldest": Out(8)})

    def elaborate(self, platform):
        m = Module()
        m.submodules.memory = memory = Memory(shape=unsigned(8 * self.lines),
                                              depth=self.width, init=[])
        read, write = memory.read_port(), memory.write_port()
        m.d.comb += [read.addr.eq(self.column), write.addr.eq(self.column), write.en.eq(1),
                     write.data.eq(Cat(self.pixel, read.data[:8 * (self.lines - 1)])),
                     self.oldest.eq(read.data[-8:])]
        return m


def line_buffer_verilog(width, lines):
    return verilog.convert(LineBuffer(width, lines), name="line_buffer", emit_src=False)


@pytest.mark.parametrize("target", ["cyclonev", "ecp5"])
def test_line_buffer_memory_bits_exact(target):
    result = synthesise(line_buffer_verilog(640, 3), target, "line_buffer")
    assert result["status"] == "ok", result
    assert result["memory_bits"] == 640 * 3 * 8
    assert result["memories"] == 1
    assert result["ffram_bits"] == 0          # in block RAM, not flip-flops
    assert result["block_rams"] >= 1
    if target == "cyclonev":
        assert result["block_rams"] * M10K_BITS >= result["memory_bits"]


def test_memory_bits_follow_the_design():
    """Broken variant: a buffer one line shorter must not report the same number."""
    result = synthesise(line_buffer_verilog(640, 2), "cyclonev", "line_buffer")
    assert result["status"] == "ok", result
    assert result["memory_bits"] == 640 * 2 * 8 != 640 * 3 * 8


def test_nextpnr_reports_clock():
    result = synthesise(line_buffer_verilog(64, 2), "ecp5", "line_buffer", pnr=True, freq=50)
    assert result["status"] == "ok", result
    assert 10 < result["fmax_mhz"] < 1000
    assert " -> " in result["critical_path"]


def test_failing_synthesis_is_reported_not_raised():
    result = synthesise("module broken(input a; endmodule\n", "cyclonev", "broken")
    assert result["status"] == "failed"
    assert "ERROR" in result["message"]


def test_timeout_is_reported():
    # A whole (small) core: Yosys needs seconds for it, far beyond the 0.2 s allowed.
    from npstereo.gen.verilog import core_verilog
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    result = synthesise(core_verilog(params), "cyclonev", "npstereo_core", timeout=0.2)
    assert result["status"] == "timeout", result
    assert result["message"] == "killed after 0.2 s"


def test_small_core_memory_matches_architecture(tmp_path):
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    # Two image line buffers of B-1 = 2 lines x 8 bits, and A-1 = 2 lines of D = 8 census
    # costs of 4 bits (k = 8 neighbours) per column.
    assert cmd_report.expected_memory_bits(params) == 2 * 32 * 2 * 8 + 32 * 2 * 8 * 4
    first = cmd_report.evaluate(params, ["cyclonev"], cache=tmp_path)
    result = first["results"]["cyclonev"]
    assert result["status"] == "ok", result
    assert result["memory_bits"] == cmd_report.expected_memory_bits(params)
    assert result["message"] == ""
    assert result["logic"] > 0 and result["registers"] > 0 and result["ffram_bits"] == 0
    again = cmd_report.evaluate(params, ["cyclonev"], cache=tmp_path)
    assert again["results"]["cyclonev"]["cached"] is True
    assert again["results"]["cyclonev"]["logic"] == result["logic"]
    assert first["cycles_per_frame"] == (32 * 8 + _latency(params)) * 2


def _latency(params):
    """The latency the generated Verilog's header states (in positions)."""
    from npstereo.gen.verilog import core_verilog
    header = core_verilog(params).split("\n", 8)[:8]
    return int(next(re.search(r"latency (\d+) pixels", line).group(1) for line in header
                    if "latency" in line))


def test_cache_key_depends_on_configuration_and_verilog():
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    key = cmd_report._cache_key(params, "cyclonev", False, 150.0, "v1")
    assert key == cmd_report._cache_key(params, "cyclonev", False, 150.0, "v1")
    assert key != cmd_report._cache_key(params.replace(block=5), "cyclonev", False, 150.0, "v1")
    assert key != cmd_report._cache_key(params, "ecp5", False, 150.0, "v1")
    assert key != cmd_report._cache_key(params, "cyclonev", False, 150.0, "v2")


def test_verilog_digest_ignores_the_header_only(tmp_path):
    from npstereo.gen.verilog import core_verilog
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    text = core_verilog(params)
    digest = cmd_report.configuration_digest(params, tmp_path)
    assert digest == cmd_report.verilog_digest(text)
    assert digest == cmd_report.verilog_digest("// another version\n" + text)
    assert digest != cmd_report.verilog_digest(text.replace("npstereo_core", "other_core"))
    assert cmd_report.configuration_digest(params, tmp_path) == digest      # memoised
    assert cmd_report.configuration_digest(params.replace(block=5), tmp_path) != digest


def test_failed_cell_keeps_the_sweep_going(monkeypatch):
    def explode(*args, **kwargs):
        raise RuntimeError("elaboration blew up")
    monkeypatch.setattr(cmd_report, "evaluate", explode)
    params = cmd_report.paper_configurations()[0]
    report = cmd_report._job(params, ("cyclonev",), False, 150.0, None, None)
    assert report["results"]["cyclonev"]["status"] == "failed"
    assert "blew up" in report["results"]["cyclonev"]["message"]
    text = cmd_report.sweep_markdown([report])
    assert "| rank | 7x7 | failed |" in text and "10,174" in text


def test_paper_sweep_configurations():
    configurations = cmd_report.paper_configurations()
    assert len(configurations) == 28
    assert {(p.width, p.height, p.disparities, p.rounds) for p in configurations} == {
        (450, 375, 100, 10)}


@pytest.mark.parametrize("argv, message", [
    (["--transform", "census", "--block", "3"], "--width and --height are required"),
    (["--width", "32", "--height", "8", "--block", "4"], "block size"),
    (["--width", "32", "--height", "8", "--jobs", "0"], "--jobs"),
    (["--width", "32", "--height", "8", "--pnr"], "--pnr"),
    (["--width", "32", "--height", "8", "--target", "vivado"], "invalid choice"),
    (["--paper", "--width", "32"], "--paper"),
    (["--width", "32", "--height", "8", "--timeout", "-1"], "--timeout"),
])
def test_bad_input_exits_2_with_one_line(argv, message, capsys, tmp_path):
    json_path = tmp_path / "out.json"
    assert main(["report", *argv, "--json", str(json_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not json_path.exists()


def test_json_to_folder_is_refused(capsys, tmp_path):
    assert main(["report", "--width", "32", "--height", "8", "--json", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err


def test_cli_single_configuration(tmp_path, capsys):
    json_path = tmp_path / "r.json"
    argv = ["report", "--transform", "rank", "--block", "3", "--disparities", "4",
            "--rounds", "2", "--aggregation", "1", "--no-lr-check", "--width", "16",
            "--height", "4", "--cache", str(tmp_path / "cache"), "--json", str(json_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "ALUT" in out and "cycles per frame" in out
    document = json.loads(json_path.read_text())
    result = document["reports"][0]["results"]["cyclonev"]
    # Only the two image line buffers (A = 1: no cost lines): 2 x 16 columns x 2 lines x 8.
    assert result["memory_bits"] == 2 * 16 * 2 * 8


def test_sweep_outputs_ratios_and_plots(tmp_path):
    ok = {"target": "cyclonev", "status": "ok", "logic": 5087, "registers": 100,
          "block_rams": 3, "memory_bits": 557056 * 2, "fmax_mhz": None, "seconds": 1.0}
    report = {"params": {"transform": "rank", "block": 7}, "results": {"cyclonev": ok}}
    text = cmd_report.sweep_markdown([report])
    # 5087 / 10174 paper logic elements, 2 x 557056 / 557056 paper memory bits.
    assert "| rank | 7x7 | 5,087 | 10,174 | 0.50 |" in text and "| 2.00 |" in text
    from PIL import Image
    written = cmd_report.sweep_plots([report], tmp_path)
    assert [p.name for p in written] == ["logic.png", "memory.png"]
    assert all(Image.open(p).size[0] > 100 for p in written)


def test_sweep_document_seeds_the_cache(tmp_path):
    """A committed sweep resumes on a fresh machine, but never for another HDL version."""
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    result = {"target": "cyclonev", "status": "ok", "logic": 123, "cached": False}
    document = {"tools": cmd_report.tool_versions(), "hdl_sources": "old sources",
                "reports": [{"params": cmd_report._params_dict(params),
                             "verilog_sha": cmd_report.configuration_digest(params),
                             "results": {"cyclonev": result,
                                         "ecp5": {"target": "ecp5", "status": "timeout"}}}]}
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps(document))
    assert cmd_report.seed_cache(sweep, tmp_path / "cache") == 1   # the timeout is not taken
    stored = cmd_report.evaluate(params, ["cyclonev"], cache=tmp_path / "cache")
    assert stored["results"]["cyclonev"]["cached"] is True
    assert stored["results"]["cyclonev"]["logic"] == 123
    assert cmd_report.seed_cache(sweep, tmp_path / "cache") == 0   # already there

    document["reports"][0]["verilog_sha"] = "0" * 24                 # another design
    sweep.write_text(json.dumps(document))
    assert cmd_report.seed_cache(sweep, tmp_path / "other") == 0
    del document["reports"][0]["verilog_sha"]                       # an older document:
    sweep.write_text(json.dumps(document))                          # only from these sources
    assert cmd_report.seed_cache(sweep, tmp_path / "other") == 0
    document["hdl_sources"] = cmd_report._source_hash()
    sweep.write_text(json.dumps(document))
    assert cmd_report.seed_cache(sweep, tmp_path / "other") == 1

