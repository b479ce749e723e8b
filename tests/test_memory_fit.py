"""A configuration whose memories the device cannot hold is refused at once (issue 27):
"does not fit (memory N %)" from ``npstereo report`` (its table, its JSON, the paper
sweep's tasks) and from the explorer, with no Verilog generated and no synthesis started.

The architecture's memory bits (``hdl.plan_memories.memory_bits``, checked against Yosys
by test_report.py) decide; the configurations below are computed to be just over and just
under the ECP5-85k's 4,502,976 bits.
"""

import json
import time

import pytest
from dask.delayed import Delayed
from PIL import Image

from npstereo.gen.cli import cmd_report
from npstereo.gen.cli.cmd_explore import write_outputs
from npstereo.gen.cli.main import main
from npstereo.gen.explore import explorer
from npstereo.gen.explore.explorer import Grid, configurations, explore, plan_tasks
from npstereo.gen.flow.capacity import DEVICES, memory_fit_message, target_device
from npstereo.gen.flow.tools import tool_versions
from npstereo.gen.reports import cache as report_cache, synthesis
from npstereo.gen.reports.plots import sweep_plots
from npstereo.gen.reports.tables import format_table, sweep_markdown
from npstereo.hdl.plan_memories import memory_bits
from npstereo.params import StereoParams

#: 1080p census 5x5, D = 128 at R = 1, a 5x5 box over cost rows: 5,048,694 bits, 112 % of
#: the ECP5-85k (its 3,833,856 bits of DP16KD and 669,120 of distributed RAM).
OVER = StereoParams(transform="census", block=5, disparities=128, rounds=1, aggregation=5,
                    width=1920, height=1080, line_buffer="costs")
#: The 3x3 box: a frame 3,342 wide is 458 bits under the 85k's memory, 3,343 886 over.
JUST_UNDER = OVER.replace(aggregation=3, width=3342)
JUST_OVER = JUST_UNDER.replace(width=3343)
#: Over the Cyclone V A9's M10K bits (12,492,800) too: 15,002,230 bits.
OVER_BOTH = OVER.replace(aggregation=7, width=3840)



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


def test_report_refuses_at_once_without_synthesis(nothing_built, tmp_path, capsys):
    json_path, cache = tmp_path / "r.json", tmp_path / "cache"
    started = time.monotonic()
    code = main([*_report(OVER), "--target", "ecp5", "--pnr", "--cache", str(cache),
                 "--json", str(json_path)])
    seconds = time.monotonic() - started
    assert code == 0 and seconds < 2, seconds
    out, err = capsys.readouterr()
    assert "ecp5 does not fit (memory 112 %)\n" in err
    row = out.splitlines()[1].split()
    assert row[:6] == ["ecp5", "-", "-", "-", "-", "5,048,694"]
    assert "does not fit (memory 112 %)" in out
    [report] = json.loads(json_path.read_text())["reports"]
    assert report["verilog_sha"] is None and report["expected_memory_bits"] == 5048694
    result = report["results"]["ecp5"]
    assert result["message"] == "does not fit (memory 112 %)"
    assert {k: result[k] for k in ("target", "status", "device", "memory_bits", "fits",
                                   "synthesised",
                                   "logic", "registers", "block_rams", "fmax_mhz",
                                   "frames_per_second")} == {
        "target": "ecp5", "status": "does not fit", "device": "ecp5-85k",
        "memory_bits": 5048694, "fits": False, "synthesised": False, "logic": None, "registers": None,
        "block_rams": None, "fmax_mhz": None, "frames_per_second": None}
    # A verdict that costs nothing is not cached.
    assert not list(cache.rglob("*.json"))


def test_both_targets_refused(nothing_built, capsys):
    assert main([*_report(OVER_BOTH), "--target", "all", "--no-cache"]) == 0
    out, err = capsys.readouterr()
    assert "cyclonev does not fit (memory 120 %), ecp5 does not fit (memory 333 %)\n" in err
    assert out.count("0 (not synthesised)") == 2


def test_just_under_is_built_just_over_is_not(monkeypatch):
    def reached(*args, **kwargs):
        raise Reached
    for name in ("synthesise", "design", "core_verilog"):
        monkeypatch.setattr(synthesis, name, reached)
    with pytest.raises(Reached):
        synthesis.synthesis_report(JUST_UNDER, ("ecp5",), pnr=True)
    report = synthesis.synthesis_report(JUST_OVER, ("ecp5",), pnr=True)
    assert report["results"]["ecp5"]["message"] == "does not fit (memory 100.1 %)"
    # The Cyclone V A9 holds what the ECP5 cannot: that target is generated.
    with pytest.raises(Reached):
        synthesis.synthesis_report(JUST_OVER, ("ecp5", "cyclonev"))


def test_lookup_and_sweep_tasks_give_the_verdict(nothing_built, tmp_path):
    found = synthesis.lookup(OVER, ("ecp5",), True, 150.0, tmp_path)
    assert found["results"]["ecp5"]["message"] == "does not fit (memory 112 %)"
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
    assert "does not fit (memory 120 %)" in table and "does not fit (memory 333 %)" in table
    paper = report | {"params": dict(report["params"], block=7)}
    text = sweep_markdown([paper])
    assert "| census | 7x7 | costs | does not fit | does not fit |" in text
    assert "| 15,002,230 |" in text
    assert "- census 7x7 (costs) cyclonev: does not fit (memory 120 %)\n" in text
    assert "| does not fit (memory 333 %) | - |" in text
    assert [p.name for p in sweep_plots([paper], tmp_path)] == ["logic.png", "memory.png"]


def _inline(client, tasks, desc, on_result=None):
    """``run_tasks`` on this process, one after another (no cluster)."""
    for task in tasks:
        args = [a.compute() if isinstance(a, Delayed) else a for a in task.args]
        on_result(task, task.function(*args), print)


def test_explorer_refuses_for_its_device_without_synthesis(monkeypatch, tmp_path,
                                                           small_pair):
    """Census 5x5 at 4096 wide on the ECP5-25k: the 3x3 box (919,590 bits) is synthesised,
    the 7x7 (2,230,902 bits: 182 % of the 25k, 50 % of the 85k the synthesis task checks
    against) is refused by the explorer itself."""
    grid = Grid(("census",), (5,), (4,), (3, 7), ("costs",), 16, 4096, 64)
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
    assert over["verdict"] == "does not fit (memory 182 %)" and over["fits"] is False
    assert over["memory_bits"] == 2230902 and over["logic"] is None
    assert over["synthesis"]["device"] == "ecp5-25k"
    assert fits["verdict"] == "fits" and result["pareto"] == [0]
    assert result["recommendation"] == 0
    assert not [p for p in tmp_path.rglob("*.json") if "memory 182" in p.read_text()]
    document = {"device": {"name": dev.name}, "scene": "synthetic", "conditions": ["clean"],
                "width": 4096, "height": 64, "disparities": 16, "pnr": False,
                "clock_mhz": 100.0, "skipped": [], "engine": "this process",
                "seconds": 1.0, **result}
    written = write_outputs(document, tmp_path / "out")
    markdown = written[1].read_text()
    assert "| 2,230,902 | - | - | - | - | does not fit (memory 182 %) |" in markdown
    assert "| memory bits | 1,226,496 | bit |" in markdown
    assert Image.open(written[2]).size[0] > 100
