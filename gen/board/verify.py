"""The board top, verified: one whole video frame of :class:`~.display.DepthDisplay`,
captured where the TMDS encoders take it, against the golden model's colour-mapped map.

Two simulators run the same check. Amaranth's own (:func:`capture_amaranth`) needs no
Verilog and runs a few thousand clocks a second: reduced frames and timings only (the
test suite). Verilator (:func:`capture_verilator`) runs a 640 x 480 frame (420,000 pixel
clocks after the first map) in seconds: the design's Verilog in a plain-Verilog harness
that clocks and resets itself, waits for the first vertical sync with ``map_ready`` high
and stores the next frame's displayed pixels in a memory, with the frame's length
in clocks and its count of horizontal syncs; cocotb (:mod:`.cocotb_board`) only
supervises, as for the core's whole-frame co-simulation (:mod:`npstereo.sim.harness`).
"""

import json
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from amaranth.back import verilog as amaranth_verilog
from amaranth.sim import Simulator

from ...sim.build import CosimError, build

__all__ = ["Capture", "Check", "compare", "capture_amaranth", "capture_verilator",
           "TOP", "HARNESS"]

TOP = "depth_display"
HARNESS = "board_harness"
TEST_MODULE = "npstereo.gen.board.cocotb_board"
PERIOD_NS = 10


@dataclass
class Capture:
    """One frame as the display receives it: the (v_active, h_active, 3) pixels with
    ``de`` high, the clocks from one vertical sync to the next and the horizontal syncs
    between them."""

    frame: np.ndarray
    frame_clocks: int
    hsyncs: int
    seconds: float


@dataclass
class Check:
    """A captured frame against the expected one."""

    mismatches: int
    first: str | None
    timing: list

    @property
    def ok(self):
        return self.mismatches == 0 and not self.timing

    def message(self):
        if self.ok:
            return "bit-exact"
        parts = list(self.timing)
        if self.mismatches:
            parts.insert(0, f"{self.mismatches} of the frame's pixels differ, first {self.first}")
        return "; ".join(parts)


def compare(expected, capture, timing):
    """Pixel by pixel and the frame's timing: a :class:`Check`."""
    bad = np.any(capture.frame != expected, axis=2)
    first = None
    if bad.any():
        y, x = (int(i) for i in np.argwhere(bad)[0])
        first = (f"at (x={x}, y={y}): expected RGB {tuple(int(c) for c in expected[y, x])}, "
                 f"got {tuple(int(c) for c in capture.frame[y, x])}")
    problems = []
    if capture.frame_clocks != timing.clocks:
        problems.append(f"a frame of {capture.frame_clocks} clocks, expected {timing.clocks}")
    if capture.hsyncs != timing.v_total:
        problems.append(f"{capture.hsyncs} horizontal syncs a frame, expected {timing.v_total}")
    return Check(int(bad.sum()), first, problems)


def capture_amaranth(display, timing):
    """The first whole frame after the map is in, under Amaranth's simulator."""
    pixels = timing.h_active * timing.v_active
    got = []
    figures = {}
    active = 0 if timing.negative else 1

    async def watch(ctx):
        clock, start, hsyncs, hsync_before, vsync_before = 0, None, 0, 1, 1
        # Room for the first map (the core's frame and its latency) and two video frames.
        limit = 4 * display.params.width * display.params.height * display.params.rounds \
            + 3 * timing.clocks
        async for _, _, ready, de, hsync, vsync, r, g, b in ctx.tick().sample(
                display.map_ready, display.de, display.hsync, display.vsync,
                display.r, display.g, display.b):
            clock += 1
            vsync_on, hsync_on = vsync == active, hsync == active
            if vsync_on and not vsync_before:
                if start is not None:
                    figures.update(frame_clocks=clock - start, hsyncs=hsyncs)
                    return
                if ready:
                    start, hsyncs = clock, 0
            if hsync_on and not hsync_before:
                hsyncs += 1
            vsync_before, hsync_before = vsync_on, hsync_on
            if start is not None and de and len(got) < pixels:
                got.append((r, g, b))
            if clock > limit:
                raise CosimError(f"no whole frame after {limit} clocks")

    sim = Simulator(display)
    sim.add_clock(PERIOD_NS * 1e-9)
    sim.add_testbench(watch)
    began = time.perf_counter()
    sim.run()
    return _capture(got, timing, figures, time.perf_counter() - began)


def _capture(pixels, timing, figures, seconds):
    frame = np.zeros((timing.v_active * timing.h_active, 3), np.uint8)
    frame[:len(pixels)] = np.asarray(pixels, np.uint8).reshape(-1, 3)
    return Capture(frame.reshape(timing.v_active, timing.h_active, 3),
                   figures.get("frame_clocks", 0), figures.get("hsyncs", 0), seconds)


