"""cocotb test module run inside the simulator (Icarus or Verilator) by :mod:`.cosim`.

The parent process writes a plan (JSON, path in ``NPSTEREO_COSIM_PLAN``) and the frames
with their golden output words (``.npz``) into the run directory; these tests execute the
plan, compare every output pixel, write ``result.json`` for the parent and fail with the
first mismatch (x, y, expected, got) and the count.

``stream_test`` drives ``npstereo_core`` with cocotbext-axi (idle cycles, backpressure,
frames back to back, resets, mis-framed lines); ``harness_test`` runs whole frames through
the Verilog harness of :mod:`.harness`, with no per-pixel Python.
"""

import itertools
import json
import logging
import os
import random
from pathlib import Path

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, First, RisingEdge, Timer
from cocotbext.axi import AxiStreamBus, AxiStreamFrame, AxiStreamSink, AxiStreamSource

from npstereo.hdl.stream import WordCodec
from npstereo.params import StereoParams
from npstereo.sim.frames import Comparison, compare_frame, decode_map

PERIOD_NS = 10


def _load_plan():
    path = Path(os.environ["NPSTEREO_COSIM_PLAN"])
    plan = json.loads(path.read_text())
    params = StereoParams(**plan["params"])
    data = np.load(path.parent / plan["data"])
    return path.parent, plan, params, data


def _finish(run_dir, plan, records, extra=None):
    """Write the results for the parent, then fail the test on any mismatch."""
    result = {"frames": [record for record in records], **(extra or {})}
    (run_dir / plan["result"]).write_text(json.dumps(result))
    bad = [(record["label"], Comparison.from_dict(record["comparison"]))
           for record in records if not Comparison.from_dict(record["comparison"]).ok]
    assert not bad, "; ".join(f"{label}: {comp.message()}" for label, comp in bad)


def _pauses(rng, probability):
    """Per-cycle pause flags: True with ``probability``, for cocotbext's pause generators."""
    return (rng.random() < probability for _ in itertools.count())


