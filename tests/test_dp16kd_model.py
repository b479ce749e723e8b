"""The DP16KD model of ``npstereo cosim --netlist ecp5`` (``gen/flow/ecp5_dp16kd.v``) against
Yosys's mapping.

Yosys's own DP16KD simulation model is an empty module, so there is nothing of Yosys's to
run the model against directly. What Yosys documents instead is what it assumes of the cell
when it maps a memory onto it (``share/lattice/brams_16kd.txt``: widths 1-36, ``WRITEMODE``
NORMAL = read data unchanged during a write, WRITETHROUGH = the new data, READBEFOREWRITE =
the old; synchronous read reset to zero) and how it drives the pins
(``brams_map_16kd.v``). So each design here is synthesised for the ECP5 by the project's
flow and its netlist, simulated with the model, is compared with the RTL under Icarus on
random stimulus, cycle by cycle (``test_outreg.simulate``): Yosys claims the netlist
equals the RTL, so any difference is the model's (or Yosys's) fault. The netlists are
checked to use the modes in question, before and after the output registers are packed
(``OUTREG``, Lattice TN1264: one more cycle, loaded when ``OCE``).

The memories start at zero in the RTL simulation; Yosys (which defines ``SYNTHESIS``)
does not see those loops, which it would unroll for a minute, and maps memories without
initial contents, whose DP16KD ``INITVAL`` is zero as the model's array.

``WIDTHS`` covers the widths 1, 2, 4 and 9 (test_outreg.py covers 18 and 36), the
output register on three of them and the synchronous reset on the fourth; ``MODES`` the
three write modes. Broken models (write-through returning the old word, the output
register ignoring ``OCE``, a read reversing the bits of the word) must fail.
"""

import json
from pathlib import Path

import pytest

from npstereo.gen.flow.cell_models import DP16KD_MODEL

from test_outreg import _synthesise, simulate

#: Four memories of widths 1, 2, 4 and 9 (one DP16KD each), sharing the address inputs:
#: ``{4{wa}}`` toggles every address pin with 16 distinct words, so reads find data.
WIDTHS = """
module top(input clk, input we, input re, input oe, input rst, input [3:0] wa,
           input [3:0] ra, input [8:0] wd, output reg [15:0] q);
  wire [15:0] wx = {4{wa}};
  wire [15:0] rx = {4{ra}};
  (* no_rw_check, ram_style = "block" *) reg [0:0] m1 [0:16383];
  (* no_rw_check, ram_style = "block" *) reg [1:0] m2 [0:8191];
  (* no_rw_check, ram_style = "block" *) reg [3:0] m4 [0:4095];
  (* no_rw_check, ram_style = "block" *) reg [8:0] m9 [0:2047];
  integer k;
  initial begin
`ifndef SYNTHESIS
    for (k = 0; k < 16384; k = k + 1) m1[k] = 0;
    for (k = 0; k < 8192; k = k + 1) m2[k] = 0;
    for (k = 0; k < 4096; k = k + 1) m4[k] = 0;
    for (k = 0; k < 2048; k = k + 1) m9[k] = 0;
`endif
    q = 0;
  end
  reg [0:0] r1 = 0, d1 = 0;
  reg [1:0] r2 = 0, d2 = 0;
  reg [3:0] r4 = 0, d4 = 0;
  reg [8:0] r9 = 0, d9 = 0;
  always @(posedge clk) begin
    if (we) begin
      m1[wx[13:0]] <= wd[0];
      m2[wx[12:0]] <= wd[1:0];
      m4[wx[11:0]] <= wd[3:0];
      m9[wx[10:0]] <= wd;
    end
    if (re) begin
      r1 <= m1[rx[13:0]];
      r2 <= m2[rx[12:0]];
      r4 <= m4[rx[11:0]];
    end
    if (rst) r9 <= 0;
    else if (re) r9 <= m9[rx[10:0]];
    if (oe) begin
      d1 <= r1;
      d2 <= r2;
      d4 <= r4;
    end
    d9 <= r9;
    q <= {d9, d4, d2, d1};
  end
endmodule
"""

