// npstereo_formal: the AXI4-Stream properties of npstereo_core, for SymbiYosys
// (gen/flow/formal.py writes one .sby per check; docs/verification.md says what each proves).
//
// Plain Verilog-2005 with Yosys's formal extensions (immediate assert/assume in clocked
// blocks, $past, $initstate, anyseq): the harness works on any Verilog with the core's
// ports, the generated core, a netlist, or a deliberately broken wrapper in the tests.
//
// Every input of the core is chosen by the solver each clock (anyseq), within the
// environment that the check's define selects:
//   ENV_FREE       any beats (any tuser, tlast, tvalid), any reset at any time;
//   ENV_FRAMED     well-framed frames of W x H beats: tuser on the first, tlast on x = W-1;
//   ENV_MISFRAMED  as ENV_FRAMED, but each beat may carry one framing fault (below).
// The flip-flops of the core start in any state (gen/flow/formal.py strips their initial
// values): the solver starts from reset applied to an arbitrary state, and may reset again
// at any clock, so every check also covers "reset from any state".
module npstereo_formal #(
    parameter W = 8, parameter H = 4, parameter DW = 8,
    // The largest output value, (D - 1) 2^F (F fractional bits).
    parameter VMAX = 255,
    // Clocks without input, with the sink ready, after which every word must be out.
    parameter QUIET = 128, parameter CW = 10
) (input clk);
    (* anyseq *) wire rst;
    (* anyseq *) wire s_tvalid;
    (* anyseq *) wire [15:0] s_tdata;
    (* anyseq *) wire free_tuser, free_tlast;
    (* anyseq *) wire m_tready;
    (* anyseq *) wire [1:0] fault;

    wire s_tready, m_tvalid, m_tuser, m_tlast, framing_error;
    wire [DW-1:0] m_tdata;
    reg s_tuser, s_tlast;

    npstereo_core dut (
        .clk(clk), .rst(rst),
        .s_axis_tdata(s_tdata), .s_axis_tvalid(s_tvalid), .s_axis_tready(s_tready),
        .s_axis_tuser(s_tuser), .s_axis_tlast(s_tlast),
        .m_axis_tdata(m_tdata), .m_axis_tvalid(m_tvalid), .m_axis_tready(m_tready),
        .m_axis_tuser(m_tuser), .m_axis_tlast(m_tlast), .framing_error(framing_error));

    // The solver starts with a reset: the state before it is arbitrary.
    always @* if ($initstate) assume (rst);

    wire s_beat = s_tvalid && s_tready;
    wire m_beat = m_tvalid && m_tready;

    // The environment's position (ex, ey) in the frame it is sending.
    reg [7:0] ex, ey;
    wire at_start = ex == 0 && ey == 0;
    wire at_last = ex == W - 1;
    // Framing faults (ENV_MISFRAMED): 1 inverts tlast and abandons the frame (the next beat
    // starts a new one); 2 raises tuser inside a frame (a new frame starts there, so the beat
    // is the new frame's first, tlast as at x = 0); 3 drops
    // tuser from a frame's first beat (a beat outside a frame, dropped).
    reg faulty;
    always @* begin
        faulty = 0;
        s_tuser = at_start;
        s_tlast = at_last;
`ifdef ENV_FREE
        s_tuser = free_tuser;
        s_tlast = free_tlast;
`endif
`ifdef ENV_MISFRAMED
        if (fault == 1) begin
            s_tlast = !at_last;
            faulty = 1;
        end else if (fault == 2 && !at_start) begin
            // The first beat of the new frame: its tlast is that of x = 0.
            s_tuser = 1;
            s_tlast = W == 1;
            faulty = 1;
        end else if (fault == 3 && at_start) begin
            s_tuser = 0;
            faulty = 1;
        end
`endif
    end

    // What went in and what came out since the last reset.
    reg [CW-1:0] in_beats, sofs, faults, out_beats, pulses;
    reg [7:0] ox, oy;
    reg [CW-1:0] quiet;
    always @(posedge clk) begin
        if (rst) begin
            ex <= 0; ey <= 0;
            in_beats <= 0; sofs <= 0; faults <= 0; out_beats <= 0; pulses <= 0;
            ox <= 0; oy <= 0; quiet <= 0;
        end else begin
            if (s_beat) begin
                in_beats <= in_beats + 1;
                sofs <= sofs + s_tuser;
                faults <= faults + faulty;
                if (faulty && fault == 1) begin
                    ex <= 0; ey <= 0;
                end else if (faulty && fault == 2) begin
                    ex <= 1; ey <= 0;
                end else if (faulty && fault == 3) begin
                    ex <= 0; ey <= 0;
                end else if (ex == W - 1) begin
                    ex <= 0;
                    ey <= ey == H - 1 ? 0 : ey + 1;
                end else begin
                    ex <= ex + 1;
                end
            end
            if (m_beat) begin
                out_beats <= out_beats + 1;
                if (ox == W - 1) begin
                    ox <= 0;
                    oy <= oy == H - 1 ? 0 : oy + 1;
                end else begin
                    ox <= ox + 1;
                end
            end
            pulses <= pulses + framing_error;
            quiet <= (!s_tvalid && m_tready) ? (quiet == QUIET ? QUIET : quiet + 1) : 0;
        end
    end

    // A clock after a reset the harness's counters are meaningful.
    reg settled;
    always @(posedge clk) settled <= !rst;

    always @(posedge clk) if (settled && !rst) begin
`ifdef CHECK_HOLD
        // The output holds its word while the sink stalls it.
        if ($past(m_tvalid && !m_tready))
            hold: assert (m_tvalid && m_tdata == $past(m_tdata) && m_tuser == $past(m_tuser)
                    && m_tlast == $past(m_tlast));
`endif
`ifdef CHECK_MARKERS
        // tuser on each frame's first word, tlast on each line's last, whatever came in.
        if (m_tvalid)
            markers: assert (m_tuser == (ox == 0 && oy == 0) && m_tlast == (ox == W - 1));
`endif
`ifdef CHECK_WORD_RANGE
        // A valid word's value lies in 0 .. (D - 1) 2^F (a sub-pixel fraction of a winner
        // within half a level, none at the range's ends) and an invalid word's is 0, the
        // bits between the value and the valid flag 0 in both.
        if (m_tvalid)
            word_range: assert (m_tdata[DW-1] ? m_tdata[DW-2:0] <= VMAX : m_tdata[DW-2:0] == 0);
`endif
`ifdef CHECK_NO_SPURIOUS
        // No output without input: at most W x H words per start of frame taken.
        no_spurious: assert (out_beats <= W * H * sofs);
`endif
`ifdef CHECK_FRAME
        // A well-framed input gives one word per beat, never more; once the input has been
        // quiet for QUIET clocks at a frame boundary, exactly one word per beat is out.
        frame_count: assert (out_beats <= in_beats);
        if (quiet == QUIET && at_start)
            frame_whole: assert (out_beats == in_beats);
`endif
`ifdef CHECK_MISFRAME
        // Every framing fault, and nothing else, pulses framing_error; every frame started
        // (faulty or not) comes out whole: W x H words.
        misframe_flag: assert (pulses <= faults);
        if (quiet == QUIET && at_start)
            misframe_whole: assert (pulses == faults && out_beats == W * H * sofs);
`endif
    end

`ifdef CHECK_RESET
    // A clock after a reset, from any state, nothing is output and no error is flagged.
    always @(posedge clk) if (!$initstate && $past(rst))
        reset: assert (!m_tvalid && !framing_error);
`endif
endmodule
