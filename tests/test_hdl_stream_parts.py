"""The stream parts (``hdl/stream_parts.py``) in Amaranth's simulator.

In the style of verilog-axis's tests: every scenario runs with and without idle cycles at
the source and with and without backpressure at the sink, every beat must come out once and
in order, and the parts' sources must keep the stream rule (a beat offered stays offered,
unchanged, until it is taken). Deliberately wrong components (a queue that ignores its
room, a slice that drops its skid, a plain register that loads while stalled, a queue that
loses a lane) must fail the same checks.
"""

import random
import re

import pytest
from amaranth.hdl import Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from npstereo.hdl import stream_parts
from npstereo.hdl.stream_parts import InputQueue, RegisterSlice

from hdl_helpers import refused_quietly, simulate

#: An 18-bit payload in three lanes, as the core's pixel beats.
WIDTH, LANES, DEPTH = 18, [(0, 8), (8, 16), (16, 18)], 4


def queue():
    return InputQueue(WIDTH, DEPTH, LANES)


def queue_registered_framing():
    """The core's queue at R = 1: the framing lane's head is a register."""
    return InputQueue(WIDTH, DEPTH, LANES, registered_heads=[2])


def queue_registered_heads():
    return InputQueue(WIDTH, DEPTH, LANES, registered_heads=range(len(LANES)))


def register_slice():
    return RegisterSlice(WIDTH)


#: Each part, and whether its consumer asserts ``ready`` only while ``valid`` (the input
#: queue's rule; the register slice takes any consumer).
PARTS = {"queue": (queue, True), "queue, framing head registered":
         (queue_registered_framing, True), "queue, heads registered":
         (queue_registered_heads, True), "slice": (register_slice, False)}
QUEUES = [name for name in PARTS if name.startswith("queue")]


def run(dut, beats, *, ready_waits_for_valid, idle=0.0, backpressure=0.0, seed=0,
        stall=0, limit=2000):
    """Offer ``beats`` (ints) at the sink, collect the source's beats.

    The source inserts an idle clock before a beat with probability ``idle``; the sink
    refuses a beat with probability ``backpressure`` and not at all in the first ``stall``
    clocks. Fails (AssertionError) when the part's source breaks the stream rule.

    Returns (received beats, clocks until the last one, beats taken during the stall).
    """
    rng = random.Random(seed)
    result = {"received": [], "cycles": 0, "taken_in_stall": 0}

    async def bench(ctx):
        index, offering, held = 0, False, None
        for cycle in range(limit):
            if not offering and index < len(beats):
                offering = rng.random() >= idle
            ctx.set(dut.sink.valid, offering)
            if offering:
                ctx.set(dut.sink.payload, beats[index])
            valid = ctx.get(dut.source.valid)
            payload = ctx.get(dut.source.payload)
            if held is not None:
                assert valid and payload == held, \
                    f"clock {cycle}: a stalled beat {held:#x} changed or was withdrawn"
            ready = cycle >= stall and rng.random() >= backpressure
            if ready_waits_for_valid:
                ready = ready and valid
            ctx.set(dut.source.ready, ready)
            if offering and ctx.get(dut.sink.ready):
                index, offering = index + 1, False
                result["taken_in_stall"] += cycle < stall
            held = payload if valid and not ready else None
            if valid and ready:
                result["received"].append(payload)
                result["cycles"] = cycle + 1
                if len(result["received"]) >= len(beats) and index >= len(beats):
                    break
            await ctx.tick()

    simulate(dut, bench)
    return result


def beats_of(count, seed):
    rng = random.Random(seed)
    return [rng.getrandbits(WIDTH) for _ in range(count)]


SCENARIOS = {
    "one beat": dict(count=1, stall=0),
    "burst": dict(count=64, stall=0),
    "sink paused at start": dict(count=16, stall=20),
}


def check_scenario(make, ready_waits_for_valid, scenario, idle, backpressure):
    settings = SCENARIOS[scenario]
    beats = beats_of(settings["count"], hash((scenario, idle, backpressure)) % 1000)
    result = run(make(), beats, ready_waits_for_valid=ready_waits_for_valid, idle=idle,
                 backpressure=backpressure, seed=7, stall=settings["stall"])
    assert result["received"] == beats, \
        f"sent {len(beats)} beats, received {len(result['received'])}, or not in order"


@pytest.mark.parametrize("backpressure", [0.0, 0.5], ids=["ready", "backpressure"])
@pytest.mark.parametrize("idle", [0.0, 0.5], ids=["valid", "idle"])
@pytest.mark.parametrize("scenario", list(SCENARIOS))
@pytest.mark.parametrize("part", list(PARTS))
def test_every_beat_once_in_order(part, scenario, idle, backpressure):
    check_scenario(*PARTS[part], scenario, idle, backpressure)


def check_full_rate(make, ready_waits_for_valid, latency):
    beats = beats_of(50, 1)
    result = run(make(), beats, ready_waits_for_valid=ready_waits_for_valid)
    assert result["received"] == beats
    assert result["cycles"] == len(beats) + latency, f"{result['cycles']} clocks"


def check_capacity(make, ready_waits_for_valid, capacity):
    beats = beats_of(20, 2)
    result = run(make(), beats, ready_waits_for_valid=ready_waits_for_valid, stall=30)
    assert result["taken_in_stall"] == capacity, f"took {result['taken_in_stall']} beats"
    assert result["received"] == beats


