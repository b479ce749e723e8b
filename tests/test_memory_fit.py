"""A configuration whose memories the device cannot hold is refused at once (issue 27):
"does not fit (memory N %)" from ``npstereo report`` (its table, its JSON, the paper
sweep's tasks) and from the explorer, with no Verilog generated and no synthesis started.

Two counts decide: the architecture's memory bits (``hdl.plan_memories.memory_bits``,
checked against Yosys by test_report.py) against the device's block and LUT RAM bits, and
on ECP5 parts the DP16KD that Yosys maps the memories to (``gen.flow.block_rams``, checked
here against the memories an elaborated core makes and against Yosys's counts measured by
hand, docs/resources.md). The bits' boundary is computed just over and just under the
ECP5-85k's 4,502,976 bits; the blocks' at 208 DP16KD (a frame one pixel wider crosses it).
"""

import json
import time
from collections import Counter

import pytest
from amaranth.hdl import Fragment, Shape
from amaranth.lib.memory import Memory
from dask.delayed import Delayed
from PIL import Image

from npstereo.gen.cli import cmd_report
from npstereo.gen.cli.cmd_explore import write_outputs
from npstereo.gen.cli.main import main
from npstereo.gen.explore import explorer
from npstereo.gen.explore.explorer import Grid, configurations, explore, plan_tasks
from npstereo.gen.flow.block_rams import block_rams, core_block_rams
from npstereo.gen.flow.capacity import DEVICES, memory_fit_message, target_device
from npstereo.gen.flow.tools import tool_versions
from npstereo.gen.reports import cache as report_cache, synthesis
from npstereo.gen.reports.plots import sweep_plots
from npstereo.gen.reports.tables import format_table, sweep_markdown
from npstereo.hdl import plan_memories
from npstereo.hdl.core import NpStereoCore
from npstereo.hdl.plan_memories import BLOCK, memory_bits
from npstereo.params import StereoParams

#: 1080p census 5x5, D = 128 at R = 1, a 5x5 box over cost rows: 5,048,694 bits, 112 % of
#: the ECP5-85k (its 3,833,856 bits of DP16KD and 669,120 of distributed RAM), and 522
#: DP16KD (251 % of its 208: 512 banks of cost lines, 512 x 20 bits each).
OVER = StereoParams(transform="census", block=5, disparities=128, rounds=1, aggregation=5,
                    width=1920, height=1080, line_buffer="costs")
#: The 3x3 box: a frame 3,342 wide is 458 bits under the 85k's memory, 3,343 886 over
#: (by its bits; its 914 DP16KD do not fit either).
JUST_UNDER = OVER.replace(aggregation=3, width=3342)
JUST_OVER = JUST_UNDER.replace(width=3343)
#: Over the Cyclone V A9's M10K bits (12,492,800) too: 15,002,230 bits (1,042 DP16KD).
OVER_BOTH = OVER.replace(aggregation=7, width=3840)
#: The issue's case: census 5x5 SGM with the fifth path at 1280 x 720, D = 64, R = 1. Its
#: 3,200,786 bits are 71 % of the 85k's memory, its 218 DP16KD 105 % of its block RAM.
FIFTH_720P = StereoParams(transform="census", block=5, disparities=64, rounds=1,
                          aggregation="sgm", fifth_path=True, width=1280, height=720)
#: Just under and just over the 85k's 208 DP16KD by blocks alone (24 % of its bits): the
#: paper's census 5x5, D = 100, R = 4 with the 3x3 box and its costs in line buffers,
#: 1,024 wide takes 206; 1,025 wide 210 (each unit's W R words of costs need a ninth bank).
BLOCKS_UNDER = StereoParams(transform="census", block=5, disparities=100, rounds=4,
                            aggregation=3, line_buffer="costs", width=1024, height=480)
BLOCKS_OVER = BLOCKS_UNDER.replace(width=1025)



def _report(p):
    """``npstereo report`` of the configuration ``p``."""
    return ["report", "--transform", p.transform, "--block", str(p.block), "--disparities",
            str(p.disparities), "--rounds", str(p.rounds), "--aggregation",
            str(p.aggregation), "--line-buffer", p.line_buffer, "--width", str(p.width),
            "--height", str(p.height)]


