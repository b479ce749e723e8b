"""Stream components the core's ports are built of: an input queue and a register slice.

Both have :class:`amaranth.lib.stream.Signature` ports (``sink`` in, ``source`` out) of any
payload shape, and are arranged for timing at the pins of an FPGA rather than for few
registers: the reasons, measured on the core, are in the comments.
"""

from amaranth.hdl import Const, Module, Mux, Shape, Signal, Value
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["InputQueue", "RegisterSlice"]


def _next_entries(word, entries, enables):
    """The queue's entries as they will be a clock later."""
    return [Mux(enable, word, entry) for entry, enable in zip(entries, enables)]


class InputQueue(wiring.Component):
    """A queue behind input pins: the beats are registered twice, then kept in ``depth``
    register entries addressed by pointers.

    Parameters
    ----------
    shape : ShapeLike
        Payload shape.
    depth : int
        Entries, a power of two >= 4 (the pointers wrap by themselves).
    lanes : list of (int, int)
        Bit ranges ``[low, high)`` of the payload that go different ways in the consumer,
        covering every bit once; each has pointers and write enables of its own.
    registered_heads : iterable of int
        Indexes into ``lanes`` whose part of the head is a register, loaded a clock ahead
        with the entry the read pointer will show (the next one on a pop): a consumer
        whose pop depends on those bits then starts from a flip-flop, not from the read
        pointer's multiplexer.

    Members
    -------
    sink : In(stream.Signature(shape))
        A beat is taken when ``valid`` and ``ready``. ``ready`` comes from registers only:
        it leaves room for the beats in the two input registers and the one the sink may
        deliver in this clock.
    source : Out(stream.Signature(shape))
        The head entry, combinational from the entries; ``valid`` is a register. ``ready``
        pops the head and must be asserted only while ``valid`` is (a consumer that waits
        for ``valid``, as AXI4-Stream allows): gating it inside would put a gate in front
        of the read pointers and of every level flag.
    """

    def __new__(cls, shape, depth, lanes, registered_heads=()):
        # Refused before the object exists: a component that raises in __init__ is garbage
        # that Amaranth reports as created but never used. ``src_loc_at`` keeps the report
        # of a queue really left unused at the caller's line.
        if depth < 4 or depth & (depth - 1):
            raise ValueError(f"depth must be a power of two >= 4, not {depth}")
        bits = sorted(bit for low, high in lanes for bit in range(low, high))
        if bits != list(range(Shape.cast(shape).width)):
            raise ValueError(f"lanes {lanes} must cover every bit of the payload once")
        unknown = sorted(set(registered_heads) - set(range(len(lanes))))
        if unknown:
            raise ValueError(f"registered_heads {unknown} must index lanes "
                             f"(0 to {len(lanes) - 1})")
        return super().__new__(cls, src_loc_at=1)

    def __init__(self, shape, depth, lanes, registered_heads=()):
        self._shape, self._depth, self._lanes = shape, depth, list(lanes)
        self._registered_heads = set(registered_heads)
        super().__init__({"sink": In(stream.Signature(shape)),
                          "source": Out(stream.Signature(shape))})

    def elaborate(self, platform):
        m = Module()
        depth = self._depth
        # The pins reach one register without an enable and nothing else (registers fed by
        # pins are placed by the pins; an enable computed inside the core had to travel
        # there: census 9x9, 8.8 ns of routing on ECP5). A second plain register stands
        # between it and the entries: the write pointer reached the enables of the entries
        # across the way to the pins (ext. rank 7x7: 8.1 ns, one LUT).
        captured, captured_valid = Signal(self._shape, name="capture"), Signal()
        m.d.sync += [captured.eq(self.sink.payload),
                     captured_valid.eq(self.sink.valid & self.sink.ready)]
        staged, staged_valid = Signal(self._shape, name="staged"), Signal()
        m.d.sync += [staged.eq(captured), staged_valid.eq(captured_valid)]
        # A push writes the staged beat; it is known a clock ahead (``captured_valid``), so
        # each entry's write enable is a register of its own (the write pointer reaching
        # the enables of every entry was 9 ns of routing, ext. rank 9x9 on ECP5). A pop only
        # steps the read pointer, so the consumer's decision reaches two flip-flops, not the
        # enables of every entry (a shifting queue's pop was 8.2 ns, census 9x9).
        push, push_next, pop = staged_valid, captured_valid, self.source.ready

        # The level in thermometer code (``above[k]``: more than k entries are held, the two
        # input registers not counted): each flag's next value is one of itself and its
        # two neighbours, chosen by push and pop (one LUT). A counter's adder and a
        # comparison with zero for ``valid`` took four LUT levels after the pop (rank 13x13
        # on ECP5, 6.7 ns).
        above = [Signal(name=f"above{k}") for k in range(depth)]
        for k in range(depth):
            lower = above[k - 1] if k > 0 else Const(1)
            upper = above[k + 1] if k + 1 < depth else Const(0)
            m.d.sync += above[k].eq(Mux(push & ~pop, lower, Mux(pop & ~push, upper, above[k])))
        m.d.comb += self.source.valid.eq(above[0])
        # level + captured_valid + staged_valid <= depth - 1, from the thermometer.
        m.d.comb += self.sink.ready.eq(~Mux(
            captured_valid & staged_valid, above[depth - 3],
            Mux(captured_valid | staged_valid, above[depth - 2], above[depth - 1])))

        word, head = Value.cast(staged), Value.cast(self.source.payload)
        # One enable for a whole entry spanned the core (census 9x9: 8.8 ns of routing):
        # each lane has pointers (counters, which synthesis does not merge) and enables of
        # its own.
        for lane, (low, high) in enumerate(self._lanes):
            write = Signal(range(depth), name=f"write{lane}")
            read = Signal(range(depth), name=f"read{lane}")
            next_write = Signal.like(write, name=f"next_write{lane}")
            m.d.comb += next_write.eq(write + push)
            m.d.sync += write.eq(next_write)
            with m.If(pop):
                m.d.sync += read.eq(read + 1)
            entries = [Signal(high - low, name=f"entry{k}_{lane}") for k in range(depth)]
            enables = [Signal(name=f"entry{k}_{lane}_write") for k in range(depth)]
            for k, (entry, enable) in enumerate(zip(entries, enables)):
                m.d.sync += enable.eq(push_next & (next_write == k))
                with m.If(enable):
                    m.d.sync += entry.eq(word[low:high])
            if lane in self._registered_heads:
                # The entries as they will be next clock, at the read pointer and after it:
                # the pop only chooses between the two.
                written = _next_entries(word[low:high], entries, enables)
                current = self._select(m, read, written, f"head{lane}_current")
                following = self._select(m, read, written[1:] + written[:1],
                                         f"head{lane}_following")
                ahead = Signal(high - low, name=f"head{lane}")
                m.d.sync += ahead.eq(Mux(pop, following, current))
                m.d.comb += head[low:high].eq(ahead)
            else:
                with m.Switch(read):
                    for k, entry in enumerate(entries):
                        with m.Case(k):
                            m.d.comb += head[low:high].eq(entry)
        return m

    @staticmethod
    def _select(m, index, values, name):
        """``values[index]``, a multiplexer of its own."""
        chosen = Signal(len(values[0]), name=name)
        with m.Switch(index):
            for k, value in enumerate(values):
                with m.Case(k):
                    m.d.comb += chosen.eq(value)
        return chosen


