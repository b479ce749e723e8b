"""Drive the core in Amaranth's simulator: input beats in, output words out.

One testbench coroutine plays both the source and the sink of
:class:`~npstereo.hdl.core.NpStereoCore`'s streams, clock by clock, so that random valid
gaps and random backpressure cost no extra simulator processes. Beats go in as structured
payloads (the layouts of :mod:`npstereo.hdl.stream`); output words come back as integers and
are decoded as the co-simulation decodes them (:func:`npstereo.sim.frames.decode_map`).
"""

import gc
import random
import warnings

import numpy as np
import pytest
from amaranth.hdl import Fragment, Module, ResetInserter, Signal, UnusedElaboratable, Value
from amaranth.lib import memory
from amaranth.sim import Simulator

from npstereo.golden.lr_check import INVALID
from npstereo.golden.pipeline import disparity_map
from npstereo.hdl.core import NpStereoCore
from npstereo.sim.frames import decode_map

__all__ = ["frame_beats", "run_scenario", "decode_frames", "first_mismatch", "check_frames",
           "RESET", "refused_quietly", "simulate"]

#: A marker in the beat list: assert ``rst`` for one clock at this point of the input.
RESET = "reset"


def frame_beats(left, right, *, drop_last_at=None):
    """Input beats ``(pixels, first, last)`` of one frame, ``pixels`` the fields of a
    :class:`~npstereo.hdl.stream.PixelPair`; optionally a missing ``last``.

    ``drop_last_at`` is a row whose end-of-line flag is left out (a line that seems too long).
    """
    height, width = left.shape
    beats = []
    for y in range(height):
        for x in range(width):
            last = x == width - 1 and y != drop_last_at
            pixels = {"left": int(left[y, x]), "right": int(right[y, x])}
            beats.append((pixels, x == 0 and y == 0, last))
    return beats


def run_scenario(params, beats, *, valid_prob=1.0, ready_prob=1.0, seed=0, max_cycles=None,
                 before_start=None, watch=None):
    """Feed ``beats`` (RESET markers: a reset; an int n: n idle clocks) through a core;
    collect every output word.

    The source keeps a beat offered until it is taken (stream rule) but inserts random gaps
    before offering the next; the sink drops ``ready`` at random. ``before_start(ctx)``
    runs in the testbench before the first clock. ``watch(dut)`` names signals of the core
    to sample in every clock.

    Returns
    -------
    dict
        ``words`` (list of (word, first, last), the word an integer), ``errors``
        (framing-error pulses), ``frame_starts`` (clock of every output word with
        ``first``), ``cycles`` (clocks until the last word came out), ``last_input`` (the
        clock the last beat was taken), ``latency`` (the core's, in positions), and with
        ``watch`` ``watched`` (the watched signals' values, a tuple per clock).
    """
    dut = NpStereoCore(params)
    watched_signals = [] if watch is None else watch(dut)
    sink, source = dut.sink, dut.source
    rst = Signal()
    top = ResetInserter({"sync": rst})(dut)
    rng = random.Random(seed)
    words, starts, state = [], [], {"errors": 0, "cycles": 0, "watched": []}
    beats = list(beats)
    expected = sum(1 for b in beats if b != RESET and not isinstance(b, int))
    slack = 4 * dut.latency * params.rounds + 50
    limit = max_cycles or int((expected * params.rounds + slack * 3)
                              / min(valid_prob, ready_prob) + slack)

    async def bench(ctx):
        if before_start is not None:
            before_start(ctx)
        index, cycle, last_word_cycle, offering = 0, 0, 0, False
        state["last_input"] = None
        while cycle < limit:
            if index < len(beats) and beats[index] == RESET:
                ctx.set(sink.valid, 0)
                ctx.set(source.ready, 0)
                ctx.set(rst, 1)
                await ctx.tick()
                ctx.set(rst, 0)
                index, offering = index + 1, False
                cycle += 1
                continue
            if index < len(beats) and isinstance(beats[index], int) and beats[index] > 0:
                # An idle gap: no beat offered for that many clocks.
                beats[index] -= 1
                if not beats[index]:
                    index += 1
                offering = False
            elif not offering and index < len(beats):
                offering = rng.random() < valid_prob
            if offering:
                pixels, first, last = beats[index]
                ctx.set(sink.payload, {"data": pixels, "first": first, "last": last})
            ctx.set(sink.valid, offering)
            ready = rng.random() < ready_prob
            ctx.set(source.ready, ready)
            if offering and ctx.get(sink.ready):
                index, offering = index + 1, False
                state["last_input"] = cycle
            if ready and ctx.get(source.valid):
                word = (ctx.get(source.payload.data.as_value()), ctx.get(source.payload.first),
                        ctx.get(source.payload.last))
                words.append(word)
                if word[1]:
                    starts.append(cycle)
                last_word_cycle = cycle
            state["errors"] += ctx.get(dut.framing_error)
            if watched_signals:
                state["watched"].append(tuple(ctx.get(s) for s in watched_signals))
            await ctx.tick()
            cycle += 1
            if index >= len(beats) and cycle > last_word_cycle + slack:
                break
        state["cycles"] = last_word_cycle + 1

    simulate(top, bench)
    return {"words": words, "frame_starts": starts, "latency": dut.latency, **state}