class Reached(Exception):
    """Verilog generation was reached: the configuration was not refused."""


@pytest.fixture
def nothing_built(monkeypatch):
    """Fail the test if any Verilog is generated or any synthesis started (``pytest.fail``
    is not an ``Exception``: ``synthesis_job`` does not turn it into a failed result)."""
    def forbidden(*args, **kwargs):
        pytest.fail("a refused configuration was generated or synthesised")
    for name in ("synthesise", "design", "core_verilog"):
        monkeypatch.setattr(synthesis, name, forbidden)
    monkeypatch.setattr(report_cache, "core_verilog", forbidden)


def test_devices_memory_capacity():
    assert {name: d.memory_bits for name, d in DEVICES.items()} == {
        "ecp5-85k": 208 * 18432 + 10455 * 64, "ecp5-45k": 108 * 18432 + 5481 * 64,
        "ecp5-25k": 56 * 18432 + 3036 * 64, "cyclonev-a9": 1220 * 10240,
        "ep2s180": 9383040}
    assert target_device("ecp5", "ecp5-25k").name == "ecp5-25k"
    assert target_device("cyclonev").name == "cyclonev-a9"


def test_memory_verdict_at_the_boundary():
    ecp5 = DEVICES["ecp5-85k"]
    assert memory_fit_message(ecp5.memory_bits, ecp5) is None
    assert memory_fit_message(ecp5.memory_bits + 1, ecp5) == "does not fit (memory 100.1 %)"
    assert memory_bits(JUST_UNDER) == ecp5.memory_bits - 458
    assert memory_bits(JUST_OVER) == ecp5.memory_bits + 886
    assert memory_bits(OVER) == 5048694
    assert memory_fit_message(memory_bits(JUST_UNDER), ecp5) is None
    assert memory_fit_message(memory_bits(JUST_OVER), ecp5) == "does not fit (memory 100.1 %)"
    assert memory_fit_message(memory_bits(OVER), ecp5) == "does not fit (memory 112 %)"
    # The blocks: 208 DP16KD fit, 209 do not; the fuller count is the one shown.
    assert memory_fit_message(0, ecp5, 208) is None
    assert memory_fit_message(0, ecp5, 209) == "does not fit (memory 100.5 %)"
    assert memory_fit_message(ecp5.memory_bits + 1, ecp5, 416) == \
        "does not fit (memory 200 %)"
    # The Cyclone V has no DP16KD: its bits alone decide.
    assert memory_fit_message(0, DEVICES["cyclonev-a9"], 10 ** 6) is None
    # Bits alone would accept the 3x3 box 3,342 wide: its 914 DP16KD do not fit.
    assert core_block_rams(JUST_UNDER) == 914 and memory_fit_message(
        memory_bits(JUST_UNDER), ecp5, core_block_rams(JUST_UNDER)) == \
        "does not fit (memory 439 %)"


def test_report_refuses_at_once_without_synthesis(nothing_built, tmp_path, capsys):
    json_path, cache = tmp_path / "r.json", tmp_path / "cache"
    started = time.monotonic()
    code = main([*_report(OVER), "--target", "ecp5", "--pnr", "--cache", str(cache),
                 "--json", str(json_path)])
    seconds = time.monotonic() - started
    assert code == 0 and seconds < 2, seconds
    out, err = capsys.readouterr()
    assert "ecp5 does not fit (memory 251 %)\n" in err
    row = out.splitlines()[1].split()
    assert row[:6] == ["ecp5", "-", "-", "-", "-", "5,048,694"]
    assert "does not fit (memory 251 %)" in out
    [report] = json.loads(json_path.read_text())["reports"]
    assert report["verilog_sha"] is None and report["expected_memory_bits"] == 5048694
    result = report["results"]["ecp5"]
    assert result["message"] == "does not fit (memory 251 %)"
    assert {k: result[k] for k in ("target", "status", "device", "memory_bits", "fits",
                                   "synthesised", "expected_block_rams",
                                   "logic", "registers", "block_rams", "fmax_mhz",
                                   "frames_per_second")} == {
        "target": "ecp5", "status": "does not fit", "device": "ecp5-85k",
        "memory_bits": 5048694, "fits": False, "synthesised": False,
        "expected_block_rams": 522, "logic": None, "registers": None,
        "block_rams": None, "fmax_mhz": None, "frames_per_second": None}
    # A verdict that costs nothing is not cached.
    assert not list(cache.rglob("*.json"))