#: Three single-port memories reading the word they write: the old word (read first), the
#: new one (transparent), and nothing (read only when not writing).
MODES = """
module top(input clk, input we, input [3:0] wa, input [8:0] wd,
           output reg [8:0] q_old, output [8:0] q_new, output reg [8:0] q_keep);
  wire [10:0] a = {wa, wa, wa[2:0]};
  (* ram_style = "block" *) reg [8:0] m_old [0:2047];
  (* ram_style = "block" *) reg [8:0] m_new [0:2047];
  (* ram_style = "block" *) reg [8:0] m_keep [0:2047];
  integer k;
  initial begin
`ifndef SYNTHESIS
    for (k = 0; k < 2048; k = k + 1) begin
      m_old[k] = 0;
      m_new[k] = 0;
      m_keep[k] = 0;
    end
`endif
    q_old = 0;
    q_keep = 0;
  end
  reg [10:0] a_new;
  always @(posedge clk) begin
    if (we) m_old[a] <= wd;
    q_old <= m_old[a];
    if (we) m_new[a] <= wd;
    a_new <= a;
    if (we) m_keep[a] <= wd;
    else q_keep <= m_keep[a];
  end
  assign q_new = m_new[a_new];
endmodule
"""

#: Broken models: (design, text of the model, its replacement).
BROKEN = {
    "write-through returns the old word": (
        "modes", 'if (writemode == "WRITETHROUGH") latch = merged;',
        'if (writemode == "WRITETHROUGH") latch = old;'),
    "output register ignores OCE": (
        "widths", "if (oce) out = rst ? 36'd0 : latch;", "out = rst ? 36'd0 : latch;"),
    "a read reverses the bits of the word": (
        "widths", "for (k = 0; k < width; k = k + 1) old[k] = mem[b + k];",
        "for (k = 0; k < width; k = k + 1) old[k] = mem[b + width - 1 - k];"),
}

_DESIGNS = {"widths": WIDTHS, "modes": MODES}


@pytest.fixture(scope="module")
def mapped(tmp_path_factory):
    """``mapped(name)``: the folder where the design was synthesised and packed (once)."""
    folders = {}

    def get(name):
        if name not in folders:
            folder = tmp_path_factory.mktemp(name)
            _synthesise(_DESIGNS[name], folder)
            folders[name] = folder
        return folders[name]
    return get


def _brams(folder, netlist):
    cells = json.loads((Path(folder) / netlist).read_text())["modules"]["top"]["cells"]
    return [cell for cell in cells.values() if cell["type"] == "DP16KD"]


def _value(parameter):
    """A parameter as written by write_json: bit strings as numbers, strings trimmed."""
    text = str(parameter).rstrip()
    return int(text, 2) if text and set(text) <= {"0", "1"} else text


def test_widths_and_output_register(mapped):
    folder = mapped("widths")
    brams = _brams(folder, "netlist.json")
    widths = sorted(_value(cell["parameters"]["DATA_WIDTH_B"]) for cell in brams)
    assert widths == [1, 2, 4, 9], widths
    registered = [cell for cell in brams if "OUTREG" in
                  (_value(cell["parameters"].get(f"REGMODE_{p}", "NOREG")) for p in "AB")]
    assert len(registered) == 3
    assert any(isinstance(bit, int) for cell in brams
               for bit in cell["connections"]["RSTA"] + cell["connections"]["RSTB"])
    for netlist in ("synth.json", "netlist.json"):        # before and after packing
        mismatches, log = simulate(WIDTHS, netlist, folder)
        assert mismatches == 0, log


def test_write_modes(mapped):
    folder = mapped("modes")
    modes = {_value(cell["parameters"].get(f"WRITEMODE_{p}")) for cell in
             _brams(folder, "netlist.json") for p in "AB"}
    assert {"NORMAL", "WRITETHROUGH", "READBEFOREWRITE"} <= modes, modes
    mismatches, log = simulate(MODES, "netlist.json", folder)
    assert mismatches == 0, log


@pytest.mark.parametrize("variant", list(BROKEN))
def test_broken_model_fails(mapped, variant):
    design, text, replacement = BROKEN[variant]
    model = DP16KD_MODEL.read_text()
    assert model.count(text) == 1
    mismatches, _ = simulate(_DESIGNS[design], "netlist.json", mapped(design),
                             model=model.replace(text, replacement))
    assert mismatches > 0