def simulate(top, bench):
    """Run the testbench coroutine ``bench`` on ``top`` with a 100 MHz ``sync`` clock."""
    sim = Simulator(top)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()


def check_frames(params, pairs, beats, **kwargs):
    """Run ``beats``; compare the last len(pairs) output frames with the golden maps.

    Fails (AssertionError) with "... pixels differ ..." naming the first differing pixel,
    or with "only N output frames".
    """
    result = run_scenario(params, beats, **kwargs)
    frames = decode_frames(result["words"], params)
    assert len(frames) >= len(pairs), f"only {len(frames)} output frames"
    for n, ((left, right), got) in enumerate(zip(pairs, frames[-len(pairs):])):
        expected = disparity_map(left, right, params).disparity
        mismatch = first_mismatch(expected, got)
        assert mismatch is None, f"frame {n} of {params.describe()}: {mismatch}"
    return result


def simulate_and_compare(dut, testbench, got, expected, what):
    """Run ``testbench`` on ``dut`` and compare every value it put into ``got`` (keyed by
    index into ``expected``), which must be all of them."""
    simulate(dut, testbench)
    assert len(got) == expected.size, f"not every {what[:-1]} was compared"
    mismatches = [(key, value, int(expected[key])) for key, value in sorted(got.items())
                  if value != expected[key]]
    assert not mismatches, (f"{len(mismatches)} {what} differ, first ((y, x, d), got, "
                            f"expected): {mismatches[0]}")


def decode_frames(words, params):
    """Split output words at ``first`` into H x W int16 maps (INVALID where not valid, -2
    where missing)."""
    frames, current = [], None
    for word, first, _ in words:
        if first:
            current = []
            frames.append(current)
        if current is not None:
            current.append(word)
    return [decode_map(values, params, missing=INVALID - 1) for values in frames]


def first_mismatch(expected, got):
    """None, or a message with the first differing pixel (raster order)."""
    diff = np.argwhere(expected != got)
    if len(diff) == 0:
        return None
    y, x = diff[0]
    return (f"{len(diff)} pixels differ; first at x={x}, y={y}: expected "
            f"{expected[y, x]}, got {got[y, x]}")


def refused_quietly(make, error, match):
    """``make()`` raises ``error`` (message matching ``match``) and leaves no object behind
    that Amaranth would report as created but never used."""
    # Amaranth reports unused elaboratables only once something has been elaborated.
    Fragment.get(Module(), None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(error, match=match):
            make()
        gc.collect()
    unused = [str(w.message) for w in caught if issubclass(w.category, UnusedElaboratable)]
    assert not unused, f"left behind: {unused}"


def record_memories(monkeypatch):
    """Every Amaranth ``Memory`` made from now on, in a list that fills as designs are
    built (tests fill them with random words: nothing may rely on what a memory holds
    before it is written)."""
    made = []
    create = memory.Memory.__init__

    def recording(self, *args, **kwargs):
        create(self, *args, **kwargs)
        made.append(self)

    monkeypatch.setattr(memory.Memory, "__init__", recording)
    return made


def random_contents(made, rng, member, mark):
    """A ``before_start`` hook that fills every memory in ``made`` with random words, then
    calls ``mark(ctx, word)`` on the words of memories whose shape has ``member`` (to make
    stale words look as harmful as they can)."""
    def fill(ctx):
        for store in made:
            for row in range(store.depth):
                word = store.data[row]
                bits = len(Value.cast(word))
                ctx.set(Value.cast(word), int(rng.integers(0, 1 << min(bits, 62))))
                if member in getattr(store.shape, "members", {}):
                    mark(ctx, word)
    return fill


def choose_bank_early(monkeypatch, suffix="_bank", clocks=None):
    """Break :mod:`npstereo.hdl.banks`: the digits of the bank index whose register chain
    ends in ``suffix`` arrive a clock early (``clocks`` registers instead of their own
    count less one, or exactly ``clocks``), so words come from the bank of the next
    address."""
    from npstereo.hdl import banks
    real_pipe = banks.pipe

    def early(m, value, steps, name, reset=False):
        if name.endswith(suffix):
            steps = steps - 1 if clocks is None else clocks
        return real_pipe(m, value, steps, name, reset)
    monkeypatch.setattr(banks, "pipe", early)
