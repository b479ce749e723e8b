"""``npstereo prove``: the stream properties proved with SymbiYosys on small cores.

Every transform and SGM gets the unbounded proofs (output held under backpressure, reset
from any state); one core runs the bounded groups. Two deliberately broken cores, built here by
wrapping the generated one (the product code has no broken mode), must fail with a
counterexample trace written: tdata changing under backpressure, and the last position of
every line dropped. Bad input is one line, exit code 2.
"""

import re

import pytest

from npstereo.gen.cli.main import main
from npstereo.gen.flow.formal import PROPERTIES, default_depth, first_word_clock, prove
from npstereo.hdl import median as hdl_median
from npstereo.hdl import subpixel as hdl_subpixel
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import StereoParams

#: The smallest cores: a 3x2 frame, D = 2, one round, no aggregation window.
TINY = {"block": 3, "disparities": 2, "rounds": 1, "aggregation": 1, "lr_threshold": None,
        "width": 3, "height": 2}


def _argv(transform, out, *extra):
    return ["prove", "--transform", transform, "--block", "3", "--disparities", "2",
            "--rounds", "1", "--width", "3", "--height", "2", "--out", str(out), *extra]


@pytest.mark.parametrize("transform,aggregation", [
    ("rank", "1"), ("census", "1"), ("ext-rank", "1"), ("ext-census", "1"), ("census", "sgm"),
    ("census", "sgm --fifth-path")])
def test_unbounded_proofs_per_transform(transform, aggregation, tmp_path, capsys):
    # The bounded pre-pass only needs to run: its failures are test_broken_*'s.
    aggregation, *options = aggregation.split()
    extra = ["--aggregation", aggregation, "--no-lr-check", "--checks", "induction",
             "--depth", "4", *options]
    if aggregation == "sgm":
        # The narrowest SGM frame is 9 at D = 2, R = 2 (plan.sgm_min_width).
        extra += ["--p1", "2", "--p2", "5", "--rounds", "2", "--width", "9"]
    assert main(_argv(transform, tmp_path, *extra)) == 0
    out = capsys.readouterr().out
    assert re.search(r"^hold +proven \(unbounded, PDR\)", out, re.M), out
    assert re.search(r"^reset +proven \(unbounded, PDR\)", out, re.M), out
    assert (tmp_path / "induction.sby").exists() and (tmp_path / "induction").is_dir()


