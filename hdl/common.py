"""Pieces shared by the pipeline stages: position tags, slot timing and free-running delays.

The core never stalls: every register of the datapath loads every clock. Time is cut into
*slots* of R clocks (round 0 .. R-1); a slot either carries a *position* (a pixel, or a
dummy position while a frame is completed or flushed) or is a bubble. Every stage carries,
next to its data, the *tag* of the slot its data belongs to (centre column ``x``, row ``y``,
``valid``: the slot carries a position, ``live``: the tag names a real position since
reset). Stages derive every border mask from the tag, never
from what their registers or memories held before, so stale contents (previous frame,
reset in mid-frame, flush positions, bubbles) never reach a result. Only state that
belongs to positions (line buffers, stores of earlier positions) is written, and only in
slots whose tag is ``valid``: bubbles leave it untouched.

A value that belongs to a slot (a tag, a transformed pixel) is *slot-aligned at offset o*:
it holds the slot's value during the R clocks from o clocks after the slot's first clock.
"""

from amaranth.hdl import Cat, Const, Mux, Signal, Value, signed, unsigned
from amaranth.lib import data
from amaranth.lib.memory import Memory

__all__ = ["bits_for", "tag_layout", "y_range", "delay_line", "delay_line_rings",
           "DELAY_LINE_MIN", "DELAY_LINE_BITS", "pipe", "delay", "round_base", "SlotClock",
           "Store", "LaneStores", "ShiftStore", "column_inside", "row_bounds", "row_inside_ahead",
           "better", "absolute_difference", "split_lanes"]


def bits_for(maximum):
    """Width of an unsigned value up to ``maximum`` (at least 1 bit, so no 0-width ports)."""
    return max(1, int(maximum).bit_length())


def y_range(params):
    """(lowest, highest) row a tag can hold.

    The input stage's first position of a frame has its window centre r rows and r columns
    behind the pixel that entered, i.e. above the frame; rows stop counting (saturate) a
    few rows below the frame, where no stage needs them any more.
    """
    r, a, width = params.radius, params.agg_radius, params.width
    lowest = -(r * width + r) // width - a - 1
    highest = params.height + a + 1
    return lowest, highest


def tag_layout(params):
    """Layout of a slot's tag."""
    lowest, highest = y_range(params)
    y_bits = max(abs(lowest), highest).bit_length() + 1
    return data.StructLayout({
        "x": unsigned(bits_for(params.width - 1)),
        "y": signed(y_bits),
        "valid": unsigned(1),
        "live": unsigned(1),
    })


def register(m, value, shape, name, enable=None):
    """``value`` in a register of ``shape`` without reset (a datapath register, see
    :func:`pipe`), loaded every clock or while ``enable`` is high."""
    return _loaded(m, Signal(shape, name=name, reset_less=True), value, enable)


def _loaded(m, reg, value, enable):
    """``reg`` loaded with ``value`` every clock or while ``enable`` is high."""
    if enable is None:
        m.d.sync += reg.eq(value)
    else:
        with m.If(enable):
            m.d.sync += reg.eq(value)
    return reg


def replica(m, value, name, shape=None, enable=None, reset_less=False):
    """``value`` a clock later (or while ``enable``) in a register that synthesis keeps as
    a copy of its own.

    A value that reaches hundreds of flip-flops or lanes is one long net; copies each
    driving a few loads are short. Identical registers would be merged back into one by
    synthesis (with the same enable they are identical), so the copy is marked ``keep``:
    the project's Yosys flow keeps the flip-flop behind a kept wire
    (:func:`npstereo.gen.flow.yosys.synthesis_script`), and other tools read the attribute
    on the register."""
    reg = Signal(value.shape() if shape is None else shape, name=name, attrs={"keep": 1},
                 reset_less=reset_less)
    return _loaded(m, reg, value, enable)


#: Units (cost units, L/R units) that one copy of a control register reaches when a round
#: has more of them: one register for all 64 units at D = 64, R = 1 was the critical path
#: of census 5x5 at 1280 x 720 on ECP5 twice (the L/R check's write enable, 819 flip-flop
#: enables; x's low bits into the pair flags, 8.27 ns). The paper's D/R = 10 keep one.
UNITS_PER_CONTROL_COPY = 12