def test_both_targets_refused(nothing_built, capsys):
    assert main([*_report(OVER_BOTH), "--target", "all", "--no-cache"]) == 0
    out, err = capsys.readouterr()
    assert "cyclonev does not fit (memory 120 %), ecp5 does not fit (memory 501 %)\n" in err
    assert out.count("0 (not synthesised)") == 2


def test_just_under_is_built_just_over_is_not(monkeypatch):
    """By blocks: 206 DP16KD are built, 210 (a frame one pixel wider) refused, both well
    within the 85k's bits."""
    def reached(*args, **kwargs):
        raise Reached
    for name in ("synthesise", "design", "core_verilog"):
        monkeypatch.setattr(synthesis, name, reached)
    ecp5 = DEVICES["ecp5-85k"]
    assert (core_block_rams(BLOCKS_UNDER), core_block_rams(BLOCKS_OVER)) == (206, 210)
    assert memory_bits(BLOCKS_OVER) < 0.3 * ecp5.memory_bits
    with pytest.raises(Reached):
        synthesis.synthesis_report(BLOCKS_UNDER, ("ecp5",), pnr=True)
    report = synthesis.synthesis_report(BLOCKS_OVER, ("ecp5",), pnr=True)
    assert report["results"]["ecp5"]["message"] == "does not fit (memory 101.0 %)"
    # The Cyclone V A9 holds what the ECP5 cannot (its bits decide there): that target is
    # generated.
    with pytest.raises(Reached):
        synthesis.synthesis_report(BLOCKS_OVER, ("ecp5", "cyclonev"))


def test_fifth_path_720p_refused_by_report_at_once(nothing_built, tmp_path, capsys):
    """The issue's case: its bits fit the 85k (71 %), its 218 DP16KD do not."""
    ecp5 = DEVICES["ecp5-85k"]
    bits = memory_bits(FIFTH_720P)
    assert bits == 3200786 and memory_fit_message(bits, ecp5) is None
    assert core_block_rams(FIFTH_720P) == 218
    json_path = tmp_path / "r.json"
    started = time.monotonic()
    code = main(["report", "--transform", "census", "--block", "5", "--disparities", "64",
                 "--rounds", "1", "--aggregation", "sgm", "--fifth-path", "--width", "1280",
                 "--height", "720", "--target", "ecp5", "--pnr", "--cache",
                 str(tmp_path / "cache"), "--json", str(json_path)])
    assert code == 0 and time.monotonic() - started < 2
    out, err = capsys.readouterr()
    assert err.splitlines()[-1] == (f"{FIFTH_720P.describe()}: ecp5 does not fit (memory "
                                    "105 %)")
    [report] = json.loads(json_path.read_text())["reports"]
    result = report["results"]["ecp5"]
    assert report["verilog_sha"] is None and result["status"] == "does not fit"
    assert (result["message"], result["expected_block_rams"], result["memory_bits"]) == (
        "does not fit (memory 105 %)", 218, 3200786)
    assert not list((tmp_path / "cache").rglob("*.json"))


