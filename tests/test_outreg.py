"""ECP5 block-RAM output-register packing (``npstereo.gen.flow.bram_output_register``): proved by simulation.

Each design is synthesised for ECP5, packed, written back to Verilog by Yosys and simulated
with Icarus against its RTL on random stimulus, cycle by cycle, with the cell models of
``npstereo cosim --netlist ecp5``. Yosys's own DP16KD model is an empty module, so the block
RAM is simulated by the project's model (``gen/flow/ecp5_dp16kd.v``, Lattice's REGMODE/OCE
semantics; tests/test_dp16kd_model.py checks it); the unpacked netlist is simulated too, so
a wrong model shows up as a mismatch before packing, not as a wrong verdict about the
packing. A deliberately broken
packing (registers with different enables merged onto one OCE) must fail the comparison.
"""

import json
import re
import subprocess
from pathlib import Path

import pytest

from npstereo.gen.flow import bram_output_register as outreg
from npstereo.gen.flow.cell_models import cell_library
from npstereo.gen.flow.synthesise import synthesise
from npstereo.gen.flow.yosys import run_yosys
from npstereo.sim.tools import require


#: A 16-bit memory (DP16KD at width 18): read enable on the array, its own enable on the
#: data register, then logic, as the core's line buffers are built.
BRAM18 = """
module top(input clk, input we, input re, input oe, input [8:0] wa, input [8:0] ra,
           input [15:0] wd, output reg [15:0] q, output [15:0] raw);
  (* no_rw_check *) reg [15:0] mem [0:511];
  integer k;
  initial for (k = 0; k < 512; k = k + 1) mem[k] = 0;  // the DP16KD model starts at 0
  reg [15:0] rd = 0;
  reg [15:0] data = 0;
  always @(posedge clk) begin
    if (we) mem[wa] <= wd;
    if (re) rd <= mem[ra];
    if (oe) data <= rd;
    q <= data + 16'd1;
  end
  assign raw = data;
endmodule
"""

#: A 36-bit memory: Yosys uses the DP16KD's 36-bit pseudo-dual-port mode, where the DOA
#: pins are the read port B's lower half (registered by CLKB/OCEB, selected by REGMODE_A).
BRAM36 = """
module top(input clk, input we, input re, input [8:0] wa, input [8:0] ra,
           input [35:0] wd, output reg [35:0] q);
  (* no_rw_check *) reg [35:0] mem [0:511];
  integer k;
  initial for (k = 0; k < 512; k = k + 1) mem[k] = 0;
  reg [35:0] rd = 0;
  reg [35:0] data = 0;
  always @(posedge clk) begin
    if (we) mem[wa] <= wd;
    if (re) rd <= mem[ra];
    data <= rd;
    q <= data ^ {data[17:0], data[35:18]};
  end
endmodule
"""

#: The data register's two halves have different enables: one OCE cannot serve both.
SPLIT = BRAM18.replace("input oe,", "input oe, input oe2,").replace(
    "if (oe) data <= rd;", "if (oe) data[7:0] <= rd[7:0];\n    if (oe2) data[15:8] <= rd[15:8];")

#: The data register has a synchronous reset the block RAM's output register lacks.
RESET = BRAM18.replace("if (oe) data <= rd;", "if (oe) data <= rd;\n    if (we & re) data <= 0;")

#: One read bit also feeds logic besides the register.
FANOUT = BRAM18.replace("assign raw = data;", "assign raw = data ^ {15'd0, rd[3]};")


def _synthesise(verilog, folder):
    result = synthesise(verilog, "ecp5", "top", keep=folder)
    assert result["status"] == "ok", result
    return result


def _netlist_verilog(folder, netlist, name):
    """The JSON netlist as Verilog (module ``name``), written by Yosys."""
    failure = run_yosys(f"read_json {netlist}\nrename top {name}\n"
                        f"write_verilog -noattr {name}.v\n", folder, name=f"write_{name}")
    assert failure is None, failure
    return Path(folder) / f"{name}.v"


def _testbench(ports, cycles, seed):
    """Random stimulus for both designs, outputs compared after every clock edge.

    Reads of the address written in the same cycle are avoided: the memories are
    ``no_rw_check``, so that case is left undefined by the design on purpose.
    """
    inputs = [(name, width) for name, width, direction in ports if direction == "input"
              and name != "clk"]
    outputs = [(name, width) for name, width, direction in ports if direction == "output"]
    lines = ["`timescale 1ns/1ps", "module tb;", "  reg clk = 0;", "  integer i, errors = 0;",
             f"  integer seed = {seed};"]
    for name, width in inputs:
        lines.append(f"  reg [{width - 1}:0] {name} = 0;")
    for name, width in outputs:
        lines.append(f"  wire [{width - 1}:0] {name}_rtl, {name}_net;")
    for module, suffix in (("rtl_top", "rtl"), ("net_top", "net")):
        connections = ", ".join([".clk(clk)"] + [f".{n}({n})" for n, _ in inputs] +
                                [f".{n}({n}_{suffix})" for n, _ in outputs])
        lines.append(f"  {module} {suffix}({connections});")
    lines += ["  initial begin", f"    for (i = 0; i < {cycles}; i = i + 1) begin"]
    for name, width in inputs:
        words = (width + 31) // 32
        value = ", ".join(["$random(seed)"] * words)
        lines.append(f"      {name} = {{{value}}};")
    if {"we", "ra", "wa"} <= {name for name, _ in inputs}:
        lines.append("      if (we && ra == wa) ra = ra + 1;")
    lines.append("      #5 clk = 1; #5 clk = 0;")
    for name, _ in outputs:
        lines += [f"      if ({name}_rtl !== {name}_net) begin",
                  "        errors = errors + 1;",
                  f"        if (errors < 5) $display(\"MISMATCH cycle %0d {name}: rtl %h net %h\","
                  f" i, {name}_rtl, {name}_net);",
                  "      end"]
    lines += ["    end", "    $display(\"RESULT %0d mismatches\", errors);", "    $finish;",
              "  end", "endmodule"]
    return "\n".join(lines) + "\n"


