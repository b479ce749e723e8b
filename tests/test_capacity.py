"""The device table and the capacity check: utilisation and ``does not fit`` (before place
and route for ECP5)."""

import time

import pytest

from npstereo.gen.flow import nextpnr
from npstereo.gen.flow.capacity import DEVICES, device, fit_message, usage, utilisation
from npstereo.gen.flow.synthesise import synthesise


def ecp5_utilisation(result):
    return utilisation(result, "ecp5-85k")


def _result(**counts):
    base = {"logic": 0, "registers": 0, "block_rams": 0, "lut_rams": 0, "dsps": 0,
            "carry_chains": 0}
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
    # One resource just at capacity fits, one more unit does not.
    assert fit_message(ecp5_utilisation(_result(dsps=156))) is None
    assert fit_message(ecp5_utilisation(_result(dsps=157))) == "does not fit (101 % DSP)"


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


#: 40 comparisons of bytes (a carry chain each) and a 16x4 distributed RAM, fed by shift
#: registers so that a few pins do.
CHAINS_AND_LUT_RAM = """
module top(input clk, input [7:0] d, input [3:0] wa, input [3:0] ra, input we,
           output reg y, output reg [3:0] q);
  reg [319:0] a, b;
  reg [39:0] lt;
  reg [3:0] mem [0:15];
  integer i;
  always @(posedge clk) begin
    a <= {a[311:0], d};
    b <= {b[311:0], a[319:312]};
    for (i = 0; i < 40; i = i + 1) lt[i] <= a[8*i +: 8] < b[8*i +: 8];
    y <= ^lt;
    if (we) mem[wa] <= d[3:0];
    q <= mem[ra];
  end
endmodule
"""


def test_lut_count_is_what_nextpnr_packs(tmp_path):
    """The LUT count of the capacity check is nextpnr's TRELLIS_COMB count after packing
    (less its two constant drivers): each carry chain takes four LUT sites more than its
    cells, each DPR16X4 six."""
    result = synthesise(CHAINS_AND_LUT_RAM, "ecp5", "top", pnr=True, freq=50, keep=tmp_path)
    assert result["status"] == "ok", result
    assert result["carry_chains"] == 40 and result["lut_rams"] == 1
    packed = nextpnr._PACKED.search((tmp_path / "place.log").read_text())
    assert 0 <= int(packed.group(1)) - usage(result, DEVICES["ecp5-85k"])["LUT"] <= 2


def test_device_table_has_a_reference_for_every_number():
    assert set(DEVICES) == {"ecp5-85k", "ecp5-45k", "ecp5-25k", "cyclonev-a9", "ep2s180"}
    for dev in DEVICES.values():
        names = [r.name for r in dev.resources]
        assert names[:2] in (["LUT", "FF"], ["ALUT", "FF"])
        assert all(r.capacity > 0 and len(r.reference) > 20 for r in dev.resources)
        assert dev.block_ram_bits > 0
    # The table's numbers agree with each other: blocks x bits per block, the EP2S180's
    # three kinds of memory block, the ECP5 capacity the synthesis flow checks.
    assert DEVICES["ecp5-85k"].block_ram_bits == 208 * 18432
    assert DEVICES["cyclonev-a9"].block_ram_bits == 1220 * 10240
    assert DEVICES["ep2s180"].capacity("RAM bits") == 930 * 576 + 768 * 4608 + 9 * 589824
    assert DEVICES["ecp5-85k"].capacity("LUT") == 41820 * 2          # two LUT4 per slice
    assert [DEVICES[f"ecp5-{s}"].nextpnr for s in ("25k", "45k", "85k")] == \
        ["--25k", "--45k", "--85k"]


def test_unknown_device_is_one_line():
    with pytest.raises(Exception, match="device must be one of ecp5-85k, .*, not 'xc7a35t'"):
        device("xc7a35t")


def test_cyclone_mlab_cells_count_as_aluts():
    """An MLAB is 10 ALMs (20 ALUTs) holding 640 bits: one 32x1 MISTRAL_MLAB per ALUT."""
    used = utilisation(_result(logic=1000, lut_rams=20, block_rams=61, registers=4542),
                       "cyclonev-a9")
    assert used == {"ALUT": round(100 * 1020 / 227120, 1), "FF": 1.0, "M10K": 5.0}