def test_bounded_groups_on_census(tmp_path, capsys):
    """The bounded properties on one core with the L/R check on, to a depth short enough
    for a loaded machine (the unbounded group is above; deeper runs are measured in
    docs/verification.md)."""
    argv = ["prove", "--transform", "census", "--block", "3", "--disparities", "2",
            "--rounds", "2", "--aggregation", "1", "--width", "3", "--height", "2",
            "--depth", "16", "--timeout", "120", "--checks", "free", "framed", "misframed",
            "--out", str(tmp_path)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    bounded = [p for p in PROPERTIES if p.group != "induction"]
    for prop in bounded:
        line = next(line for line in out.splitlines() if line.startswith(prop.name + " "))
        assert "bounded to depth 16" in line, line
    for group in ("free", "framed", "misframed"):
        assert (tmp_path / f"{group}.sby").exists()
    verdicts = (tmp_path / "verdict.tsv").read_text().splitlines()
    assert [v.split("\t")[0] for v in verdicts] == [p.name for p in bounded]


def test_unbounded_proofs_with_median_and_subpixel(tmp_path, capsys):
    """One core with both (the test budget): the median, and D = 5 with F = 5, whose word
    grows to 16 bits (3 + 5 bits and the valid flag)."""
    argv = _argv("census", tmp_path, "--aggregation", "1", "--no-lr-check", "--checks",
                 "induction", "--depth", "4", "--median", "--disparities", "5", "--width",
                 "6", "--subpixel-bits", "5")
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert re.search(r"^hold +proven \(unbounded, PDR\)", out, re.M), out
    assert re.search(r"^reset +proven \(unbounded, PDR\)", out, re.M), out
    assert " median 6x2 F=5" in out
    assert "output [15:0] m_axis_tdata" in (tmp_path / "core.v").read_text()


#: The median's smallest core; its first word leaves at clock 41 at the earliest.
MEDIAN = {**TINY, "median": True}


@pytest.mark.parametrize("broken", [False, True])
def test_median_guard_against_stale_rows(broken, tmp_path, monkeypatch):
    """The free group past the median core's first word (depth 42) holds; with the
    median's priming guard removed (a window of rows written before the reset counts as
    words), the stale row's word comes out after a reset and ``markers`` fails."""
    params = StereoParams(transform="census", **MEDIAN)
    depth = first_word_clock(params) + 3
    if broken:
        monkeypatch.setattr(hdl_median, "_priming_ticks", lambda width: 0)
    core = tmp_path / "core.v"
    core.write_text(core_verilog(params))
    verdicts = {v.name: v for v in prove(core, params, tmp_path, depth=depth, timeout=120,
                                         groups=("free",))}
    if broken:
        assert verdicts["markers"].status == "failed", verdicts["markers"]
        assert "$var" in verdicts["markers"].trace.read_text()
    else:
        assert {v.status for v in verdicts.values()} == {"bounded"}, verdicts
        assert verdicts["markers"].detail.startswith(f"bounded to depth {depth} (words from")


@pytest.mark.parametrize("broken", [False, True])
def test_word_range_with_the_fraction(broken, tmp_path, monkeypatch):
    """D = 3, F = 2 (values 0 .. 8): the free group past the first line of words holds
    (depth 48); with the fit's numerator scaled by 2^(F+2) instead of 2^(F+1), the
    quotient overflows its 0 .. 2^F and a winner at d = 1 comes out as up to 9:
    ``word_range`` fails with a trace."""
    params = StereoParams(transform="census", **{**TINY, "disparities": 3, "width": 4},
                          subpixel_bits=2)
    if broken:
        monkeypatch.setattr(hdl_subpixel, "numerator",
                            lambda a, denominator, bits: (a << (bits + 2)) + denominator)
    core = tmp_path / "core.v"
    core.write_text(core_verilog(params))
    depth = default_depth(params)
    verdicts = {v.name: v for v in prove(core, params, tmp_path, depth=depth, timeout=120,
                                         groups=("free",))}
    if broken:
        assert verdicts["word_range"].status == "failed", verdicts["word_range"]
        assert "$var" in verdicts["word_range"].trace.read_text()
    else:
        assert {v.status for v in verdicts.values()} == {"bounded"}, verdicts
        assert verdicts["word_range"].detail.startswith(f"bounded to depth {depth} (words")


def _broken_core(params, wrapper):
    """The generated core renamed, behind a wrapper module ``npstereo_core`` whose body
    (the ports' logic) is ``wrapper``."""
    text = core_verilog(params).replace(f"module {TOP_NAME}(", f"module {TOP_NAME}_inner(")
    width = int(re.search(r"output \[(\d+):0\] m_axis_tdata", text).group(1)) + 1
    return text + f"""
module {TOP_NAME}(input clk, input rst, input [15:0] s_axis_tdata, input s_axis_tvalid,
    output s_axis_tready, input s_axis_tuser, input s_axis_tlast,
    output [{width - 1}:0] m_axis_tdata, output m_axis_tvalid, input m_axis_tready,
    output m_axis_tuser, output m_axis_tlast, output framing_error);
  wire [{width - 1}:0] tdata;
  wire tvalid, tready, tlast, tuser, error;
  {TOP_NAME}_inner inner(.clk(clk), .rst(rst), .s_axis_tdata(s_axis_tdata),
    .s_axis_tvalid(s_axis_tvalid), .s_axis_tready(s_axis_tready),
    .s_axis_tuser(s_axis_tuser), .s_axis_tlast(s_axis_tlast), .m_axis_tdata(tdata),
    .m_axis_tvalid(tvalid), .m_axis_tready(tready), .m_axis_tuser(tuser),
    .m_axis_tlast(tlast), .framing_error(error));
{wrapper}
endmodule
"""


#: tdata's bit 0 follows the input's tvalid, also while the sink stalls the word.
TOGGLING_TDATA = """  assign m_axis_tdata = tdata ^ s_axis_tvalid;
  assign m_axis_tvalid = tvalid, tready = m_axis_tready, m_axis_tlast = tlast;
  assign m_axis_tuser = tuser, framing_error = error;"""

#: Every line's last word is taken from the core and never offered.
DROPPED_LAST = """  assign m_axis_tdata = tdata, m_axis_tlast = tlast;
  assign m_axis_tvalid = tvalid && !tlast;
  assign tready = m_axis_tready || tlast;
  assign m_axis_tuser = tuser, framing_error = error;"""

#: The clock after a reset: what the next three wrappers misuse.
FRESH = """  reg fresh;
  always @(posedge clk) fresh <= rst;
"""

#: A word offered in the clock after a reset.
VALID_AFTER_RESET = FRESH + """  assign m_axis_tdata = tdata, m_axis_tlast = tlast, framing_error = error;
  assign m_axis_tuser = tuser;
  assign m_axis_tvalid = tvalid || fresh;
  assign tready = m_axis_tready;"""

#: A word of its own (a start of frame) offered after every reset until taken: output
#: without input.
SPURIOUS_WORD = """  reg extra;
  always @(posedge clk) extra <= rst ? 1'b1 : extra && !m_axis_tready;
  assign m_axis_tdata = extra ? 0 : tdata;
  assign m_axis_tvalid = extra || tvalid;
  assign m_axis_tuser = extra || tuser;
  assign m_axis_tlast = !extra && tlast;
  assign framing_error = error;
  assign tready = !extra && m_axis_tready;"""

#: framing_error raised in the clock after a reset, with no input at all.
SPURIOUS_ERROR = FRESH + """  assign m_axis_tdata = tdata, m_axis_tlast = tlast, m_axis_tvalid = tvalid;
  assign m_axis_tuser = tuser;
  assign tready = m_axis_tready;
  assign framing_error = error || fresh;"""


@pytest.mark.parametrize("wrapper,group,failing,depth", [
    (TOGGLING_TDATA, "induction", "hold", 36), (VALID_AFTER_RESET, "induction", "reset", 6),
    (DROPPED_LAST, "free", "markers", None), (SPURIOUS_WORD, "free", "no_spurious", 6),
    (SPURIOUS_WORD, "framed", "frame_count", 6),
    (SPURIOUS_ERROR, "misframed", "misframe_flag", 6)])
def test_broken_core_fails_with_a_trace(wrapper, group, failing, depth, tmp_path):
    """Each property that a bounded depth reaches fails on a core broken for it (the two
    completion properties, ``*_whole``, are beyond the depths the tests can afford). A
    depth of None: the default, past the first line of words (the first last marker)."""
    params = StereoParams(transform="census", **TINY)
    depth = default_depth(params) if depth is None else depth
    core = tmp_path / "broken.v"
    core.write_text(_broken_core(params, wrapper))
    verdicts = prove(core, params, tmp_path, depth=depth, timeout=60, groups=(group,))
    status = {v.name: v for v in verdicts}
    assert status[failing].status == "failed", status[failing]
    assert status[failing].trace is not None and status[failing].trace.stat().st_size > 0
    assert "$var" in status[failing].trace.read_text()


@pytest.mark.parametrize("extra,message", [
    (["--block", "7"], "block size must be <= 5 to prove, not 7"),
    (["--disparities", "16", "--width", "20"], "disparities must be <= 8 to prove, not 16"),
    (["--width", "20", "--height", "4"], "frame must have <= 64 pixels to prove, not 20x4"),
    (["--depth", "0"], "--depth must be >= 1, not 0"),
    (["--timeout", "0"], "--timeout must be > 0 seconds, not 0"),
    (["--checks", "nope"], "invalid choice: 'nope'"),
    (["--width", "2"], "image width must be an integer > 2"),
])
def test_bad_input_is_one_line(extra, message, tmp_path, capsys):
    out = tmp_path / "out"
    argv = ["prove", "--block", "3", "--disparities", "2", "--rounds", "1",
            "--out", str(out), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err, err
    assert not out.exists()


@pytest.mark.parametrize("bits", ["6", "-1"])
def test_subpixel_bits_out_of_range_is_one_line(bits, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["prove", "--subpixel-bits", bits, "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [
        f"npstereo: error: subpixel bits must be an integer 0 .. 5, not {bits}"]
    assert "Traceback" not in captured.err + captured.out and not out.exists()
