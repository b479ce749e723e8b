"""Synthesis of generated Verilog with Yosys (and nextpnr) for resource and timing figures.

Two targets stand in for the paper's Stratix II EP2S180:

``cyclonev``
    ``synth_intel_alm -family cyclonev``: ALUTs (``MISTRAL_ALUT*``), registers
    (``MISTRAL_FF``), M10K block RAMs and MLAB LUT RAMs.
``ecp5``
    ``synth_ecp5``: LUT4s (two per ``CCU2C`` carry cell), registers (``TRELLIS_FF``), DP16KD
    block RAMs, ``TRELLIS_DPR16X4`` LUT RAMs; optionally placed and routed by
    ``nextpnr-ecp5`` (on :data:`~.capacity.DEFAULT_DEVICE` unless another ECP5 part is
    asked for) for the achieved clock.

Yosys runs the script of :mod:`.yosys` natively or as WebAssembly (:mod:`.tools`). After
synthesis the ECP5 flow packs block-RAM output registers (:mod:`.bram_output_register`),
every result gets the logic depth of its worst register-to-register path
(:mod:`.logic_depth`), and an ECP5 result is checked against the ECP5 part's capacity
before place and route (:mod:`.capacity`, :mod:`.nextpnr`). ``docs/synthesis-flow.md``
describes the flow.
"""

import json
import shutil
import tempfile
import time
from pathlib import Path

from ...params import UserError
from ..atomic import write_text
from .bram_output_register import pack_outreg_file
from .capacity import DEFAULT_DEVICE, device as find_device, fit_message, utilisation
from .logic_depth import logic_depth
from .logs import carry_chains, cell_counts, memory_cells_bits, target_resources, time_split
from .nextpnr import Placement, place_and_route
from .processes import INTERRUPTED, run_tool
from .tools import TARGETS, chosen_engine, engine_version
from .yosys import synthesis_script, yosys_command

__all__ = ["synthesise"]


def synthesise(verilog, target, top, pnr=False, freq=100.0, timeout=None, keep=None,
               engine=None, outreg=True, device=DEFAULT_DEVICE, placement=Placement()):
    """Synthesise Verilog text for one target and return its figures.

    Parameters
    ----------
    verilog : str
        The design.
    target : str
        One of :data:`~.tools.TARGETS`.
    top : str
        Top module name.
    pnr : bool
        For ``ecp5``: also place and route (``nextpnr-ecp5`` on ``device``, package
        CABGA381) and report the achieved clock, unless the design is above the part's
        capacity (status ``does not fit``, nextpnr is not started). Ignored for
        ``cyclonev`` (no open place and route).
    freq : float
        Clock constraint for nextpnr in MHz.
    timeout : float or None
        Seconds for the whole run; past it the tool is killed and the status is ``timeout``.
    keep : path or None
        Build directory to keep (logs, netlists); a temporary one otherwise.
    engine : str or None
        One of :data:`~.tools.ENGINES`; None takes :func:`~.tools.default_engine`
        (``native`` when ``pyosys`` is installed, else ``wasm``).
    outreg : bool
        For ``ecp5``: pack the register behind each block-RAM read port into the DP16KD
        (``REGMODE = "OUTREG"``, :mod:`.bram_output_register`). False hands nextpnr Yosys's
        netlist unchanged (for comparisons).
    device : str
        For ``ecp5``: the ECP5 part of :data:`.capacity.DEVICES` whose capacity is checked
        and that nextpnr places on (default :data:`~.capacity.DEFAULT_DEVICE`, the
        LFE5U-85F).
    placement : Placement
        For ``ecp5`` with ``pnr``: nextpnr's placer seed and weight of timing and its
        router's weights (:class:`~.nextpnr.Placement`; nextpnr's own by default), recorded
        as ``seed``, ``placer_timing_weight`` and ``router_alt_weights``
        (docs/synthesis-flow.md).

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
          :mod:`.logic_depth`; None without such a path), and
          ``logic_levels_path``: ``from``, ``to``, ``luts``, ``carry_cells``, ``cells``;
        - ``utilisation`` (``ecp5``: percent of ``device`` per resource, ``LUT``,
          ``FF``, ``DP16KD``, ``DSP``, ``LUTRAM``; None for ``cyclonev``) and ``fits``
          (``ecp5``: all within 100 %; None for ``cyclonev``);
        - ``carry_chains`` (``ecp5``: CCU2C chains, :func:`~.logs.carry_chains`; each costs
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
    engine = chosen_engine(engine)
    command, log_name, tool = yosys_command(engine)
    started = time.monotonic()
    deadline = None if timeout is None else started + timeout
    identity = {"target": target, "engine": engine, "engine_version": engine_version(engine)}
    with tempfile.TemporaryDirectory(prefix=f"npstereo-{target}-") as scratch:
        build = Path(keep) if keep is not None else Path(scratch)
        build.mkdir(parents=True, exist_ok=True)
        write_text(build / "design.v", verilog)
        write_text(build / "synth.ys", synthesis_script(target, top))
        result = dict(identity, status="ok", message="", fmax_mhz=None)
        failure = run_tool(command, build, deadline, log_name, name=tool)
        if failure is None:
            # A failure from here on is place and route's: the synthesis figures stand.
            failure = _after_synthesis(result, target, build, pnr, freq, deadline, outreg,
                                       part, placement)
        else:
            result = dict(identity, fmax_mhz=None)
        if failure is not None:
            result.update(fmax_mhz=None, status=_status(failure),
                          message=failure if failure != "timeout" else
                          f"killed after {timeout:g} s")
    result["seconds"] = round(time.monotonic() - started, 1)
    return result


def _status(failure):
    """A failed run's status: ``timeout``, ``interrupted`` (a signal from outside stopped
    the tool; neither is cached) or ``failed``."""
    if failure == "timeout":
        return "timeout"
    return INTERRUPTED if failure.startswith(INTERRUPTED) else "failed"


def _after_synthesis(result, target, build, pnr, freq, deadline, outreg, part, placement):
    """Figures of a finished synthesis, packing and place and route; None or a failure."""
    result["yosys_time_split"] = time_split(build / "yosys.log")
    result.update(target_resources(target, cell_counts(build / "stat.json")))
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
    return place_and_route(result, build, part, freq, deadline, placement)

