"""The core as the device gets it: synthesised, packed and written back as Verilog.

:func:`mapped_netlist` runs the project's own flow (:func:`.synthesise.synthesise`: the
split ``synth_ecp5`` script with the DP16KD output registers packed by
:mod:`.bram_output_register`, or ``synth_intel_alm`` for the Cyclone V), then has Yosys
write the netlist that flow hands on (``netlist.json`` for the ECP5, what nextpnr reads;
``synth.json`` for the Cyclone V) back as Verilog. Simulated with the cell models of
:mod:`.cell_models`, that is a gate-level model of what reaches the device.

Synthesis takes seconds to minutes, so netlists are cached like simulation models:
``build/netlist/<hash>/``, the hash covering the family, the core's Verilog, the Yosys
script, the tool versions (:func:`.tools.tool_versions`, the flow's version among them)
and the source of the packing pass, behind a file lock for parallel test workers.
"""

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

from ...sim.build import locked
from ..atomic import write_text
from . import bram_output_register
from .cell_models import cell_library
from .synthesise import synthesise
from .tools import tool_versions
from .yosys import run_yosys, synthesis_script

__all__ = ["NetlistError", "Netlist", "mapped_netlist", "netlist_verilog",
           "default_netlist_root"]

#: What the flow hands on after synthesis (and, for the ECP5, packing).
_FLOW_OUTPUT = {"ecp5": "netlist.json", "cyclonev": "synth.json"}

#: The figures of the synthesis result kept with a cached netlist.
_KEPT = ("logic", "logic_unit", "registers", "block_rams", "block_ram_kind", "lut_rams",
         "dsps", "outreg_packed", "outreg_registers", "outreg_not_packed")


class NetlistError(RuntimeError):
    """Synthesis or writing the netlist failed; the message names the log."""


@dataclass
class Netlist:
    """A mapped netlist as Verilog, with the cell models it needs."""

    family: str
    verilog: str = field(repr=False)
    libraries: dict = field(repr=False)   # file name -> Verilog of the cell models
    figures: dict                          # cell counts, output-register packing
    directory: Path
    seconds: float = 0.0                   # synthesis and writing; 0 when cached

    def summary(self):
        """One line: the cells, and for the ECP5 the packed block-RAM output registers."""
        f = self.figures
        text = (f"{f['logic']} {f['logic_unit']}, {f['registers']} FF, "
                f"{f['block_rams']} {f['block_ram_kind']}, {f['lut_rams']} LUT RAM")
        if self.family == "ecp5":
            text += (f"; {f['outreg_packed']} DP16KD output registers packed "
                     f"({f['outreg_registers']} flip-flops absorbed)")
        return text


def default_netlist_root():
    return Path.cwd() / "build" / "netlist"


def _key(family, verilog, top, outreg):
    # The script and the pass as they are now, so that an edit re-synthesises.
    packing = Path(bram_output_register.__file__).read_text()
    text = json.dumps([family, verilog, top, synthesis_script(family, top), tool_versions(),
                       outreg, packing])
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def netlist_verilog(source):
    """A Yosys JSON netlist (``source``) as Verilog text, written by Yosys itself
    (``write_verilog``) into ``<source>.v`` next to it."""
    source = Path(source)
    target = source.with_suffix(".v")
    failure = run_yosys(f"read_json {source.name}\nwrite_verilog -noattr {target.name}\n",
                        source.parent, name=f"write_{source.stem}")
    if failure is not None:
        raise NetlistError(f"writing {source.name} as Verilog failed: {failure}; see "
                           f"{source.parent / f'write_{source.stem}.log'}")
    return target.read_text()


def mapped_netlist(verilog, family, top, build_root=None, outreg=True, timeout=None):
    """Synthesise ``verilog`` for ``family`` with the project's flow; the netlist as Verilog.

    Parameters
    ----------
    verilog : str
        The core's Verilog (:func:`npstereo.hdl.verilog.core_verilog`).
    family : str
        One of :data:`.cell_models.FAMILIES`.
    top : str
        Top module; the netlist keeps its name and ports.
    build_root : path, optional
        Cache folder (default ``build/netlist`` in the working directory).
    outreg : bool
        For the ECP5: pack the block-RAM output registers (the flow's default).
    timeout : float, optional
        Seconds for synthesis.

    Returns
    -------
    Netlist
    """
    libraries = cell_library(family)
    root = Path(build_root or default_netlist_root())
    directory = root / _key(family, verilog, top, outreg)
    done = directory / "netlist.v"
    with locked(directory / ".lock"):
        if done.exists():
            figures = json.loads((directory / "figures.json").read_text())
            return Netlist(family, done.read_text(), libraries, figures, directory)
        start = time.perf_counter()
        synth = directory / "synth"
        result = synthesise(verilog, family, top, keep=synth, outreg=outreg, timeout=timeout)
        if result["status"] != "ok":
            raise NetlistError(f"synthesis for {family} {result['status']}: "
                               f"{result['message']}; see {synth / 'yosys.log'}")
        text = netlist_verilog(synth / _FLOW_OUTPUT[family])
        figures = {name: result.get(name) for name in _KEPT}
        write_text(directory / "figures.json", json.dumps(figures))
        write_text(done, text)
        return Netlist(family, text, libraries, figures, directory,
                       time.perf_counter() - start)

