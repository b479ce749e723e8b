// Behavioural model of the ECP5 DP16KD block RAM, for simulating synthesised netlists
// (npstereo cosim --netlist ecp5, tests/test_outreg.py, tests/test_dp16kd_model.py).
//
// Why this file exists: the DP16KD of Yosys 0.70 (share/lattice/cells_sim_ecp5.v, and the
// older share/ecp5/cells_sim.v) is an empty module with the parameter list only, so a
// mapped netlist cannot be simulated with Yosys's models alone. This model follows
// Lattice's DP16KD description (TN1264, ECP5 and ECP5-5G Memory Usage Guide) and what
// Yosys's mapping assumes of the cell (share/lattice/brams_16kd.txt, brams_map_16kd.v):
//   - one array of 18,432 bits. At widths 9, 18 and 36 a word of width w at word address
//     a is bits [a*w, a*w+w) (AD[13:3], AD[13:4], AD[13:5]); at widths 1, 2 and 4 the
//     9th bits are not addressable and a word is bit [a*w, a*w+w) of 16,384 data bits
//     (AD[13:0], AD[13:1], AD[13:2]). Mixing a narrow (1/2/4) port with a 9/18/36 one
//     stops the simulation: the two address maps are not modelled against each other.
//   - writes: at width 18 AD[1:0] are the byte enables of the two 9-bit halves, at
//     width 36 (port A writing DIA and DIB) AD[3:0] those of the four quarters;
//   - the array output ("latch") is loaded on the port's clock edge when CEx is high:
//     the addressed word when reading; when writing, per WRITEMODE_x, unchanged
//     (NORMAL, Yosys "rdwr no_change"), the word after the write (WRITETHROUGH, "new") or
//     before it (READBEFOREWRITE, "old"); RSTx (synchronous) clears it;
//   - REGMODE_x = "OUTREG" adds the output register: on the same clock edge, when OCEx is
//     high, it loads the latch's previous value (one more cycle of latency); RSTx clears it;
//   - DATA_WIDTH_B = 36 (pseudo dual port, 36-bit read on B): DOA carries the lower and
//     DOB the upper half of the word, both registered by CLKB/OCEB, REGMODE_A/REGMODE_B
//     selecting register or latch for DOA/DOB. DATA_WIDTH_A = 36 is a 36-bit write on A;
//   - a write on one port and a read of the same word on the other in the same clock
//     returns the old word (Lattice leaves it undefined; Yosys does not rely on it).
// Anything else (chip selects in use, an asynchronous reset that is used, a non-zero
// INITVAL, a 36-bit read on A or write on B) stops the simulation with $fatal instead of
// giving silently wrong data.
`timescale 1ns/1ps
module DP16KD(
  input DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6, DIA5, DIA4, DIA3, DIA2, DIA1, DIA0,
  input ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0,
  input CEA, OCEA, CLKA, WEA, RSTA,
  input CSA2, CSA1, CSA0,
  output DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6, DOA5, DOA4, DOA3, DOA2, DOA1, DOA0,
  input DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6, DIB5, DIB4, DIB3, DIB2, DIB1, DIB0,
  input ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0,
  input CEB, OCEB, CLKB, WEB, RSTB,
  input CSB2, CSB1, CSB0,
  output DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6, DOB5, DOB4, DOB3, DOB2, DOB1, DOB0
);
  parameter DATA_WIDTH_A = 18;
  parameter DATA_WIDTH_B = 18;
  parameter REGMODE_A = "NOREG";
  parameter REGMODE_B = "NOREG";
  parameter RESETMODE = "SYNC";
  parameter ASYNC_RESET_RELEASE = "SYNC";
  parameter CSDECODE_A = "0b000";
  parameter CSDECODE_B = "0b000";
  parameter WRITEMODE_A = "NORMAL";
  parameter WRITEMODE_B = "NORMAL";
  parameter CLKAMUX = "CLKA";
  parameter CLKBMUX = "CLKB";
  parameter OCEAMUX = "OCEA";
  parameter OCEBMUX = "OCEB";
  parameter RSTAMUX = "RSTA";
  parameter RSTBMUX = "RSTB";
  parameter WEAMUX = "WEA";
  parameter WEBMUX = "WEB";
  parameter GSR = "ENABLED";
  parameter WID = 0;
  parameter INIT_DATA = "STATIC";
  parameter INITVAL_00 = 320'h0;
  parameter INITVAL_01 = 320'h0;
  parameter INITVAL_02 = 320'h0;
  parameter INITVAL_03 = 320'h0;
  parameter INITVAL_04 = 320'h0;
  parameter INITVAL_05 = 320'h0;
  parameter INITVAL_06 = 320'h0;
  parameter INITVAL_07 = 320'h0;
  parameter INITVAL_08 = 320'h0;
  parameter INITVAL_09 = 320'h0;
  parameter INITVAL_0A = 320'h0;
  parameter INITVAL_0B = 320'h0;
  parameter INITVAL_0C = 320'h0;
  parameter INITVAL_0D = 320'h0;
  parameter INITVAL_0E = 320'h0;
  parameter INITVAL_0F = 320'h0;
  parameter INITVAL_10 = 320'h0;
  parameter INITVAL_11 = 320'h0;
  parameter INITVAL_12 = 320'h0;
  parameter INITVAL_13 = 320'h0;
  parameter INITVAL_14 = 320'h0;
  parameter INITVAL_15 = 320'h0;
  parameter INITVAL_16 = 320'h0;
  parameter INITVAL_17 = 320'h0;
  parameter INITVAL_18 = 320'h0;
  parameter INITVAL_19 = 320'h0;
  parameter INITVAL_1A = 320'h0;
  parameter INITVAL_1B = 320'h0;
  parameter INITVAL_1C = 320'h0;
  parameter INITVAL_1D = 320'h0;
  parameter INITVAL_1E = 320'h0;
  parameter INITVAL_1F = 320'h0;
  parameter INITVAL_20 = 320'h0;
  parameter INITVAL_21 = 320'h0;
  parameter INITVAL_22 = 320'h0;
  parameter INITVAL_23 = 320'h0;
  parameter INITVAL_24 = 320'h0;
  parameter INITVAL_25 = 320'h0;
  parameter INITVAL_26 = 320'h0;
  parameter INITVAL_27 = 320'h0;
  parameter INITVAL_28 = 320'h0;
  parameter INITVAL_29 = 320'h0;
  parameter INITVAL_2A = 320'h0;
  parameter INITVAL_2B = 320'h0;
  parameter INITVAL_2C = 320'h0;
  parameter INITVAL_2D = 320'h0;
  parameter INITVAL_2E = 320'h0;
  parameter INITVAL_2F = 320'h0;
  parameter INITVAL_30 = 320'h0;
  parameter INITVAL_31 = 320'h0;
  parameter INITVAL_32 = 320'h0;
  parameter INITVAL_33 = 320'h0;
  parameter INITVAL_34 = 320'h0;
  parameter INITVAL_35 = 320'h0;
  parameter INITVAL_36 = 320'h0;
  parameter INITVAL_37 = 320'h0;
  parameter INITVAL_38 = 320'h0;
  parameter INITVAL_39 = 320'h0;
  parameter INITVAL_3A = 320'h0;
  parameter INITVAL_3B = 320'h0;
  parameter INITVAL_3C = 320'h0;
  parameter INITVAL_3D = 320'h0;
  parameter INITVAL_3E = 320'h0;
  parameter INITVAL_3F = 320'h0;
  localparam INIT_NONZERO =
    INITVAL_00 != 0 || INITVAL_01 != 0 || INITVAL_02 != 0 || INITVAL_03 != 0 ||
    INITVAL_04 != 0 || INITVAL_05 != 0 || INITVAL_06 != 0 || INITVAL_07 != 0 ||
    INITVAL_08 != 0 || INITVAL_09 != 0 || INITVAL_0A != 0 || INITVAL_0B != 0 ||
    INITVAL_0C != 0 || INITVAL_0D != 0 || INITVAL_0E != 0 || INITVAL_0F != 0 ||
    INITVAL_10 != 0 || INITVAL_11 != 0 || INITVAL_12 != 0 || INITVAL_13 != 0 ||
    INITVAL_14 != 0 || INITVAL_15 != 0 || INITVAL_16 != 0 || INITVAL_17 != 0 ||
    INITVAL_18 != 0 || INITVAL_19 != 0 || INITVAL_1A != 0 || INITVAL_1B != 0 ||
    INITVAL_1C != 0 || INITVAL_1D != 0 || INITVAL_1E != 0 || INITVAL_1F != 0 ||
    INITVAL_20 != 0 || INITVAL_21 != 0 || INITVAL_22 != 0 || INITVAL_23 != 0 ||
    INITVAL_24 != 0 || INITVAL_25 != 0 || INITVAL_26 != 0 || INITVAL_27 != 0 ||
    INITVAL_28 != 0 || INITVAL_29 != 0 || INITVAL_2A != 0 || INITVAL_2B != 0 ||
    INITVAL_2C != 0 || INITVAL_2D != 0 || INITVAL_2E != 0 || INITVAL_2F != 0 ||
    INITVAL_30 != 0 || INITVAL_31 != 0 || INITVAL_32 != 0 || INITVAL_33 != 0 ||
    INITVAL_34 != 0 || INITVAL_35 != 0 || INITVAL_36 != 0 || INITVAL_37 != 0 ||
    INITVAL_38 != 0 || INITVAL_39 != 0 || INITVAL_3A != 0 || INITVAL_3B != 0 ||
    INITVAL_3C != 0 || INITVAL_3D != 0 || INITVAL_3E != 0 || INITVAL_3F != 0;

  wire [17:0] dia = {DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6, DIA5, DIA4, DIA3, DIA2, DIA1, DIA0};
  wire [17:0] dib = {DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6, DIB5, DIB4, DIB3, DIB2, DIB1, DIB0};
  wire [13:0] ada = {ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0};
  wire [13:0] adb = {ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0};

  wire clka = (CLKAMUX == "INV") ? ~CLKA : CLKA;
  wire clkb = (CLKBMUX == "INV") ? ~CLKB : CLKB;
  wire ocea = (OCEAMUX == "INV") ? ~OCEA : OCEA;
  wire oceb = (OCEBMUX == "INV") ? ~OCEB : OCEB;
  wire rsta = (RSTAMUX == "INV") ? ~RSTA : RSTA;
  wire rstb = (RSTBMUX == "INV") ? ~RSTB : RSTB;
  wire wea = (WEAMUX == "INV") ? ~WEA : WEA;
  wire web = (WEBMUX == "INV") ? ~WEB : WEB;

  function automatic narrow(input integer width);
    narrow = width == 1 || width == 2 || width == 4;
  endfunction

  function automatic integer log2w(input integer width);
    log2w = width == 1 ? 0 : width == 2 ? 1 : width == 4 ? 2 : width == 9 ? 3 :
            width == 18 ? 4 : 5;
  endfunction

  // First bit of the addressed word; the word address is AD[13:log2(width)].
  function automatic integer base(input integer width, input [13:0] ad);
    base = (ad >> log2w(width)) * width;
  endfunction

  // The byte (9-bit lane) enables of a write: one per 9 bits at widths 18 and 36.
  function automatic [3:0] lanes(input integer width, input [13:0] ad);
    lanes = width == 18 ? {2'b00, ad[1:0]} : width == 36 ? ad[3:0] : 4'b1111;
  endfunction

  reg mem [0:18431];
  reg [35:0] latch_a = 0, latch_b = 0, out_a = 0, out_b = 0;
  integer i;

  initial begin
    if (!((DATA_WIDTH_A == 1 || DATA_WIDTH_A == 2 || DATA_WIDTH_A == 4 || DATA_WIDTH_A == 9 ||
           DATA_WIDTH_A == 18 || DATA_WIDTH_A == 36) &&
          (DATA_WIDTH_B == 1 || DATA_WIDTH_B == 2 || DATA_WIDTH_B == 4 || DATA_WIDTH_B == 9 ||
           DATA_WIDTH_B == 18 || DATA_WIDTH_B == 36)))
      $fatal(1, "DP16KD model: DATA_WIDTH_A=%0d DATA_WIDTH_B=%0d not a DP16KD width",
             DATA_WIDTH_A, DATA_WIDTH_B);
    if (narrow(DATA_WIDTH_A) != narrow(DATA_WIDTH_B))
      $fatal(1, "DP16KD model: widths %0d and %0d mix the two address maps (not modelled)",
             DATA_WIDTH_A, DATA_WIDTH_B);
    if (CSDECODE_A != "0b000" || CSDECODE_B != "0b000")
      $fatal(1, "DP16KD model: only unused chip selects are modelled");
    if (INIT_NONZERO)
      $fatal(1, "DP16KD model: INITVAL is not modelled (the array starts at zero)");
    // Non-blocking like every other write of the array (Verilator: no BLKANDNBLK).
    for (i = 0; i < 18432; i = i + 1) mem[i] <= 1'b0;
  end

  // The asynchronous reset is not modelled: a netlist that uses it stops the simulation.
  always @(posedge RSTA, posedge RSTB)
    if (RESETMODE != "SYNC") $fatal(1, "DP16KD model: RESETMODE ASYNC with a reset in use");
  always @(posedge CSA0, posedge CSA1, posedge CSA2, posedge CSB0, posedge CSB1, posedge CSB2)
    $fatal(1, "DP16KD model: chip select in use");

  // One port's clock edge. The array is written with non-blocking assignments, so that
  // the other port, on the same edge, reads the old word whichever block runs first.
  task automatic port_edge(input integer width, input [13:0] ad, input [35:0] di,
                           input ce, input we, input rst, input [8*16-1:0] writemode,
                           input oce, inout [35:0] latch, inout [35:0] out);
    integer b, k;
    reg [35:0] old, merged;
    reg [3:0] en;
    begin
      if (oce) out = rst ? 36'd0 : latch;
      b = base(width, ad);
      en = lanes(width, ad);
      old = 0;
      for (k = 0; k < width; k = k + 1) old[k] = mem[b + k];
      merged = old;
      for (k = 0; k < width; k = k + 1)
        if (en[k / 9]) merged[k] = di[k];
      if (rst) latch = 0;
      else if (ce) begin
        if (we) begin
          for (k = 0; k < width; k = k + 1) mem[b + k] <= merged[k];
          if (writemode == "WRITETHROUGH") latch = merged;
          else if (writemode == "READBEFOREWRITE") latch = old;
        end else latch = old;
      end
    end
  endtask

  always @(posedge clka) begin : port_a
    reg [35:0] latch, out;
    if (DATA_WIDTH_A == 36 && CEA && !wea)
      $fatal(1, "DP16KD model: 36-bit read on port A does not exist");
    latch = latch_a;
    out = out_a;
    port_edge(DATA_WIDTH_A, ada, {dib, dia}, CEA, wea, rsta, WRITEMODE_A, ocea, latch, out);
    latch_a <= latch;
    out_a <= out;
  end

  always @(posedge clkb) begin : port_b
    reg [35:0] latch, out;
    if (DATA_WIDTH_B == 36 && CEB && web)
      $fatal(1, "DP16KD model: 36-bit write on port B is not modelled");
    latch = latch_b;
    out = out_b;
    port_edge(DATA_WIDTH_B, adb, {18'd0, dib}, CEB, web, rstb, WRITEMODE_B, oceb, latch, out);
    latch_b <= latch;
    out_b <= out;
  end

  // A 36-bit read on B drives DOA with its lower half (register or latch per REGMODE_A).
  wire [35:0] word_b = (REGMODE_B == "OUTREG") ? out_b : latch_b;
  wire [35:0] low_b = (REGMODE_A == "OUTREG") ? out_b : latch_b;
  wire [17:0] doa = DATA_WIDTH_B == 36 ? low_b[17:0]
                                       : ((REGMODE_A == "OUTREG") ? out_a[17:0] : latch_a[17:0]);
  wire [17:0] dob = DATA_WIDTH_B == 36 ? word_b[35:18] : word_b[17:0];
  assign {DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6, DOA5, DOA4, DOA3, DOA2, DOA1, DOA0} = doa;
  assign {DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6, DOB5, DOB4, DOB3, DOB2, DOB1, DOB0} = dob;
endmodule