def harness_verilog(timing):
    """The self-clocking harness around ``depth_display`` (see the module docstring)."""
    pixels = timing.h_active * timing.v_active
    active = "1'b0" if timing.negative else "1'b1"
    return f"""\
// Whole-frame capture harness for {TOP}, generated by npstereo.gen.board.verify.
`timescale 1ns/1ps
module {HARNESS} (
    input  wire        dump /*verilator public_flat_rw*/,
    output reg         done /*verilator public_flat_rw*/,
    output reg  [31:0] captured /*verilator public_flat_rw*/,
    output reg  [31:0] frame_clocks /*verilator public_flat_rw*/,
    output reg  [31:0] hsyncs /*verilator public_flat_rw*/,
    output reg  [31:0] cycle /*verilator public_flat_rw*/
);
    localparam PIXELS = {pixels};
    reg clk = 1'b0;
    always #{PERIOD_NS // 2} clk = ~clk;
    reg rst = 1'b1;
    reg [3:0] reset_count = 4'd0;
    always @(posedge clk) begin
        reset_count <= reset_count + (rst ? 4'd1 : 4'd0);
        if (reset_count == 4'd3) rst <= 1'b0;
    end

    wire [7:0] r, g, b;
    wire hsync, vsync, de, map_ready;
    {TOP} dut (.clk(clk), .rst(rst), .r(r), .g(g), .b(b), .hsync(hsync), .vsync(vsync),
               .de(de), .map_ready(map_ready));

    reg [23:0] frame [0:PIXELS-1];
    reg started, dumped, vsync_before, hsync_before;
    reg [31:0] start;
    wire vsync_on = vsync == {active};
    wire hsync_on = hsync == {active};
    always @(posedge clk) begin
        if (rst) begin
            started <= 0; dumped <= 0; done <= 0; captured <= 0; cycle <= 0;
            frame_clocks <= 0; hsyncs <= 0; start <= 0; vsync_before <= 1; hsync_before <= 1;
        end else begin
            cycle <= cycle + 1;
            vsync_before <= vsync_on;
            hsync_before <= hsync_on;
            if (vsync_on && !vsync_before) begin
                if (started && !done) begin
                    frame_clocks <= cycle - start;
                    done <= 1;
                end else if (map_ready && !started) begin
                    started <= 1;
                    start <= cycle;
                end
            end
            if (started && !done && hsync_on && !hsync_before) hsyncs <= hsyncs + 1;
            if (started && !done && de && captured < PIXELS) begin
                frame[captured] <= {{b, g, r}};
                captured <= captured + 1;
            end
            if (dump && !dumped) begin
                $writememh("frame.hex", frame);
                dumped <= 1;
            end
        end
    end
endmodule
"""


def capture_verilator(display, timing, progress=None):
    """The first whole frame after the map is in, under Verilator (cocotb supervising).

    ``progress(pixels)`` is called now and then with the frame's pixels captured so far.
    Returns the :class:`Capture` and the model's build seconds (0 when it was cached).
    """
    design = amaranth_verilog.convert(display, name=TOP)
    model = build("verilator", {f"{TOP}.v": design, f"{HARNESS}.v": harness_verilog(timing)},
                  HARNESS, harness=True)
    runs = model.directory / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    run_dir = Path(tempfile.mkdtemp(prefix="frame-", dir=runs))
    p = display.params
    budget = 4 * p.width * p.height * p.rounds + 3 * timing.clocks
    plan = {"period_ns": PERIOD_NS, "timeout_cycles": budget,
            "chunk_cycles": max(10_000, timing.clocks // 20)}
    (run_dir / "plan.json").write_text(json.dumps(plan))
    began = time.perf_counter()
    log = run_dir / "sim.log"
    try:
        model.runner().test(
            test_module=TEST_MODULE, hdl_toplevel=HARNESS, testcase="frame_test",
            hdl_toplevel_lang="verilog", build_dir=model.sim_dir, test_dir=run_dir,
            extra_env={"NPSTEREO_BOARD_PLAN": str(run_dir / "plan.json")},
            results_xml=str(run_dir / "results.xml"), log_file=log)
    except (RuntimeError, SystemExit) as error:
        raise CosimError(f"verilator run failed ({error}); see {log}") from None
    seconds = time.perf_counter() - began
    result_file = run_dir / "result.json"
    if not result_file.exists():
        raise CosimError(f"verilator run ended without a frame; see {log}")
    figures = json.loads(result_file.read_text())
    if progress is not None:
        progress(figures["captured"])
    words = _read_memh(run_dir / "frame.hex", figures["captured"])
    pixels = [(w & 0xFF, (w >> 8) & 0xFF, (w >> 16) & 0xFF) for w in words]
    return _capture(pixels, timing, figures, seconds), model.seconds


def _read_memh(path, count):
    """The first ``count`` words of a ``$writememh`` file (comments skipped; x words are
    -1, which no colour equals)."""
    words = []
    for line in path.read_text().splitlines():
        line = line.split("//")[0].strip()
        if not line or line.startswith("@"):
            continue
        words.append(-1 if any(c in "xXzZ" for c in line) else int(line, 16))
        if len(words) == count:
            break
    return words