class RegisterSlice(wiring.Component):
    """An AXI4-Stream register slice: an output register and a skid register.

    Parameters
    ----------
    shape : ShapeLike
        Payload shape.

    Members
    -------
    sink : In(stream.Signature(shape))
        ``ready`` is a register of its own: the skid register is empty.
    source : Out(stream.Signature(shape))
        ``payload`` and ``valid`` are registers; ``ready`` reaches the output register's
        enable and nothing else.
    """

    def __init__(self, shape):
        self._shape = shape
        super().__init__({"sink": In(stream.Signature(shape)),
                          "source": Out(stream.Signature(shape))})

    def elaborate(self, platform):
        m = Module()
        # The words need no reset: ``valid`` says whether they mean anything.
        head = Signal(self._shape, name="head", reset_less=True)
        skid = Signal(self._shape, name="skid", reset_less=True)
        valid, skid_valid = self.source.valid, Signal(name="skid_valid")
        # The port's valid drives the port only; the slice decides from a kept copy of it
        # (m_axis_tvalid's register, placed by the pins, into the skid's flag was census
        # 7x7's path at R = 10, 7.0-7.2 ns, and at 640 x 480, R = 1, 9.9 ns).
        valid_here = Signal(name="valid_here", attrs={"keep": 1})
        incoming, ready = self.sink.payload, self.source.ready
        taken = self.sink.valid & ~skid_valid
        # The skid takes every word while it is empty: the enable of its data is then the
        # register beside it, not the port's valid by the pins (census 7x7 on ECP5: 7.3 ns
        # from m_axis_tvalid to the skid's enables).
        with m.If(~skid_valid):
            m.d.sync += skid.eq(incoming)
        with m.If(ready | ~valid_here):
            m.d.sync += [head.eq(Mux(skid_valid, skid, incoming)),
                         valid.eq(skid_valid | self.sink.valid),
                         valid_here.eq(skid_valid | self.sink.valid), skid_valid.eq(0)]
        with m.Elif(taken):
            m.d.sync += skid_valid.eq(1)
        m.d.comb += [self.source.payload.eq(head), self.sink.ready.eq(~skid_valid)]
        return m