def test_lookup_and_sweep_tasks_give_the_verdict(nothing_built, tmp_path):
    found = synthesis.lookup(OVER, ("ecp5",), True, 150.0, tmp_path)
    assert found["results"]["ecp5"]["message"] == "does not fit (memory 251 %)"
    assert synthesis.lookup(OVER, ("ecp5",), False, 150.0, None) is not None
    # The Cyclone V synthesis is not in the cache: no whole report, the ECP5 part of it.
    assert synthesis.lookup(OVER, ("ecp5", "cyclonev"), False, 150.0, tmp_path) is None
    partial = synthesis.lookup(OVER, ("ecp5", "cyclonev"), False, 150.0, tmp_path,
                               partial=True)
    assert list(partial["results"]) == ["ecp5"]
    cached, tasks = cmd_report.synthesis_tasks([OVER], ("ecp5",), True, 150.0, 60.0,
                                               tmp_path, None)
    assert tasks == [] and cached[0]["results"]["ecp5"]["status"] == "does not fit"
    # A worker's mixed report: the synthesised target is stored, the refused one is not.
    mixed = dict(found, verilog_sha="0" * 24,
                 results={"ecp5": found["results"]["ecp5"],
                          "cyclonev": {"target": "cyclonev", "status": "ok", "logic": 1}})
    synthesis.store_report(mixed, tmp_path, False, 150.0)
    assert [json.loads(p.read_text())["target"] for p in tmp_path.glob("*.json")] == \
        ["cyclonev"]
    # A sweep document holding the verdict seeds nothing and generates nothing.
    sweep = tmp_path / "sweep.json"
    sweep.write_text(json.dumps({"tools": tool_versions(), "hdl_sources":
                                 report_cache.source_hash(), "reports": [found]}))
    assert report_cache.earlier_reports(sweep, tmp_path / "seeded") == []
    assert report_cache.seed_cache(sweep, tmp_path / "seeded") == 0


def test_tables_and_plots_show_the_verdict(nothing_built, tmp_path):
    report = synthesis.synthesis_report(OVER_BOTH, ("cyclonev", "ecp5"))
    table = format_table(report)
    assert "does not fit (memory 120 %)" in table and "does not fit (memory 501 %)" in table
    paper = report | {"params": dict(report["params"], block=7)}
    text = sweep_markdown([paper])
    assert "| census | 7x7 | costs | does not fit | does not fit |" in text
    assert "| 15,002,230 |" in text
    assert "- census 7x7 (costs) cyclonev: does not fit (memory 120 %)\n" in text
    assert "| does not fit (memory 501 %) | - |" in text
    assert [p.name for p in sweep_plots([paper], tmp_path)] == ["logic.png", "memory.png"]


def _inline(client, tasks, desc, on_result=None):
    """``run_tasks`` on this process, one after another (no cluster)."""
    for task in tasks:
        args = [a.compute() if isinstance(a, Delayed) else a for a in task.args]
        on_result(task, task.function(*args), print)


def test_explorer_refuses_for_its_device_without_synthesis(monkeypatch, tmp_path,
                                                           small_pair):
    """Census 5x5 at 1024 wide on the ECP5-25k: the 3x3 box (38 DP16KD) is synthesised,
    the 9x9 (70 DP16KD: 125 % of the 25k's 56 with 59 % of its bits, 34 % of the 85k the
    synthesis task checks against) is refused by the explorer itself."""
    grid = Grid(("census",), (5,), (4,), (3, 9), ("costs",), 16, 1024, 64)
    configs, _ = configurations(grid)
    dev = DEVICES["ecp5-25k"]
    started = time.monotonic()
    plan = plan_tasks(configs, {}, dev, False, 150.0, None, tmp_path, None)
    assert time.monotonic() - started < 1
    assert [t.args[0] for t in plan.tasks] == [configs[0]]
    built = []

    def design(params, cache):
        built.append(params)
        return "0" * 24, "// stands for the core"

    def synthesise(verilog, target, top, **options):
        return {"target": target, "status": "ok", "message": "", "fmax_mhz": None,
                "logic": 9000, "carry_chains": 100, "lut_rams": 0, "registers": 5000,
                "block_rams": 40, "dsps": 0, "memory_bits": memory_bits(configs[0]),
                "logic_levels": 6.0, "seconds": 1.0}
    monkeypatch.setattr(synthesis, "design", design)
    monkeypatch.setattr(synthesis, "synthesise", synthesise)
    monkeypatch.setattr(explorer, "run_tasks", _inline)
    scenes = {"clean": (small_pair.left, small_pair.right, small_pair.ground_truth)}
    result = explore("inline", configs, scenes, dev, cache=tmp_path)
    assert built == [configs[0]]
    fits, over = result["points"]
    assert over["verdict"] == "does not fit (memory 125 %)" and over["fits"] is False
    assert over["memory_bits"] == 723766 and over["logic"] is None
    assert over["synthesis"]["expected_block_rams"] == 70
    assert over["synthesis"]["device"] == "ecp5-25k"
    assert fits["verdict"] == "fits" and result["pareto"] == [0]
    assert result["recommendation"] == 0
    assert not [p for p in tmp_path.rglob("*.json") if "memory 125" in p.read_text()]
    document = {"device": {"name": dev.name}, "scene": "synthetic", "conditions": ["clean"],
                "width": 1024, "height": 64, "disparities": 16, "pnr": False,
                "clock_mhz": 100.0, "skipped": [], "engine": "this process",
                "seconds": 1.0, **result}
    written = write_outputs(document, tmp_path / "out")
    markdown = written[1].read_text()
    assert "| 723,766 | - | - | - | - | does not fit (memory 125 %) |" in markdown
    assert "| memory bits | 1,226,496 | bit |" in markdown
    assert Image.open(written[2]).size[0] > 100


