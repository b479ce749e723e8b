// Behavioural model of the ECP5 DP16KD block RAM, for simulating synthesised netlists.
//
// Why this file exists: the DP16KD in Yosys 0.70's share/lattice/cells_sim_ecp5.v (and
// share/ecp5/cells_sim.v) is an empty module with the parameter list only, so it cannot
// show what REGMODE/OCE do. This model follows the behaviour of Lattice's DP16KD
// simulation model and TN1264 (ECP5 Memory Usage Guide):
//   - the array output ("latch") is loaded on the port's clock edge when CEx is high and the
//     port is not writing (WRITEMODE NORMAL), cleared by RSTx (synchronous RESETMODE; an
//     asynchronous reset that is used stops the simulation);
//   - REGMODE_x = "OUTREG" adds the output register: on the same clock edge, when OCEx is
//     high, it loads the latch's previous value (one more cycle of latency), cleared by RSTx;
//   - with DATA_WIDTH_B = 36 (pseudo dual port, read on B) the DOA pins carry the lower and
//     DOB the upper half of the 36-bit word; both halves are registered by CLKB/OCEB and
//     REGMODE_A/REGMODE_B select register or latch for DOA/DOB.
// Only the modes Yosys's brams_map_16kd.v produces for 9-, 18- and 36-bit words are
// modelled (DATA_WIDTH 9 or 18 on both ports, or 36 on both, chip selects unused); any other configuration stops
// the simulation with $fatal instead of giving silently wrong data. INITVAL is not
// modelled: the array starts at zero, and a design whose memory has another initial
// content must not be checked with this model.
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
  parameter GSR = "ENABLED";
  parameter WID = 0;
  parameter INIT_DATA = "STATIC";

  wire [17:0] dia = {DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6, DIA5, DIA4, DIA3, DIA2, DIA1, DIA0};
  wire [17:0] dib = {DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6, DIB5, DIB4, DIB3, DIB2, DIB1, DIB0};
  wire [13:0] ada = {ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0};
  wire [13:0] adb = {ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0};

  wire clka = (CLKAMUX == "INV") ? ~CLKA : CLKA;
  wire clkb = (CLKBMUX == "INV") ? ~CLKB : CLKB;
  wire ocea = (OCEAMUX == "INV") ? ~OCEA : OCEA;
  wire oceb = (OCEBMUX == "INV") ? ~OCEB : OCEB;

  localparam WIDE = (DATA_WIDTH_A == 36) || (DATA_WIDTH_B == 36);

  reg [17:0] rows [0:1023];   // 9- and 18-bit modes: 1024 rows of two 9-bit halves
  reg [35:0] words [0:511];   // 36-bit mode
  reg [17:0] latch_a = 0, latch_b = 0, out_a = 0, out_b = 0;
  reg [35:0] latch_w = 0, out_w = 0;
  integer i;

  initial begin
    if (!((DATA_WIDTH_A == 36 && DATA_WIDTH_B == 36) ||
          ((DATA_WIDTH_A == 9 || DATA_WIDTH_A == 18) && (DATA_WIDTH_B == 9 || DATA_WIDTH_B == 18))))
      $fatal(1, "DP16KD model: DATA_WIDTH_A=%0d DATA_WIDTH_B=%0d not modelled", DATA_WIDTH_A, DATA_WIDTH_B);
    if (CSDECODE_A != "0b000" || CSDECODE_B != "0b000")
      $fatal(1, "DP16KD model: only unused chip selects are modelled");
    for (i = 0; i < 1024; i = i + 1) rows[i] = 0;
    for (i = 0; i < 512; i = i + 1) words[i] = 0;
  end

  // One port of the 9/18-bit array: write (byte enables on AD[1:0] at width 18, half AD[3]
  // at width 9), or read into the port's latch (WRITEMODE NORMAL: no read while writing).
  task automatic port_cycle(input integer width, input [13:0] ad, input [17:0] di,
                            input we, inout [17:0] latch);
    begin
      if (we) begin
        if (width == 18) begin
          if (ad[0]) rows[ad[13:4]][8:0] = di[8:0];
          if (ad[1]) rows[ad[13:4]][17:9] = di[17:9];
        end else if (ad[3]) rows[ad[13:4]][17:9] = di[8:0];
        else rows[ad[13:4]][8:0] = di[8:0];
      end else begin
        if (width == 18) latch = rows[ad[13:4]];
        else latch = {9'd0, ad[3] ? rows[ad[13:4]][17:9] : rows[ad[13:4]][8:0]};
      end
    end
  endtask

  // Asynchronous reset is not modelled: a netlist that uses it stops the simulation.
  always @(posedge RSTA, posedge RSTB)
    if (RESETMODE != "SYNC") $fatal(1, "DP16KD model: RESETMODE ASYNC with a reset in use");

  always @(posedge clka) begin
    if (!WIDE) begin
      // Non-blocking: the output register takes the latch value from before this edge.
      if (ocea) out_a <= RSTA ? 18'd0 : latch_a;
      if (RSTA) latch_a <= 0;
      else if (CEA) begin : a_port
        reg [17:0] next;
        next = latch_a;
        port_cycle(DATA_WIDTH_A, ada, dia, WEA, next);
        latch_a <= next;
      end
    end else if (CEA && WEA) begin
      // 36-bit write: AD[3:0] are the byte enables of the four 9-bit quarters.
      if (ada[0]) words[ada[13:5]][8:0] <= dia[8:0];
      if (ada[1]) words[ada[13:5]][17:9] <= dia[17:9];
      if (ada[2]) words[ada[13:5]][26:18] <= dib[8:0];
      if (ada[3]) words[ada[13:5]][35:27] <= dib[17:9];
    end
  end

  always @(posedge clkb) begin
    if (!WIDE) begin
      if (oceb) out_b <= RSTB ? 18'd0 : latch_b;
      if (RSTB) latch_b <= 0;
      else if (CEB) begin : b_port
        reg [17:0] next;
        next = latch_b;
        port_cycle(DATA_WIDTH_B, adb, dib, WEB, next);
        latch_b <= next;
      end
    end else begin
      if (oceb) out_w <= RSTB ? 36'd0 : latch_w;
      if (RSTB) latch_w <= 0;
      else if (CEB) latch_w <= words[adb[13:5]];
    end
  end

  wire [17:0] doa = WIDE ? ((REGMODE_A == "OUTREG") ? out_w[17:0] : latch_w[17:0])
                         : ((REGMODE_A == "OUTREG") ? out_a : latch_a);
  wire [17:0] dob = WIDE ? ((REGMODE_B == "OUTREG") ? out_w[35:18] : latch_w[35:18])
                         : ((REGMODE_B == "OUTREG") ? out_b : latch_b);
  assign {DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6, DOA5, DOA4, DOA3, DOA2, DOA1, DOA0} = doa;
  assign {DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6, DOB5, DOB4, DOB3, DOB2, DOB1, DOB0} = dob;
endmodule