def control_copies(units):
    """Copies of a control register that ``units`` units take
    (:data:`UNITS_PER_CONTROL_COPY` each); unit i takes copy i // UNITS_PER_CONTROL_COPY."""
    return -(-units // UNITS_PER_CONTROL_COPY)


def unit_copies(m, value, units, name):
    """``value`` a clock later for each of ``units`` units (the list of each unit's copy):
    one register ``name`` when :func:`control_copies` is one (the Verilog of a round of up
    to :data:`UNITS_PER_CONTROL_COPY` units), else kept :func:`replica` copies."""
    copies = control_copies(units)
    if copies == 1:
        registers = [_loaded(m, Signal(value.shape(), name=name), value, None)]
    else:
        registers = [replica(m, value, f"{name}{k}") for k in range(copies)]
    return each_unit(registers, units)


def each_unit(copies, units):
    """Each of ``units`` units' copy among the :func:`control_copies` ``copies``."""
    return [copies[i // UNITS_PER_CONTROL_COPY] for i in range(units)]


def split_lanes(word, count, bits):
    """The ``count`` values of ``bits`` bits packed low to high in ``word``."""
    return [word[i * bits:(i + 1) * bits] for i in range(count)]


def taps(m, value, depth, name):
    """``value`` and free-running copies of it 1 .. ``depth`` clocks late (taps[k])."""
    copies = [value]
    for k in range(depth):
        copies.append(register(m, copies[-1], value.shape(), f"{name}_d{k + 1}"))
    return copies


#: Free-running delays of at least this many clocks go into rings of LUT RAM
#: (:func:`delay_line`): a word of LUT RAM per four bits holds 16 clocks of them, where
#: flip-flops hold one. At R = 1 the SGM stage's delays held 15,700 of census 5x5 SGM's
#: 73,000 flip-flops at 640 x 480, D = 64 (87 % of the ECP5-85k's; it did not place).
DELAY_LINE_MIN = 4
#: Bits per ring of a delay line, each ring with pointers of its own (one pointer into every
#: LUT RAM of a wide delay would be a long wire, as for :class:`LaneStores`).
DELAY_LINE_BITS = 32


def delay_line_rings(width, steps):
    """The rings of LUT RAM of a :func:`delay_line` of ``width`` bits by ``steps`` clocks,
    as (bits, depth) each: none below :data:`DELAY_LINE_MIN` (registers then)."""
    if steps < DELAY_LINE_MIN:
        return []
    depth = 1 << (steps - 1).bit_length()
    return [(min(DELAY_LINE_BITS, width - start), depth)
            for start in range(0, width, DELAY_LINE_BITS)]


def delay_line(m, value, steps, name):
    """``value`` ``steps`` clocks late, free-running (``taps(m, value, steps, name)[-1]``).

    From :data:`DELAY_LINE_MIN` clocks on, a ring of LUT RAM per :data:`DELAY_LINE_BITS`
    bits: written every clock at a pointer, read combinationally at a pointer ``steps`` - 1
    behind it, into a register. Both pointers count freely from their initial values, so
    their distance holds from configuration on, and no reset is needed.
    """
    rings = delay_line_rings(len(value), steps)
    if not rings:
        return taps(m, value, steps, name)[-1]
    parts, start = [], 0
    for k, (bits, depth) in enumerate(rings):
        m.submodules[f"{name}_ring{k}"] = ring = Memory(shape=unsigned(bits), depth=depth,
                                                        init=[])
        write, read = ring.write_port(), ring.read_port(domain="comb")
        pointers = depth.bit_length() - 1
        written = Signal(pointers, name=f"{name}_ring{k}_write", reset_less=True)
        reading = Signal(pointers, name=f"{name}_ring{k}_read",
                         init=-_ring_distance(steps) % depth, reset_less=True)
        m.d.sync += [written.eq(written + 1), reading.eq(reading + 1)]
        m.d.comb += [write.addr.eq(written), write.data.eq(value[start:start + bits]),
                     write.en.eq(1), read.addr.eq(reading)]
        parts.append(register(m, read.data, bits, f"{name}_ring{k}_out"))
        start += bits
    return Cat(*parts)


def _ring_distance(steps):
    """How far a ring's read pointer trails its write pointer: the word written ``steps``
    - 1 clocks ago, read into the register that makes the ``steps``-th clock."""
    return steps - 1


def pipe(m, value, steps, name, reset=False):
    """``value`` delayed by ``steps`` clocks: a free-running shift register.

    Datapath registers have no reset (``reset=False``): nothing downstream trusts their
    contents without a valid tag, and a reset net reaching every one of them would only
    cost routing. Control bits that start writes or count positions must be reset, or a
    pulse in flight before a reset would come out after it.
    """
    if len(Value.cast(value)) == 0:
        return value
    for step in range(steps):
        reg = Signal(value.shape(), name=f"{name}_p{step}", reset_less=not reset)
        m.d.sync += reg.eq(value)
        value = reg
    return value


def delay(m, en, value, steps, name):
    """``value`` delayed by ``steps`` ``en``-high clocks (a shift register without reset;
    0 steps: itself)."""
    for step in range(steps):
        reg = Signal(value.shape(), name=f"{name}_d{step}", reset_less=True)
        with m.If(en):
            m.d.sync += reg.eq(value)
        value = reg
    return value


def round_base(m, slots, offset, step, start=0):
    """``start`` + round * ``step`` at ``offset`` (``start`` 0: the round's first disparity),
    no multiplier: a register that restarts at ``start`` with each slot, + ``step`` a clock."""
    if slots.rounds == 1:
        return Const(start)
    assert offset >= 1, "the counter restarts from the slot pulse a clock ahead"
    value = Signal(range(start + slots.rounds * step),
                   name=f"{slots.name}_round_base{offset}" + (f"_from{start}" if start else ""))
    restart = (value == start + (slots.rounds - 1) * step) | slots.first(offset - 1)
    m.d.sync += value.eq(Mux(restart, start, value + step))
    return value


class SlotClock:
    """Slot timing inside one component: where round 0 of a slot falls, offset by offset.

    Parameters
    ----------
    m : Module
    first : Value
        1 in the first clock (round 0) of every slot, at the component's input offset.
    round_ : Value
        The round at the component's input offset.
    rounds : int
        R, the slot length in clocks.
    name : str
        Prefix of the registers it creates.
    base : int
        Clocks from the core's slot clock (round 0 in the first clock after reset) to
        ``first``: what :meth:`phased_round`'s free-running counters start from.

    The pulse is delayed by one shared shift register whose taps are handed out, so any
    number of users at any offsets cost max(offset) flip-flops in all.
    """

    def __init__(self, m, first, round_, rounds, name, base=0):
        self.m, self.rounds, self.name, self.base = m, rounds, name, base
        self._taps = [first]
        self._rounds = {0: round_}

    def first(self, offset):
        """1 in round 0 of every slot, ``offset`` clocks after the input offset."""
        if self.rounds == 1:
            return Const(1)
        while len(self._taps) <= offset:
            tap = Signal(name=f"{self.name}_first{len(self._taps)}")
            self.m.d.sync += tap.eq(self._taps[-1])
            self._taps.append(tap)
        return self._taps[offset]

    def round(self, offset):
        """The round (0 .. R-1) ``offset`` clocks after the input offset.

        A local counter, cleared by the slot-start pulse a clock ahead, rather than the
        input's round carried along: a few flip-flops, and no long wires between stages.
        """
        if self.rounds == 1:
            return Const(0)
        if offset not in self._rounds:
            counter = Signal(range(self.rounds), name=f"{self.name}_round{offset}")
            wrap = (counter == self.rounds - 1) | self.first(offset - 1)
            self.m.d.sync += counter.eq(Mux(wrap, 0, counter + 1))
            self._rounds[offset] = counter
        return self._rounds[offset]

    def phased_round(self, offset, phase, name):
        """(round + phase) mod R ``offset`` clocks after the input offset: a counter of
        its own.

        The address of one of many small stores: a round counter shared by all of them
        fans out to every RAM cell (rank 7x7: 6.3 ns of routing on ECP5). Each store
        addresses its word j at (j + phase) mod R, which is as good as j for a store read
        and written at the same round. The counter runs free from its reset value, which
        the slot timing fixes (the core's slot clock starts at reset with round 0, and this
        component's input offset is ``base`` clocks after the core's): a reload from a slot
        pulse would make that pulse fan out to every counter (census 9x9: 7.9 ns).
        Free-running counters are never merged by synthesis, whatever their phases.
        """
        if self.rounds == 1:
            return Const(0)
        rounds = self.rounds
        # One value more than it counts to: ``counter != R`` is then no constant, and
        # ANDed into an enable it keeps that enable a register of its own.
        counter = Signal(range(rounds + 1), name=name,
                         init=(phase - self.base - offset) % rounds)
        self.m.d.sync += counter.eq(Mux(counter == rounds - 1, 0, counter + 1))
        return counter

    def private_first(self, offset, phase, name):
        """Like :meth:`first`, but from a round counter of its own (:meth:`phased_round`).

        For clock enables of register copies that must stay copies: copies loaded by the
        same enable would be merged back into one register by synthesis.
        """
        if self.rounds == 1:
            return Const(1)
        return self.phased_round(offset, phase, name) == phase % self.rounds

    def private_copy(self, pulse, offset, copy, name):
        """``pulse`` (1 at most in the clock ``offset`` of a slot) a clock later, as a
        register of its own: ANDed with :meth:`private_first`, which holds in that clock,
        so that synthesis cannot merge the copies (the enable of a whole window's shift
        register as one register was 10 ns of routing, census 9x9 on ECP5)."""
        register = Signal(name=name, attrs=self.private_attrs())
        self.m.d.sync += register.eq(pulse & self.private_first(offset, copy,
                                                                f"{name}_round"))
        return register

    def private_attrs(self):
        """Attributes of a register loaded by :meth:`private_first`. At R = 1 that enable
        is a constant, the copies are identical registers and synthesis merged them back
        into one (the input stage's shift enables: one register reaching the whole right
        window, 8.4 ns of wire, census 5x5 box at 1280 x 720 on ECP5), so there they are
        marked ``keep`` as :func:`replica`'s are. With R > 1 the round counters keep them
        apart, and the Verilog stays as it was."""
        return {"keep": 1} if self.rounds == 1 else {}

    def delay(self, value, start, steps, name, reset_less=False, keep=False):
        """A value slot-aligned at ``start`` moved ``steps`` clocks later.

        A latch loaded in clock k of a slot (0 <= k < R) holds the slot's value from
        clock k + 1 to k + R: one register moves a value by up to R clocks, so the delay
        costs ceil(steps / R) registers, not ``steps`` (the value is constant for R
        clocks). Tags keep their reset (their valid bits must clear); data need not.
        ``keep``: the registers are copies synthesis must keep apart (as :func:`replica`'s).
        """
        done = 0
        while done < steps:
            jump = min(self.rounds, steps - done)
            reg = Signal(value.shape(), name=f"{name}_s{start + done + jump}",
                         reset_less=reset_less, attrs={"keep": 1} if keep else {})
            with self.m.If(self.first(start + done + jump - 1)):
                self.m.d.sync += reg.eq(value)
            value, done = reg, done + jump
        return value


class Store:
    """A few words of LUT RAM with an asynchronous read port, or a register for one word.

    Parameters
    ----------
    m : Module
    name : str
    shape : shape-castable
        One word.
    depth : int
        Words; a depth of 1 (R = 1) is a plain register (a memory would need a 0-bit
        address, which Verilog cannot declare).
    """

    def __init__(self, m, name, shape, depth):
        self.m, self.depth = m, depth
        if depth > 1:
            m.submodules[name] = memory = Memory(shape=shape, depth=depth, init=[])
            self._read, self._write = memory.read_port(domain="comb"), memory.write_port()
        else:
            self._word = Signal(shape, name=name, reset_less=True)

    def read(self, address):
        """The word at ``address`` (combinational)."""
        if self.depth == 1:
            return self._word
        self.m.d.comb += self._read.addr.eq(address)
        return self._read.data

    def write(self, address, data, enable):
        """Write ``data`` at ``address`` at the clock edge when ``enable``."""
        if self.depth == 1:
            with self.m.If(enable):
                self.m.d.sync += self._word.eq(data)
            return
        self.m.d.comb += [self._write.addr.eq(address), self._write.data.eq(data),
                          self._write.en.eq(enable)]


#: Lanes per LUT RAM of a :class:`LaneStores`.
LANES_PER_STORE = 4


def lane_groups(units):
    """The lanes of each LUT RAM of a :class:`LaneStores` of ``units`` lanes."""
    return [range(first, min(first + LANES_PER_STORE, units))
            for first in range(0, units, LANES_PER_STORE)]


class LaneStores:
    """A :class:`Store` of ``depth`` words of ``sections`` x ``units`` lanes of ``bits`` bits
    (packed section by section, lane by lane: Cat(*section0, *section1, ...)), kept as one
    LUT RAM per :data:`LANES_PER_STORE` lanes (all sections of those lanes), each read at an
    address of its own: one address register reaching every lane's RAM cells is a long
    wire (census 7x7 SGM's left store at R = 10, 6.2-6.7 ns)."""

    def __init__(self, m, name, units, bits, depth, sections=1):
        self.bits, self.units, self.sections = bits, units, sections
        self.groups = lane_groups(units)
        self.stores = [Store(m, f"{name}{k}", unsigned(sections * len(g) * bits), depth)
                       for k, g in enumerate(self.groups)]

    def read(self, address):
        """The word (combinational); group k reads at ``address(k)``."""
        lanes = [[None] * self.units for _ in range(self.sections)]
        for k, (group, store) in enumerate(zip(self.groups, self.stores)):
            word = split_lanes(store.read(address(k)), self.sections * len(group), self.bits)
            for section in range(self.sections):
                for i, lane in zip(group, word[section * len(group):]):
                    lanes[section][i] = lane
        return Cat(*(lane for section in lanes for lane in section))

    def write(self, address, word, enable):
        """Write ``word`` at ``address`` at the clock edge when ``enable``."""
        lanes = split_lanes(word, self.sections * self.units, self.bits)
        for group, store in zip(self.groups, self.stores):
            store.write(address, Cat(*(lanes[section * self.units + i]
                                       for section in range(self.sections) for i in group)),
                        enable)


class ShiftStore:
    """``depth`` words of registers that shift by one at every write: the oldest word is
    read, always the same register, so no address and no multiplexer stand in front of it.

    It stands in for a :class:`Store` whose word of round j is read exactly ``depth``
    writes after it was written, which holds when writes come in round order and every
    slot writes all of its rounds or none (a slot without a position writes nothing, so
    the gaps between positions do not move the word read).
    """

    def __init__(self, m, name, shape, depth):
        self.m = m
        self._words = [Signal(shape, name=f"{name}{k}", reset_less=True) for k in range(depth)]

    @property
    def oldest(self):
        """The word written ``depth`` writes ago."""
        return self._words[-1]

    def write(self, address, data, enable):
        """At the clock edge when ``enable``: ``data`` in, every word one place older.
        ``address`` (the round) is implied by the order of the writes; it is taken so that
        a shifting store is written as a :class:`Store` is."""
        with self.m.If(enable):
            self.m.d.sync += [newer.eq(older) for newer, older
                              in zip(self._words[1:], self._words[:-1])]
            self.m.d.sync += self._words[0].eq(data)


def column_inside(x, offset, width):
    """Column ``x + offset`` lies inside the frame, for a column counter ``x`` that is
    always in 0 .. W-1 (so only one side can fail, and offset 0 never does)."""
    if offset < 0:
        return x >= -offset
    return x < width - offset if offset > 0 else Const(1)


def row_bounds(y, above, height):
    """Row ``y - above`` lies in the frame: ``y >= above`` and ``y < height + above``."""
    return y >= above, y < height + above


def row_inside_ahead(m, y, above, height, name, suffix=""):
    """:func:`row_bounds` a clock after ``y``, each a register, ANDed in the reader's clock
    (both carry chains and the AND in one clock: census 5x5 box on ECP5, 6.96-7.23 ns)."""
    low, high = (register(m, bound, 1, f"{name}_{side}{suffix}")
                 for side, bound in zip(("above", "below"), row_bounds(y, above, height)))
    return low & high


def better(candidate, best):
    """The tie rule of every WTA: a candidate replaces the best so far only if strictly
    smaller.

    Candidates are visited (or, in a tree, paired) in increasing disparity order, so among
    equal costs the lowest disparity stays, as in the golden model.
    """
    return candidate < best


def absolute_difference(a, b):
    """Eq. 6: |a - b| of two unsigned values, as wide as the wider operand.

    Both differences and a select: yosys shares the ``<`` with the borrow of one of the
    subtractors (8 CCU2C + 7 LUT4 for 8 bits on ECP5, the cheapest of the forms tried,
    including a conditional negation).
    """
    width = max(len(a), len(b))
    return Mux(b < a, (a - b)[:width], (b - a)[:width])
