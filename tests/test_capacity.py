"""ECP5 LFE5U-85F capacity check: utilisation and ``does not fit`` before place and route."""

import time

from npstereo.gen.capacity import ECP5_85K, ecp5_utilisation, fit_message
from npstereo.gen.synth import synthesise


def _result(**counts):
    base = {"logic": 0, "registers": 0, "block_rams": 0, "lut_rams": 0, "dsps": 0}
    return dict(base, **counts)


def test_utilisation_percentages():
    used = ecp5_utilisation(_result(logic=41820, registers=8364, block_rams=52, dsps=78,
                                    lut_rams=10))
    assert used == {"LUT": round(100 * (41820 + 60) / 83640, 1), "FF": 10.0,
                    "DP16KD": 25.0, "DSP": 50.0, "LUTRAM": 0.1}
    assert fit_message(used) is None


def test_over_capacity_names_the_resource():
    used = ecp5_utilisation(_result(logic=93677, block_rams=208))
    assert used["LUT"] == 112.0 and used["DP16KD"] == 100.0
    assert fit_message(used) == "does not fit (112 % LUT)"
    both = ecp5_utilisation(_result(logic=90000, registers=100000))
    assert fit_message(both) == "does not fit (120 % FF, 108 % LUT)"
    # Broken variant: one resource just at capacity fits, one more unit does not.
    assert fit_message(ecp5_utilisation(_result(dsps=ECP5_85K["MULT18X18D"]))) is None
    assert fit_message(ecp5_utilisation(_result(dsps=ECP5_85K["MULT18X18D"] + 1))) \
        == "does not fit (101 % DSP)"


#: 160 independent 18x18 products: 160 MULT18X18D where the 85k has 156.
TOO_MANY_MULTIPLIERS = """
module top(input clk, input [18*160-1:0] a, input [18*160-1:0] b, output reg [36*160-1:0] p);
  integer i;
  always @(posedge clk)
    for (i = 0; i < 160; i = i + 1) p[36*i +: 36] <= a[18*i +: 18] * b[18*i +: 18];
endmodule
"""


def test_design_above_capacity_is_not_placed(tmp_path):
    started = time.monotonic()
    result = synthesise(TOO_MANY_MULTIPLIERS, "ecp5", "top", pnr=True, keep=tmp_path)
    assert result["status"] == "does not fit", result
    assert result["dsps"] == 160 and result["fits"] is False
    assert result["message"] == "does not fit (103 % DSP)"
    assert result["fmax_mhz"] is None
    assert not (tmp_path / "nextpnr.log").exists()      # nextpnr never started
    assert time.monotonic() - started < 120


def test_small_design_fits_and_has_utilisation():
    design = ("module top(input clk, input [7:0] a, output reg [7:0] y);\n"
              "  always @(posedge clk) y <= y + a;\nendmodule\n")
    result = synthesise(design, "ecp5", "top")
    assert result["status"] == "ok" and result["fits"] is True
    assert result["registers"] == 8
    assert result["utilisation"] == ecp5_utilisation(result)
    assert result["utilisation"]["FF"] == round(100 * 8 / 83640, 1)
    cyclone = synthesise(design, "cyclonev", "top")
    assert cyclone["utilisation"] is None and cyclone["fits"] is None