class TB:
    """Clock, reset, AXI4-Stream source and sink around one ``npstereo_core``."""

    def __init__(self, dut, params, seed):
        self.dut = dut
        self.params = params
        self.rng = random.Random(seed)
        Clock(dut.clk, PERIOD_NS, unit="ns").start()
        # One lane of the full width: every beat is one pixel word.
        self.source = AxiStreamSource(AxiStreamBus.from_prefix(dut, "s_axis"), dut.clk,
                                      dut.rst, byte_lanes=1)
        self.sink = AxiStreamSink(AxiStreamBus.from_prefix(dut, "m_axis"), dut.clk,
                                  dut.rst, byte_lanes=1)
        for port in (self.source, self.sink):
            port.log.setLevel(logging.WARNING)

    def set_traffic(self, idle, backpressure):
        """Random idle cycles on the input and random backpressure on the output."""
        for port, probability in ((self.source, idle), (self.sink, backpressure)):
            if probability > 0:
                port.set_pause_generator(_pauses(self.rng, probability))
            else:
                # Clearing the generator keeps its last value: unpause explicitly.
                port.clear_pause_generator()
                port.pause = False

    async def reset(self, cycles=4):
        self.dut.rst.value = 1
        await ClockCycles(self.dut.clk, cycles)
        self.dut.rst.value = 0
        await RisingEdge(self.dut.clk)
        self.sink.clear()

    async def send_lines(self, lines):
        """Queue lines (lists of input words); the first carries the start of frame."""
        for y, line in enumerate(lines):
            await self.source.send(AxiStreamFrame(
                tdata=list(line), tuser=[int(y == 0)] + [0] * (len(line) - 1)))

    async def receive(self, count, quiet_cycles):
        """Beats until ``count`` arrived, or until nothing arrived for ``quiet_cycles``.

        ``count=None`` drains: everything up to the first quiet period.
        """
        data, tuser, tlast = [], [], []
        poll = max(16, quiet_cycles // 16)
        quiet = 0
        while count is None or len(data) < count:
            if self.sink.empty():
                if quiet >= quiet_cycles:
                    break
                await Timer(poll * PERIOD_NS, unit="ns")
                quiet += poll
                continue
            quiet = 0
            frame = self.sink.recv_nowait(compact=False)
            data.extend(int(word) for word in frame.tdata)
            tuser.extend(int(flag) for flag in frame.tuser)
            tlast.extend([0] * (len(frame.tdata) - 1) + [1])
        return data, tuser, tlast


def _lines(words, width):
    return [words[i:i + width] for i in range(0, len(words), width)]


@cocotb.test()
async def stream_test(dut):
    """Execute the plan's steps through cocotbext-axi and compare every frame."""
    run_dir, plan, params, data = _load_plan()
    width, pixels = params.width, params.width * params.height
    tb = TB(dut, params, plan.get("seed", 1))
    quiet = plan["quiet_cycles"]
    records = []
    await tb.reset()
    for number, step in enumerate(plan["steps"]):
        op = step["op"]
        label = f"step {number} ({op})"
        tb.set_traffic(step.get("idle", 0.0), step.get("backpressure", 0.0))
        if op == "reset":
            await tb.reset()
        elif op == "frames":
            for index in step["frames"]:
                await tb.send_lines(_lines(data[f"in{index}"].tolist(), width))
            for index in step["frames"]:
                got = await tb.receive(pixels, quiet)
                comparison = compare_frame(data[f"out{index}"], *got, params)
                records.append({"label": f"{label} frame {index}",
                                "comparison": comparison.to_dict()})
        elif op == "abort":
            # Part of a frame, then a reset in the middle of it.
            words = data[f"in{step['frame']}"].tolist()
            await tb.send_lines(_lines(words[:step["lines"] * width], width))
            await tb.source.wait()
            await tb.reset()
        elif op == "misframed":
            words = _lines(data[f"in{step['frame']}"].tolist(), width)
            line, delta = step["line"], step["delta"]
            words[line] = words[line][:width + delta] if delta < 0 else \
                words[line] + words[line][:delta]
            await tb.send_lines(words)
            good = step["good"]
            await tb.send_lines(_lines(data[f"in{good}"].tolist(), width))
            got = await tb.receive(None, quiet)
            # Whatever the core made of the broken frame, the good one comes last.
            tail = [column[-pixels:] for column in got]
            comparison = compare_frame(data[f"out{good}"], *tail, params)
            records.append({"label": f"{label} frame {good} after a line of "
                            f"{width + delta} pixels", "comparison": comparison.to_dict()})
        else:
            raise ValueError(f"unknown plan step {op!r}")
    _finish(run_dir, plan, records)


def _read_memh(path, count):
    values = []
    for line in path.read_text().splitlines():
        # Icarus writes "// 0x..." address comments, Verilator may write "@" addresses.
        word = line.split("//")[0].strip()
        if not word or word.startswith("@"):
            continue
        values.append(int(word, 16) if all(c in "0123456789abcdefABCDEF" for c in word)
                      else -1)
        if len(values) == count:
            break
    return np.array(values, dtype=np.int64)


@cocotb.test()
async def harness_test(dut):
    """One whole frame through the Verilog harness, which clocks and resets itself; cocotb
    only supervises."""
    run_dir, plan, params, data = _load_plan()
    pixels = params.width * params.height
    period = plan["period_ns"]
    dut.dump.value = 0
    # The harness's registers hold X until its reset has passed.
    await Timer((plan["reset_cycles"] + 1) * period, unit="ns")
    progress = run_dir / plan["progress"]
    chunk = plan["progress_cycles"]
    waited = 0
    while not int(dut.done.value) and waited < plan["timeout_cycles"]:
        await First(RisingEdge(dut.done), Timer(chunk * period, unit="ns"))
        waited += chunk
        progress.write_text(str(int(dut.received.value)))
    received = int(dut.received.value)
    progress.write_text(str(received))
    dut.dump.value = 1
    await Timer(2 * period, unit="ns")
    records = _read_memh(run_dir / "resp.hex", min(received, pixels))
    got, tuser, tlast = WordCodec(params).unpack_beats(records)
    comparison = compare_frame(data["out0"], got, tuser, tlast, params)
    np.save(run_dir / "disparity.npy", decode_map(got, params))
    if received > pixels:
        comparison.framing.append(f"received {received} output pixels, expected {pixels}")
    cycles = int(dut.last_out.value) - int(dut.first_in.value) + 1
    _finish(run_dir, plan, [{"label": "frame 0", "comparison": comparison.to_dict()}],
            {"cycles": cycles, "received": received})
