"""cocotb test module run inside Verilator by :func:`.verify.capture_verilator`.

The harness clocks, resets and captures by itself; this test waits for its ``done`` (a
whole frame after the first map), writing the pixels captured so far now and then, has it
dump the frame (``frame.hex``) and writes the frame's figures to ``result.json``.
"""

import json
import os
from pathlib import Path

import cocotb
from cocotb.triggers import First, RisingEdge, Timer


@cocotb.test()
async def frame_test(dut):
    plan_path = Path(os.environ["NPSTEREO_BOARD_PLAN"])
    plan = json.loads(plan_path.read_text())
    period, chunk = plan["period_ns"], plan["chunk_cycles"]
    dut.dump.value = 0
    await Timer(8 * period, unit="ns")
    waited = 0
    while not int(dut.done.value) and waited < plan["timeout_cycles"]:
        await First(RisingEdge(dut.done), Timer(chunk * period, unit="ns"))
        waited += chunk
        (plan_path.parent / "progress.txt").write_text(str(int(dut.captured.value)))
    assert int(dut.done.value), f"no whole frame after {waited} clocks"
    dut.dump.value = 1
    await Timer(2 * period, unit="ns")
    figures = {"captured": int(dut.captured.value), "frame_clocks": int(dut.frame_clocks.value),
               "hsyncs": int(dut.hsyncs.value), "cycles": int(dut.cycle.value)}
    (plan_path.parent / "result.json").write_text(json.dumps(figures))