def _ports(verilog):
    ports = []
    for direction, width, names in re.findall(
            r"(input|output)\s+(?:reg\s+)?(?:\[(\d+):0\]\s*)?([\w\s,]+?)(?=,\s*(?:input|output)|\);)",
            verilog):
        for name in names.split(","):
            ports.append((name.strip(), int(width or 0) + 1, direction))
    return ports


def simulate(verilog, netlist, folder, cycles=600, seed=7, model=None):
    """Mismatching cycles between the RTL and a JSON netlist of it under random stimulus.

    The cells are those of ``npstereo cosim --netlist ecp5`` (Yosys's ECP5 models and the
    DP16KD model), or ``model`` (Verilog text) instead of the DP16KD model.
    """
    folder = Path(folder)
    rtl = folder / "rtl.v"
    rtl.write_text(verilog.replace("module top(", "module rtl_top("))
    net = _netlist_verilog(folder, netlist, "net_top")
    libraries = cell_library("ecp5")
    if model is not None:
        libraries["dp16kd.v"] = model
    for name, text in libraries.items():
        (folder / name).write_text(text)
    tb = folder / "tb.v"
    tb.write_text(_testbench(_ports(verilog), cycles, seed))
    binary = folder / "sim.vvp"
    subprocess.run([require("iverilog"), "-g2012", "-o", str(binary),
                    str(tb), str(rtl), str(net), *libraries],
                   check=True, capture_output=True, text=True, cwd=folder)
    run = subprocess.run([require("vvp"), "-n", str(binary)], check=True,
                         capture_output=True, text=True, cwd=folder)
    found = re.search(r"RESULT (\d+) mismatches", run.stdout)
    assert found, run.stdout + run.stderr
    return int(found.group(1)), run.stdout


def _regmodes(netlist):
    cells = json.loads(Path(netlist).read_text())["modules"]["top"]["cells"]
    return [(c["parameters"].get("REGMODE_A"), c["parameters"].get("REGMODE_B"))
            for c in cells.values() if c["type"] == "DP16KD"]


@pytest.mark.parametrize("design, width", [(BRAM18, 16), (BRAM36, 36)])
def test_packed_netlist_matches_rtl(tmp_path, design, width):
    result = _synthesise(design, tmp_path)
    assert result["outreg_packed"] >= 1
    assert result["outreg_registers"] == width      # the data register, not the output one
    unpacked, log = simulate(design, "synth.json", tmp_path)
    assert unpacked == 0, log                       # the model and Yosys's mapping agree
    packed, log = simulate(design, "netlist.json", tmp_path)
    assert packed == 0, log
    regmodes = _regmodes(tmp_path / "netlist.json")
    if width == 36:
        assert ("OUTREG", "OUTREG") in regmodes     # DOA is port B's lower half
    else:
        assert any("OUTREG" in pair for pair in regmodes)
    assert f"({width} flip-flops absorbed)" in (tmp_path / "outreg.log").read_text()


def test_registers_with_different_enables_are_left_alone(tmp_path):
    result = _synthesise(SPLIT, tmp_path)
    assert result["outreg_packed"] == 0
    assert result["outreg_not_packed"].get("registers differ in clock or enable") == 1
    mismatches, log = simulate(SPLIT, "netlist.json", tmp_path)
    assert mismatches == 0, log


def test_broken_packing_is_caught(tmp_path, monkeypatch):
    """Broken variant: registers on one clock are taken as equal whatever their enable."""
    _synthesise(SPLIT, tmp_path)
    real, first = outreg._register_signature, {}

    def lenient(ff):
        signature = real(ff)
        return first.setdefault(signature[:2], signature)  # the first register's enable

    monkeypatch.setattr(outreg, "_register_signature", lenient)
    report = outreg.pack_outreg_file(tmp_path / "synth.json", tmp_path / "broken.json")
    assert report["packed"] == 1 and report["registers"] == 16
    mismatches, _ = simulate(SPLIT, "broken.json", tmp_path)
    assert mismatches > 0