@pytest.mark.parametrize("part,latency", [*((name, 3) for name in QUEUES), ("slice", 1)])
def test_full_rate(part, latency):
    """Without idle cycles or backpressure a beat per clock, after the part's latency."""
    check_full_rate(*PARTS[part], latency)


@pytest.mark.parametrize("part,capacity", [*((name, DEPTH) for name in QUEUES),
                                           ("slice", 2)])
def test_holds_its_capacity_while_stalled(part, capacity):
    """A source that always offers and a sink that takes nothing for 30 clocks: the part
    takes exactly as many beats as it holds, then hands all of them on in order."""
    check_capacity(*PARTS[part], capacity)


def test_queue_parameters_are_checked():
    for depth in (2, 6):
        refused_quietly(lambda: InputQueue(WIDTH, depth, LANES), ValueError,
                        "power of two >= 4")
    for lanes in ([(0, 8), (8, 16)], [(0, 10), (8, 18)]):
        refused_quietly(lambda: InputQueue(WIDTH, DEPTH, lanes), ValueError,
                        "cover every bit of the payload once")
    refused_quietly(lambda: InputQueue(WIDTH, DEPTH, LANES, registered_heads=[1, 3, -1]),
                    ValueError, re.escape("registered_heads [-1, 3] must index lanes (0 to 2)"))


# Deliberately wrong components must fail the checks above -----------------------------

class AlwaysReadyQueue(InputQueue):
    """Takes a beat whether or not it has room."""

    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.sink.ready.eq(1)
        return m


class LaneLosingQueue(InputQueue):
    """Loses the framing lane (the top two bits) on the way through."""

    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.source.payload[16:].eq(0)
        return m


class SkidDroppingSlice(RegisterSlice):
    """Takes a beat even when its skid register is full."""

    def elaborate(self, platform):
        m = super().elaborate(platform)
        m.d.comb += self.sink.ready.eq(1)
        return m


class PlainRegister(wiring.Component):
    """A register that loads every clock, stalled or not: no skid, and ``ready`` passed
    through."""

    def __init__(self):
        super().__init__({"sink": In(stream.Signature(WIDTH)),
                          "source": Out(stream.Signature(WIDTH))})

    def elaborate(self, platform):
        m = Module()
        head = Signal(WIDTH)
        m.d.sync += [head.eq(self.sink.payload), self.source.valid.eq(self.sink.valid)]
        m.d.comb += [self.source.payload.eq(head), self.sink.ready.eq(self.source.ready)]
        return m


class OneEntrySlice(wiring.Component):
    """A correct but slow buffer: one register, ready only while it is empty."""

    def __init__(self):
        super().__init__({"sink": In(stream.Signature(WIDTH)),
                          "source": Out(stream.Signature(WIDTH))})

    def elaborate(self, platform):
        m = Module()
        with m.If(self.source.valid & self.source.ready):
            m.d.sync += self.source.valid.eq(0)
        with m.If(self.sink.valid & self.sink.ready):
            m.d.sync += [self.source.payload.eq(self.sink.payload), self.source.valid.eq(1)]
        m.d.comb += self.sink.ready.eq(~self.source.valid)
        return m


@pytest.mark.parametrize("broken,waits", [
    (lambda: AlwaysReadyQueue(WIDTH, DEPTH, LANES), True),
    (lambda: SkidDroppingSlice(WIDTH), False),
    (PlainRegister, False),
], ids=["queue without room", "slice dropping its skid", "plain register"])
def test_broken_parts_lose_beats(broken, waits):
    with pytest.raises(AssertionError, match="received|changed or was withdrawn"):
        check_scenario(broken, waits, "burst", 0.0, 0.5)
    with pytest.raises(AssertionError):
        check_scenario(broken, waits, "sink paused at start", 0.0, 0.0)


@pytest.mark.parametrize("part", ["queue, framing head registered", "queue, heads registered"])
def test_broken_registered_head_is_caught(part, monkeypatch):
    """A registered head loaded from the entries as they are, not as they will be: a beat
    written in the clock the head moves onto its entry is missed."""
    monkeypatch.setattr(stream_parts, "_next_entries", lambda word, entries, enables: entries)
    with pytest.raises(AssertionError, match="received|changed or was withdrawn"):
        check_scenario(*PARTS[part], "burst", 0.5, 0.5)


def test_broken_lane_is_caught():
    with pytest.raises(AssertionError, match="received"):
        check_scenario(lambda: LaneLosingQueue(WIDTH, DEPTH, LANES), True, "burst", 0.0, 0.0)


def test_broken_rate_is_caught():
    with pytest.raises(AssertionError, match="clocks"):
        check_full_rate(OneEntrySlice, False, 1)


def test_broken_capacity_is_caught():
    with pytest.raises(AssertionError, match="took|changed or was withdrawn"):
        check_capacity(lambda: AlwaysReadyQueue(WIDTH, DEPTH, LANES), True, DEPTH)


class CheckingInInit(InputQueue):
    """Checks its depth in ``__init__``, after the object exists."""

    def __new__(cls, *args):
        return super(InputQueue, cls).__new__(cls)

    def __init__(self, shape, depth, lanes):
        if depth != DEPTH:
            raise ValueError("depth must be a power of two >= 4")
        super().__init__(shape, depth, lanes)


def test_a_refusal_that_leaves_an_object_is_caught():
    with pytest.raises(AssertionError, match="left behind"):
        refused_quietly(lambda: CheckingInInit(WIDTH, 2, LANES), ValueError, "power of two")