def _elaborated_shapes(params):
    """(depth, width) -> count of the ``Memory`` objects an elaborated core makes."""
    made = record_memories_for(params)
    return Counter((m.depth, Shape.cast(m.shape).width) for m in made)


def record_memories_for(params):
    made = []
    create = Memory.__init__

    def recording(self, *args, **kwargs):
        create(self, *args, **kwargs)
        made.append(self)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Memory, "__init__", recording)
        Fragment.get(NpStereoCore(params), None)
    return made


def _listed_shapes(uses):
    shapes = Counter()
    for use in uses:
        shapes[use.depth, use.width] += use.count
    return shapes


#: Cores whose memories the HDL cuts every way: line buffers over 512 words (slices of
#: 1K x 18 and 2K x 9), cost lines in banks, SGM's path rows in banks of 72-bit slices, the
#: fifth path's rows, the median's rows, the cost term's and the stores' LUT RAM.
SHAPED = [
    StereoParams(transform="census", block=5, disparities=16, rounds=4, width=640,
                 height=16, line_buffer="costs", median=True),
    StereoParams(transform="census", block=5, disparities=32, rounds=4, width=1280,
                 height=16, line_buffer="transforms"),
    StereoParams(transform="census", block=5, disparities=16, rounds=4, aggregation="sgm",
                 fifth_path=True, width=640, height=16),
    StereoParams(transform="census", block=5, disparities=16, rounds=2, aggregation="sgm",
                 cost_term="ad3", subpixel_bits=4, median=True, width=1280, height=16),
    # R = 1: the SGM stage's delay lines of LUT RAM at their longest.
    StereoParams(transform="census", block=5, disparities=64, rounds=1, aggregation="sgm",
                 fifth_path=True, width=640, height=16),
]


@pytest.mark.parametrize("params", SHAPED, ids=lambda p: p.describe())
def test_built_memories_are_the_ones_the_hdl_makes(params):
    """The shapes the block count starts from are the ``Memory`` objects an elaborated core
    makes, one for one, and hold the architecture's bits."""
    built = plan_memories.built_memories(params)
    assert _listed_shapes(built) == _elaborated_shapes(params)
    assert sum(use.bits for use in built) == memory_bits(params)


def test_a_count_that_forgets_a_memory_kind_is_caught(monkeypatch):
    """Broken variant: the fifth path's S4 row left out of the list. The shapes no longer
    match the elaborated core's, the issue's 720p core counts fewer blocks, and the
    fifth-path cores measured by Yosys no longer get its count."""
    params = SHAPED[2]
    whole = plan_memories.memories

    def forgetful(*args, **kwargs):
        return [use for use in whole(*args, **kwargs) if use.name != "fifth path S4 row"]
    monkeypatch.setattr(plan_memories, "memories", forgetful)
    assert _listed_shapes(plan_memories.built_memories(params)) != _elaborated_shapes(params)
    assert core_block_rams(FIFTH_720P) < 218
    assert [p for p, measured in MEASURED_BY_YOSYS if core_block_rams(p) != measured] == [
        p for p, _ in MEASURED_BY_YOSYS if p.fifth_path]