@pytest.mark.parametrize("design, reason", [
    (RESET, "register has a set/reset"),
    (FANOUT, "data bit has several loads"),
])
def test_registers_that_differ_are_not_packed(tmp_path, design, reason):
    result = _synthesise(design, tmp_path)
    assert result["outreg_packed"] == 0
    assert result["outreg_not_packed"].get(reason) == 1, result["outreg_not_packed"]
    mismatches, log = simulate(design, "netlist.json", tmp_path)
    assert mismatches == 0, log


def test_packing_raises_fmax_above_150_mhz(tmp_path):
    """nextpnr-ecp5: block RAM -> register -> adder -> register, with and without packing."""
    fmax = {}
    for outreg_on in (False, True):
        result = synthesise(BRAM18, "ecp5", "top", pnr=True, freq=150, outreg=outreg_on,
                            keep=tmp_path / str(outreg_on))
        assert result["status"] == "ok", result
        fmax[outreg_on] = result["fmax_mhz"]
    # Unpacked, the DP16KD's 5.83 ns clock-to-output alone limits the clock.
    assert fmax[False] < 150 <= fmax[True], fmax


def _hand_netlist(**changes):
    """One DP16KD (18-bit read on B) whose DOB0/DOB1 feed two flip-flops, as JSON.

    ``changes`` edit it: ``ff`` (parameters of both flip-flops), ``ff_attributes``,
    ``bram`` (DP16KD parameters), ``bram_pins`` (DP16KD connections), ``extra`` (cells).
    """
    bram = {"type": "DP16KD", "parameters": {"DATA_WIDTH_A": "00000000000000000000000000010010",
                                             "DATA_WIDTH_B": "00000000000000000000000000010010",
                                             "REGMODE_A": "NOREG", "REGMODE_B": "NOREG",
                                             "CLKBMUX": "CLKB", "CSDECODE_B": "0b000"},
            "attributes": {}, "port_directions": {"CLKB": "input", "OCEB": "input",
                                                  "RSTB": "input", "DOB0": "output",
                                                  "DOB1": "output"},
            "connections": {"CLKB": [2], "OCEB": ["1"], "RSTB": ["0"], "DOB0": [10],
                            "DOB1": [11]}}
    bram["parameters"].update(changes.get("bram", {}))
    bram["connections"].update(changes.get("bram_pins", {}))
    cells = {"mem": bram}
    for index, (d, q) in enumerate(((10, 20), (11, 21))):
        cells[f"ff{index}"] = {
            "type": "TRELLIS_FF",
            "parameters": dict({"CEMUX": "CE", "CLKMUX": "CLK", "LSRMUX": "LSR",
                                "REGSET": "RESET", "GSR": "DISABLED"}, **changes.get("ff", {})),
            "attributes": dict(changes.get("ff_attributes", {})),
            "port_directions": {"CLK": "input", "CE": "input", "LSR": "input", "DI": "input",
                                "Q": "output"},
            "connections": {"CLK": [2], "CE": [5], "LSR": ["0"], "DI": [d], "Q": [q]}}
    cells.update(changes.get("extra", {}))
    return {"modules": {"top": {"attributes": {"top": "00000000000000000000000000000001"},
                                "ports": {"q": {"direction": "output", "bits": [20, 21]}},
                                "cells": cells}}}


@pytest.mark.parametrize("changes, reason", [
    ({}, None),
    ({"ff": {"CEMUX": "1"}}, None),
    ({"ff": {"REGSET": "SET"}}, "register initialised to 1"),
    ({"ff": {"CLKMUX": "INV"}}, "register on another clock"),
    ({"ff": {"CEMUX": "INV"}}, "register enable inverted or constant"),
    ({"ff_attributes": {"keep": "00000000000000000000000000000001"}}, "register marked keep"),
    ({"bram_pins": {"RSTB": [7]}}, "read port has a reset"),
    ({"bram_pins": {"CLKB": [3]}}, "register on another clock"),
    ({"bram": {"REGMODE_B": "OUTREG"}}, "port already registered"),
    ({"extra": {"g": {"type": "GSR", "parameters": {}, "attributes": {},
                      "port_directions": {"GSR": "input"}, "connections": {"GSR": [9]}}}},
     "design uses GSR"),
])
def test_hand_netlist_conditions(changes, reason):
    netlist = _hand_netlist(**changes)
    report = outreg.pack_outreg(netlist)
    cells = netlist["modules"]["top"]["cells"]
    if reason is None:
        assert report["packed"] == 1 and report["registers"] == 2
        assert "ff0" not in cells and "ff1" not in cells
        assert cells["mem"]["parameters"]["REGMODE_B"] == "OUTREG"
        assert cells["mem"]["connections"]["DOB0"] == [20]
        enable = "1" if changes.get("ff", {}).get("CEMUX") == "1" else 5
        assert cells["mem"]["connections"]["OCEB"] == [enable]
    else:
        assert report["packed"] == 0
        assert report["not_packed"].get(reason, 0) >= 1, report["not_packed"]
        assert "ff0" in cells and cells["mem"]["connections"]["DOB0"] == [10]
