"""The whole core: pixel pairs in, disparities out, as ``amaranth.lib.stream`` streams.

Chains :class:`~.input_stage.InputStage`, :class:`~.calculation_stage.CalculationStage`,
:class:`~.evaluation_stage.EvaluationStage`, :class:`~.lr_check.LRCheck` and, with
``params.median``, :class:`~.median.Median3` (the order of
:func:`npstereo.golden.pipeline.disparity_map`).

**A pipeline that never stalls.** Time is cut into slots of R clocks; in the last clock of a
slot the admission logic decides whether the next slot carries a position (the next input
pixel, or a dummy position while a frame is completed or flushed) or is a bubble. Nothing
downstream has a clock enable: data flow every clock with the tag of their slot, and only
state that belongs to positions (line buffers, the stores of earlier positions) is written,
in slots that carry one. Backpressure is handled at the ports only: the output queue
(:class:`amaranth.lib.fifo.SyncFIFOBuffered`) is deep enough for every position in flight,
and a position is admitted only when the queue is sure to have room for its word (a credit
counter: queue depth minus words queued minus positions in flight). So no signal fans out
to every register, and no combinational path runs from one port to the other.

Framing (see docs/semantics.md, "Hardware"): IDLE waits for a start of frame (``first``)
and drops pixels without one; FRAME takes W x H pixels checking ``last``; a framing error (a
wrong ``last``, a start of frame inside a frame) pulses ``framing_error`` and the rest of
the frame is filled with zero pixels (FILL); FLUSH feeds dummy positions until the frame's last
output word is out, then IDLE again. A start of frame that is waiting at the beginning of a
flush line is taken at once: the frames overlap in the pipeline (the input stage keeps the
finishing frame's coordinates for its last centres), so back-to-back frames cost W x H
slots each, with no flush between them.

The payloads are :mod:`.stream`'s formats; :mod:`.verilog` wraps the core in the Verilog
top level ``npstereo_core`` with AXI4-Stream port names.
"""

from amaranth.hdl import Const, Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from .calculation_stage import CalculationStage
from .common import SlotClock, pipe
from .credits import credit_flag
from .evaluation_stage import EvaluationStage
from .input_stage import InputStage
from .lr_check import LRCheck
from .median import Median3
from .mirror import RowTurn, reversed_sums
from .plan import check_buildable
from .plan_structure import masks_after_compare
from .plan_timing import core_timing, decision_clocks, latency
from .stream import PixelPair, disparity_word, framed
from .stream_parts import InputQueue, RegisterSlice
from .subpixel import SubpixelFit
from .ticks import TickWords, ticked
from .trees import DEFAULT_EVERY

__all__ = ["NpStereoCore"]

#: Framing states (see the module docstring).
IDLE, FRAME, FILL, FLUSH = range(4)