def test_block_shapes_as_yosys_chooses_them():
    """memory_libmap's choices (docs/resources.md, "Block RAM before synthesis")."""
    assert block_rams(512, 72) == 2          # 512 x 36, two side by side
    assert block_rams(1280, 18) == 2         # two address ranges of 1K x 18
    assert block_rams(2560, 4) == 1          # 4K x 4
    assert block_rams(2048, 27) == 3         # 2K x 9, three bytes
    assert block_rams(1024, 27) == 2         # 1K x 18 holds two of the 9-bit bytes
    assert block_rams(128, 8) == 0           # LUT RAM: 16 DPR16X4 cost less than a block
    assert block_rams(128, 72) == 2          # 144 DPR16X4 do not
    assert block_rams(63, 10) == 0 and block_rams(4, 40, "async") == 0
    # The output queue (Amaranth's FIFO, its reads ordered with its writes): Yosys's
    # read-first emulation in front of a block RAM tips 127 x 10 to LUT RAM (measured).
    assert block_rams(127, 10) == 1 and block_rams(127, 10, ordered=True) == 0
    assert block_rams(32, 4, BLOCK) == 1     # ram_style block: the L/R check's
    assert block_rams(64, 24, rom=True) == 0     # a small ROM in LUTs
    assert block_rams(1009, 24, rom=True) == 2


def test_explorer_refuses_the_fifth_path_at_720p_at_once(monkeypatch, nothing_built):
    """The issue's case in a grid with the four paths: the fifth path's core is told "does
    not fit" by the explorer's planning, with no task for its synthesis (the four paths'
    127 DP16KD fit and get one)."""
    grid = Grid(("census",), (5,), (1,), ("sgm",), ("auto",), 64, 1280, 720,
                fifth_paths=(False, True))
    configs, skipped = configurations(grid)
    assert skipped == [] and [p.fifth_path for p in configs] == [False, True]
    assert core_block_rams(configs[0]) == 127
    started = time.monotonic()
    plan = plan_tasks(configs, {}, DEVICES["ecp5-85k"], True, 150.0, None, None, None)
    assert time.monotonic() - started < 1
    assert [t.args[0] for t in plan.tasks] == [configs[0]]
    result = plan.synthesis[1]["results"]["ecp5"]
    assert result["message"] == "does not fit (memory 105 %)"
    assert result["expected_block_rams"] == 218 and result["synthesised"] is False


#: DP16KD that Yosys 0.70's synth_ecp5 mapped these cores to, measured by hand with
#: ``gen.reports.synthesis.synthesis_report(params, ["ecp5"])`` (docs/resources.md, "Block RAM
#: before synthesis"; 1-4 min each, not in ``make test``). An HDL change that moves a count
#: must be measured again and this table and the document's updated.
C5 = dict(transform="census", block=5)
MEASURED_BY_YOSYS = [
    (StereoParams(**C5, disparities=16, rounds=1, width=640, height=48), 8),
    (StereoParams(**C5, disparities=16, rounds=4, width=640, height=48, line_buffer="costs",
                  median=True), 28),
    (StereoParams(**C5, disparities=32, rounds=4, width=1280, height=48,
                  line_buffer="transforms"), 21),
    (StereoParams(**C5, disparities=16, rounds=1, aggregation="sgm", width=640, height=48), 29),
    (StereoParams(**C5, disparities=16, rounds=4, aggregation="sgm", fifth_path=True,
                  width=640, height=48), 37),
    (StereoParams(**C5, disparities=16, rounds=1, aggregation="sgm", fifth_path=True,
                  median=True, cost_term="ad3", width=640, height=48), 48),
    (StereoParams(**C5, disparities=16, rounds=2, aggregation="sgm", cost_term="ad3",
                  subpixel_bits=4, width=1280, height=48), 41),
    (StereoParams(**C5, disparities=64, rounds=4, aggregation="sgm", width=1280,
                  height=720), 109),
    (StereoParams(transform="census", block=7, disparities=64, rounds=4, aggregation="sgm",
                  fifth_path=True, cost_term="ad3", median=True, width=640, height=480), 107),
]


@pytest.mark.parametrize("params, measured", MEASURED_BY_YOSYS,
                         ids=[p.describe() for p, _ in MEASURED_BY_YOSYS])
def test_block_count_is_what_yosys_measured(params, measured):
    assert core_block_rams(params) == measured
