"""Logic levels of the worst register-to-register path (``npstereo.gen.flow.logic_depth``).

Small designs whose depth is known: a register feeding a register (0 levels), one gate
(1 level), an adder (one level plus its carry chain), XOR trees whose depth grows with
their width; a deep path that starts at a top-level input must not count. The counting
rules are also checked on hand-written netlists, where every number is exact.
"""

import pytest

from npstereo.gen.flow.logic_depth import CARRY_WEIGHT, logic_depth
from npstereo.gen.flow.synthesise import synthesise

TARGETS = ["cyclonev", "ecp5"]


def _registered(body, inputs, width=1):
    """A module whose inputs are registered, then ``body`` computes ``y`` into a register."""
    regs = "\n".join(f"  reg [{width - 1}:0] {name}_r = 0;" for name in inputs)
    loads = "\n".join(f"    {name}_r <= {name};" for name in inputs)
    ports = ", ".join(f"input [{width - 1}:0] {name}" for name in inputs)
    return f"""
module top(input clk, {ports}, input [255:0] wide, output reg [{width - 1}:0] y, output reg z);
{regs}
  always @(posedge clk) begin
{loads}
    y <= {body};
    z <= ^wide;   // deep, but from top-level inputs: not a register-to-register path
  end
endmodule
"""


def _levels(verilog, target):
    result = synthesise(verilog, target, "top")
    assert result["status"] == "ok", result
    return result


@pytest.mark.parametrize("target", TARGETS)
def test_register_to_register_is_zero_levels(target):
    result = _levels(_registered("a_r", ["a"]), target)
    assert result["logic_levels"] == 0
    assert "a_r" in result["logic_levels_path"]["from"]


@pytest.mark.parametrize("target", TARGETS)
def test_one_gate_is_one_level(target):
    result = _levels(_registered("a_r & b_r", ["a", "b"]), target)
    assert result["logic_levels"] == 1
    path = result["logic_levels_path"]
    assert path["luts"] == 1 and path["carry_cells"] == 0
    assert path["to"].startswith("y")


@pytest.mark.parametrize("target", TARGETS)
def test_adder_counts_its_carry_chain_as_a_fraction(target):
    result = _levels(_registered("a_r + b_r", ["a", "b"], width=32), target)
    path = result["logic_levels_path"]
    assert path["luts"] == 1 and path["carry_cells"] > 8
    assert result["logic_levels"] == round(1 + path["carry_cells"] * CARRY_WEIGHT[target], 1)
    assert 1.5 <= result["logic_levels"] < 3


@pytest.mark.parametrize("target", TARGETS)
def test_wider_xor_tree_is_deeper(target):
    """Broken variant of 'depth': a 256-input XOR must be deeper than an 8-input one."""
    narrow = _levels(_registered("^a_r", ["a"], width=8).replace(
        "output reg [7:0] y", "output reg y"), target)
    wide = _levels(_registered("^a_r", ["a"], width=256).replace(
        "output reg [255:0] y", "output reg y"), target)
    assert 1 <= narrow["logic_levels"] <= 2
    assert wide["logic_levels"] >= narrow["logic_levels"] + 2   # log_6(256) > 3
    assert wide["logic_levels"] <= 6


def _cell(kind, connections, directions):
    return {"type": kind, "parameters": {}, "attributes": {}, "connections": connections,
            "port_directions": directions}


def _ff(d, q):
    return _cell("TRELLIS_FF", {"CLK": [2], "DI": [d], "Q": [q]},
                 {"CLK": "input", "DI": "input", "Q": "output"})


def _lut(inputs, z):
    ports = dict(zip("ABCD", [[bit] for bit in inputs]))
    return _cell("LUT4", {**ports, "Z": [z]}, {**{p: "input" for p in ports}, "Z": "output"})


def _ccu2c(a0, cin, s0, cout):
    return _cell("CCU2C", {"A0": [a0], "CIN": [cin], "S0": [s0], "COUT": [cout]},
                 {"A0": "input", "CIN": "input", "S0": "output", "COUT": "output"})


def _netlist(cells, inputs=(2,)):
    return {"modules": {"top": {"attributes": {"top": "00000000000000000000000000000001"},
                                "ports": {"in": {"direction": "input", "bits": list(inputs)}},
                                "cells": cells}}}


def test_hand_netlist_lut_chain_and_carry():
    """FF 10 -> LUT -> LUT -> FF, and FF 20 -> 4 carry cells -> FF: exact counts."""
    cells = {"r0": _ff(3, 10), "l1": _lut([10], 11), "l2": _lut([11, 10], 12),
             "r1": _ff(12, 13), "r2": _ff(4, 20)}
    # carry chain: entered at c0's A0, three carry hops, sum out of c3
    cells.update({"c0": _ccu2c(20, "0", 30, 31), "c1": _ccu2c("0", 31, 32, 33),
                  "c2": _ccu2c("0", 33, 34, 35), "c3": _ccu2c("0", 35, 36, 37),
                  "r3": _ff(36, 40)})
    depth = logic_depth(_netlist(cells), "ecp5")
    chain = 1 + 3 * CARRY_WEIGHT["ecp5"]
    assert chain < 2
    assert depth["levels"] == 2 and depth["luts"] == 2
    assert depth["from"] == "r0 (TRELLIS_FF.Q)" and depth["to"] == "r1 (TRELLIS_FF.DI)"
    assert depth["cells"] == ["l1", "l2"]
    # a longer chain overtakes the two LUTs: 1 + 31 hops x 0.071 = 3.2 levels
    previous = 37
    for index in range(4, 32):
        cells[f"c{index}"] = _ccu2c("0", previous, 100 + index, 200 + index)
        previous = 200 + index
    cells["r3"] = _ff(100 + 31, 40)
    longer = logic_depth(_netlist(cells), "ecp5")
    assert longer["carry_cells"] == 31 and longer["luts"] == 1
    assert longer["levels"] == round(1 + 31 * CARRY_WEIGHT["ecp5"], 1) > 2
    assert longer["to"] == "r3 (TRELLIS_FF.DI)"


def test_hand_netlist_paths_from_inputs_are_ignored():
    """A LUT chain fed only by a top-level input (bit 2 here is both) does not count."""
    cells = {"l1": _lut([5], 6), "l2": _lut([6], 7), "l3": _lut([7], 8), "r": _ff(8, 9)}
    netlist = _netlist(cells, inputs=(5,))
    assert logic_depth(netlist, "ecp5")["levels"] is None
    cells["r0"] = _ff(5, 50)
    cells["l1"] = _lut([50], 6)
    assert logic_depth(netlist, "ecp5")["levels"] == 3