class NpStereoCore(wiring.Component):
    """Streaming stereo core for one parameter set.

    Parameters
    ----------
    params : StereoParams
        Must have ``width`` and ``height`` (else :class:`ParameterError`).
    every : int
        Register spacing of the trees (see :mod:`.trees`).

    Members
    -------
    sink : In(stream.Signature(framed(PixelPair)))
        Pixel pairs in raster order, ``first`` on (0, 0), ``last`` on every line's end.
    source : Out(stream.Signature(framed(disparity_word(params))))
        One beat per input pixel in raster order (``data.disparity`` 0 where
        ``data.valid`` is 0), with the input's ``first`` and ``last``.
    framing_error : Out(1)
        One-clock pulse per framing error (registered).

    Attributes
    ----------
    latency : int
        Positions from a pixel's admission to the position whose admission completes its
        output word: the flush after the last frame of a stream.
    clock_latency : int
        Clocks from the admission of that position to the word entering the output queue.
    """

    def __new__(cls, params, *args, **kwargs):
        # Refused before the object exists: a component that raises in __init__ is garbage
        # that Amaranth reports as created but never used. ``src_loc_at`` keeps the report
        # of a core really left unused at the caller's line.
        check_buildable(params)
        return super().__new__(cls, src_loc_at=1)

    def __init__(self, params, every=DEFAULT_EVERY):
        self.params = params
        timing = core_timing(params, every)
        self.input_stage = InputStage(params)
        self.calculation_stage = CalculationStage(params, every, timing.calculation)
        self.evaluation_stage = EvaluationStage(params)
        #: With F > 0: the sub-pixel fit between the evaluation stage and the L/R check.
        self.subpixel = SubpixelFit(params) if params.subpixel_bits else None
        # Offsets (clocks after admission) where each stage's input is slot-aligned.
        self.calculation_at, self.sums_at = timing.calculation, timing.sums
        self.evaluation_at = timing.evaluation
        self.check_at = timing.check
        self.lr_check = LRCheck(params, timing.left - timing.check, timing.check)
        #: With the fifth path: the words of the mirrored rows turned round.
        self.row_turn = RowTurn(params, len(self.lr_check.disparity_out)) \
            if params.fifth_path else None
        self.median = Median3(params, len(self.lr_check.disparity_out)) if params.median \
            else None
        self.clock_latency = timing.output
        #: Output queue depth: every position in flight must find room for its word.
        self.queue_depth = timing.queue_depth
        self.latency = latency(params)
        super().__init__({
            "sink": In(stream.Signature(framed(PixelPair))),
            "source": Out(stream.Signature(framed(disparity_word(params)))),
            "framing_error": Out(1),
        })

    def elaborate(self, platform):
        p = self.params
        width, height, rounds = p.width, p.height, p.rounds
        m = Module()
        m.submodules.input_stage = inp = self.input_stage
        m.submodules.calculation_stage = calc = self.calculation_stage
        m.submodules.evaluation_stage = ev = self.evaluation_stage
        m.submodules.lr_check = lr = self.lr_check
        words = self._output_words(m, lr)

        # The slot clock: round 0 .. R-1, free-running.
        round_ = Const(0)
        if rounds > 1:
            round_ = Signal(range(rounds), name="round")
            m.d.sync += round_.eq(Mux(round_ == rounds - 1, 0, round_ + 1))
        first = Signal(name="slot_first", init=1)
        m.d.sync += first.eq(round_ == rounds - 1)
        slots = SlotClock(m, first, round_, rounds, "core")

        # Input: the queue by the pins (see InputQueue). The left pixels, the right pixels
        # and the framing flags go different ways: a lane each.
        beat = data.Layout.cast(self.sink.payload.shape())
        pixels_at = beat["data"].offset
        lanes = [(pixels_at + field.offset, pixels_at + field.offset + field.width)
                 for _, field in data.Layout.cast(PixelPair)]
        lanes.append((beat["first"].offset, beat["last"].offset + 1))
        # At R = 1 the admission decides from the head's framing flags in the clock it
        # pops: they are a register of the queue's (the read pointer's multiplexer in front
        # of the decision was census 5x5 box's critical path at 1920 x 1080, 7.44 ns).
        framing = [len(lanes) - 1] if rounds == 1 else []
        m.submodules.in_queue = in_queue = InputQueue(beat, INPUT_QUEUE, lanes, framing)
        wiring.connect(m, wiring.flipped(self.sink), in_queue.sink)
        # The decision pops only a head it saw valid, as the queue requires (a pop only
        # happens in round R-1, so a head seen valid earlier in the slot still is).
        pop = in_queue.source.ready
        head, head_valid = in_queue.source.payload, in_queue.source.valid
        # The head is registered on its way to the admission and the position's register
        # (the queue sits by the pins: census 9x9, 9.6 ns through the queue's read
        # multiplexer to the position's register, census 7x7 8.9 ns to the admission's
        # conditions). The read pointer moves only when the decision pops, in round R-1:
        # with R >= 4 the conditions, registered in round R-3, see the registered head of
        # the new read pointer; with R = 2 or 3 only the pixels (taken in round R-1) are
        # registered.
        if rounds >= 4:
            head = pipe(m, head, 1, "in_queue_head")
            head_pixels = head.data
        else:
            head_pixels = head.data if rounds == 1 else pipe(m, head.data, 1, "in_queue_pixels")

        # Output: the queue of words, and the credits of positions it can still take.
        word = Signal(self.source.payload.shape())
        m.submodules.out_queue = queue = SyncFIFOBuffered(
            width=len(word.as_value()), depth=self.queue_depth)
        # The port is driven by a register slice (an output register and a skid register):
        # the consumer's ready reaches the output register's enable and nothing else, and
        # that enable is one LUT from the pin and valid (a shifting queue's pop logic was three
        # LUTs and 8.8 ns from m_axis_tvalid to m_axis_tdata, ext. rank 7x7 on ECP5).
        m.submodules.out_port = out_port = RegisterSlice(word.shape())
        # The word is registered on its way into the queue, and a second slice stands
        # between the queue and the port's: the L/R check's pulse into the queue's LUT RAM
        # write (census 5x5 box at 1280 x 720, R = 1: 9.39 ns) and the port slice's skid
        # flag into the queue's read (census 7x7 box at 640 x 480, R = 1: 10.87 ns) each
        # crossed the die in one clock. (plan_timing.OUTPUT_REGISTERS counts these two.)
        m.submodules.out_slice = out_slice = RegisterSlice(word.shape())
        wiring.connect(m, queue.r_stream, out_slice.sink)
        wiring.connect(m, out_slice.source, out_port.sink)
        wiring.connect(m, out_port.source, wiring.flipped(self.source))
        m.d.sync += [
            queue.w_en.eq(words.produce), queue.w_data.eq(word),
        ]
        m.d.comb += [
            word.data.disparity.eq(Mux(words.valid, words.disparity, 0)),
            word.data.valid.eq(words.valid),
            word.first.eq(words.frame_start), word.last.eq(words.line_end),
        ]
        admit = Signal()        # the decision of this clock: the next slot has a position
        credit_taken = Signal()  # the same, a clock late (see below)
        # The queue's room: the credits, and the flag the decision reads.
        credit = credit_flag(
            m, self.queue_depth, rounds, credit_taken,
            popped=out_slice.sink.valid & out_slice.sink.ready,
            retired=words.retire & ~words.produce)
        has_credit = credit.flag

        # Frames started whose last word is not queued yet: a flush ends when none is left
        # (frames shorter than the pipeline may overlap the flush of the one before).
        outstanding = Signal(range(8))
        # The last word's pulse is registered where the L/R check makes it, a clock late
        # (a flush then ends a clock later): the counter sits between the admission and
        # the output, and its adder took the pulse's own logic across the core.
        frame_done = pipe(m, words.produce & words.frame_end, 1, "frame_done", reset=True)

        # Framing and admission. An explicit state register and if/else chains rather
        # than m.FSM: Amaranth's FSM emits partial case statements that Verilator's lint
        # rejects (CASEINCOMPLETE). The decision, its pop and the queue's next head form a
        # loop of one clock, so every comparison it needs is a flag registered beside its
        # counter: the decision is then a few LUTs deep (13 ns on ECP5 with the
        # comparisons inside the loop).
        # One hot: each state's flag is a register of its own, so the proposal's LUTs take
        # one input per state they test instead of decoding two bits.
        state = Signal(4, name="framing_state", init=1 << IDLE)
        column = Signal(range(width))             # column of the next admitted position
        row = Signal(range(max(2, height)))
        line_start = Signal(init=1, name="column_zero")          # column == 0
        end_of_line = Signal(name="end_of_line")                  # column == W - 1
        last_row = Signal(name="last_row")                        # row == H - 1
        end_of_frame = end_of_line & last_row
        none_outstanding = Signal(init=1, name="none_outstanding")
        m.d.sync += none_outstanding.eq(outstanding == 0)  # a clock late: a flush ends late
        idle, framing, filling = state[IDLE], state[FRAME], state[FILL]

        # The proposal for the next slot, from registers only. With R >= 2 it is made in
        # round R-2 and registered, and applied in round R-1: nothing it depends on can
        # change in between except towards a later, more cautious decision (a beat
        # arriving, credits coming back, a switch completing, a frame finishing), since
        # only an applied decision pops the queue or takes a credit. So the decision, the
        # pop and the queue's next head no longer form a loop of one clock (9.9 ns, 6
        # levels on ECP5). With R = 1 the proposal is applied in the clock it is made.
        # With R >= 3 the conditions it combines are themselves registered in round R-3
        # (by the same argument, over two clocks), so that neither half is more than two
        # or three LUTs deep. The proposal also carries the framing state that follows it
        # (``change``, ``state``): applying it is one multiplexer in front of the state.
        conditions = data.StructLayout({name: 1 for name in (
            "drop", "can_start", "restart", "can_take", "misframed", "last_beat",
            "frame_end", "credit", "flush_start", "done")})
        now = Signal(conditions)
        # With the input stage's decision a clock late (decision_clocks, below), its
        # switch_pending rises a clock late too: at R = 1 the starts of those clocks hold
        # the next one.
        if decision_clocks(rounds):
            # At R = 1 the decision closes a loop of one clock through the queue's pop,
            # and what it reads from elsewhere comes through registers by it: the credit
            # flag through a copy of its own (credit_flag), and the conditions that hold
            # back a start as one register, start_allowed (below). Straight from where
            # they are made, each was census 5x5 box's critical path at 1280 x 720 or
            # 1920 x 1080 in turn (has_credit, a start's hold, the input stage's
            # switch_pending: 6.7-8.8 ns, 3-4 levels, into the queue's read pointers or
            # the row counter). none_outstanding may not come later: a flush would end
            # while a frame started in it is on its way to the count (3x1 frames fail).
            start_allowed = Signal(name="start_allowed")
            can_start = head_valid & head.first & start_allowed
        else:
            can_start = head_valid & head.first & ~inp.switch_pending & has_credit
        m.d.comb += [
            now.drop.eq(head_valid & ~head.first),      # a beat without a start of frame
            now.can_start.eq(can_start),
            now.restart.eq(head_valid & head.first),    # a start of frame inside a frame
            now.can_take.eq(head_valid & has_credit),
            now.misframed.eq(head.last != end_of_line),
            now.last_beat.eq(head.last),
            now.frame_end.eq(end_of_line & last_row),
            now.credit.eq(has_credit),
            now.flush_start.eq(line_start & can_start),
            now.done.eq(none_outstanding),
        ]
        if rounds >= 3:
            given = Signal(conditions, name="admission_conditions")
            m.d.sync += given.eq(now)
        else:
            given = now

        proposal = data.StructLayout({
            **{name: 1 for name in ("admit", "take", "start", "overlap", "pop", "error",
                                    "change")},
            "state": 4})
        proposed = Signal(proposal)

        def to(new_state):
            return [proposed.change.eq(1), proposed.state.eq(1 << new_state)]

        def start_frame(overlapping):
            # A line of one pixel cannot end on the first pixel: width > 2 always.
            return [proposed.admit.eq(1), proposed.take.eq(1), proposed.start.eq(1),
                    proposed.overlap.eq(overlapping), proposed.pop.eq(1),
                    proposed.error.eq(given.last_beat),
                    proposed.change.eq(1),
                    proposed.state.eq(Mux(given.last_beat, 1 << FILL, 1 << FRAME))]

        with m.If(idle):
            with m.If(given.drop):
                # Outside a frame every beat without a start of frame is dropped.
                m.d.comb += [proposed.pop.eq(1), proposed.error.eq(1)]
            with m.Elif(given.can_start):
                m.d.comb += start_frame(0)
        with m.Elif(framing):
            with m.If(given.restart):
                m.d.comb += [proposed.error.eq(1), *to(FILL)]
            with m.Elif(given.can_take):
                m.d.comb += [proposed.admit.eq(1), proposed.take.eq(1), proposed.pop.eq(1),
                             proposed.error.eq(given.misframed)]
                with m.If(given.frame_end):
                    m.d.comb += to(FLUSH)
                with m.Elif(given.misframed):
                    m.d.comb += to(FILL)
        with m.Elif(filling):
            m.d.comb += proposed.admit.eq(given.credit)
            with m.If(given.credit & given.frame_end):
                m.d.comb += to(FLUSH)
        with m.Else():  # FLUSH
            with m.If(given.drop):
                m.d.comb += [proposed.pop.eq(1), proposed.error.eq(1)]
            with m.If(given.done):
                m.d.comb += to(IDLE)
            with m.Elif(given.flush_start):
                m.d.comb += start_frame(1)
            with m.Else():
                m.d.comb += proposed.admit.eq(given.credit)
        if rounds == 1:
            def decision(group, copy):
                return proposed
        else:
            def decision(group, copy):
                # Loaded in round R-2 (a clock enable, no logic) and used only in round
                # Registered as the proposal in round R-2 and as nothing in every
                # other round, so the register itself is the decision of round R-1: no
                # slot pulse and no multiplexer between it and what it drives (ext. rank
                # 7x7 on ECP5: 7.6 ns from the slot pulse through the decision to the row
                # flags). The framing logic by the input pins and the input stage's
                # groups have a copy each, loaded by an enable of its own
                # (slots.private_first) so that synthesis keeps the copies apart: one
                # register for both was 7.9 ns to the frame counter (census 9x9 on ECP5).
                latched = Signal(proposal, name=f"decision_{group}")
                first = slots.private_first(rounds - 2, copy, f"decision_{group}_round")
                m.d.sync += latched.eq(Mux(first, proposed, 0))
                return latched
        chosen = decision("framing", 0)
        handed = decision("input", 1)
        if decision_clocks(rounds):
            # At R = 1 the input stage's copy is registered here, by the admission: the
            # queue's head through the admission into the line buffers' read address (a
            # register by the block RAMs) was census 7x7 box's critical path at 640 x 480
            # (11.36 ns, 5.79 of it one wire). The stage raises switch_pending three clocks
            # after a start reaches it, and the admission sees it a clock later still; the
            # two clocks they come later are held here (3x1 frames back to back catch it,
            # tests/test_hdl_core.py): a start decided three or four clocks before, the
            # stage's switch_pending and the credit flag, each as of a clock before.
            latched = Signal(proposal, name="decision_input")
            m.d.sync += latched.eq(handed)
            handed = latched
            late = pipe(m, handed.admit & handed.start, 1, "start_late", reset=True)
            later = pipe(m, late, 1, "start_later", reset=True)
            m.d.sync += start_allowed.eq(~(inp.switch_pending | late | later) & credit.early)
        # The credits and the count of frames in flight sit by the output: they take the
        # decision a clock late, through a register of its own (a copy loaded from the
        # proposal was 8.7 ns from the proposal's logic, census 9x9 on ECP5; at R = 1 the
        # decision straight into the credits, 7-8 ns). _unseen_decisions counts the
        # decisions the credit flag has not seen; a frame's count starts a clock late,
        # long before its flush can end.
        taking = pipe(m, chosen.admit, 1, "credit_taken", reset=True)
        starting = pipe(m, chosen.admit & chosen.start, 1, "frame_started", reset=True)
        take = chosen.take        # the admitted position is the head pixel (else zeros)
        error = Signal()
        m.d.sync += self.framing_error.eq(error)
        m.d.comb += [admit.eq(chosen.admit), pop.eq(chosen.pop), error.eq(chosen.error)]
        with m.If(chosen.change):
            m.d.sync += state.eq(chosen.state)

        # The comparisons the counters' flags need, registered: the row changes only at
        # line ends (W > 2 positions apart), the column once per slot (R clocks apart), so
        # a flag a clock late is in time; with R = 1 the column's is compared at once.
        second_last_row = Signal(name="second_last_row")
        m.d.sync += second_last_row.eq(row == height - 2)
        if rounds > 1:
            second_last_column = Signal(name="second_last_column")
            m.d.sync += second_last_column.eq(column == width - 2)
        else:
            second_last_column = column == width - 2
        with m.If(admit):
            with m.If(chosen.start):
                m.d.sync += [column.eq(1), row.eq(0), line_start.eq(0),
                             end_of_line.eq(width == 2), last_row.eq(height == 1)]
            with m.Else():
                m.d.sync += [column.eq(Mux(end_of_line, 0, column + 1)),
                             line_start.eq(end_of_line),
                             end_of_line.eq(~end_of_line & second_last_column)]
                with m.If(end_of_line):
                    m.d.sync += [row.eq(Mux(end_of_frame, 0, row + 1)),
                                 last_row.eq(~end_of_frame & second_last_row)]

        m.d.comb += credit_taken.eq(taking)
        m.d.sync += outstanding.eq(outstanding + starting - frame_done)

        # The pixels leave the queue unchanged and are zeroed (dummy positions) two clocks
        # later, by a flag registered with them twice: the decision's register reached the
        # pixels' multiplexers by the line buffers across the core (census 9x9 and ext.
        # rank 7x7 on ECP5: 7.9 ns through one LUT, also with one register between).
        late_input = decision_clocks(rounds)
        raw = pipe(m, head_pixels, 2 + late_input, "raw_pixels")
        taken = pipe(m, take, 2 + late_input, "taken")
        pixels = Signal(PixelPair, reset_less=True)
        m.d.sync += pixels.eq(Mux(taken, raw, 0))

        if p.fifth_path and p.lr_check:
            sums = reversed_sums(m, p, slots, calc.sums, self.sums_at, "lr_reversed_sums")
            checked = [*(lr.sums[i].eq(value) for i, value in enumerate(sums)),
                       lr.tag.eq(slots.delay(calc.centre, self.sums_at,
                                             self.check_at - self.sums_at, "lr_tag"))]
        else:
            checked = [lr.sums.eq(calc.sums), lr.tag.eq(calc.centre)]
        m.d.comb += [
            # The decision itself: the input stage registers it where it is used.
            inp.admit.eq(handed.admit), inp.start.eq(handed.start), inp.overlap.eq(handed.overlap),
            inp.left.eq(pixels.left), inp.right.eq(pixels.right),
            inp.first.eq(first), inp.round.eq(round_),
            calc.window_left.eq(inp.window_left), calc.window_right.eq(inp.window_right),
            calc.centres_left.eq(inp.centres_left), calc.centres_right.eq(inp.centres_right),
            calc.tag.eq(inp.tag),
            calc.first.eq(slots.first(self.calculation_at)),
            calc.round.eq(slots.round(self.calculation_at)),
            ev.cost.eq(calc.best_cost), ev.disparity.eq(calc.best_disparity),
            ev.tag.eq(slots.delay(calc.centre, self.sums_at,
                                  self.evaluation_at - self.sums_at, "evaluation_tag")),
            ev.first.eq(slots.first(self.evaluation_at)),
            ev.round.eq(slots.round(self.evaluation_at)),
            *checked,
            lr.first.eq(slots.first(self.check_at)), lr.round.eq(slots.round(self.check_at)),
        ]
        if self.subpixel is None:
            m.d.comb += [lr.disparity.eq(ev.disparity_out), lr.left_tag.eq(ev.tag_out)]
        else:
            m.submodules.subpixel = fit = self.subpixel
            fit_at = self.evaluation_at + ev.latency
            m.d.comb += [ev.before.eq(calc.best_before), ev.after.eq(calc.best_after)]
            m.d.comb += [
                fit.disparity.eq(ev.disparity_out), fit.centre.eq(ev.cost_out),
                fit.before.eq(ev.before_out), fit.after.eq(ev.after_out),
                lr.disparity.eq(fit.disparity_out), lr.value.eq(fit.value),
                lr.left_tag.eq(slots.delay(ev.tag_out, fit_at, fit.latency, "subpixel_tag")),
            ]
        if masks_after_compare(p):
            m.d.comb += calc.keep.eq(inp.keep)
        return m

    def _output_words(self, m, lr):
        """The words that go to the output queue: the L/R check's, turned round with the
        fifth path, then the 3x3 median of them (each stage one tick out per tick in, so
        the credits balance either way)."""
        words = TickWords(lr.retire, lr.produce, lr.valid, lr.disparity_out, lr.x, lr.y,
                          lr.frame_start, lr.line_end, lr.frame_end)
        for name, stage in (("row_turn", self.row_turn), ("median", self.median)):
            if stage is not None:
                m.submodules[name] = stage
                words = ticked(m, stage, words)
        return words


#: Entries of the input queue (a power of two: its pointers wrap by themselves).
INPUT_QUEUE = 4
