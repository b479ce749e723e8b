"""Pack ECP5 block-RAM output registers (``DP16KD`` ``REGMODE = "OUTREG"``).

Yosys 0.70 maps every ECP5 block RAM read port with ``REGMODE_A/B = "NOREG"``
(``techlibs/lattice/brams_map_16kd.txt``/``brams_map_16kd.v``; yosys issue #5814). A
DP16KD read without its output register has a 5.83 ns clock-to-output at the default speed
grade (0.97 ns with ``OUTREG``), so even a block RAM feeding one flip-flop misses 150 MHz.
The cores put a plain register behind every block-RAM read port; this pass moves that
register into the block RAM: for each read port whose every used ``DO`` bit drives exactly
one ``TRELLIS_FF`` ``DI`` input, and whose flip-flops match what the output register does,
it sets ``REGMODE`` to ``OUTREG``, connects ``OCE`` to the flip-flops' clock enable, drives
the flip-flops' outputs from ``DO`` and removes the flip-flops.

What the DP16KD output register does (Lattice's DP16KD simulation model, TN1264 *ECP5 and
ECP5-5G Memory Usage Guide*): on the port's clock edge (``CLKx`` through ``CLKxMUX``),
when ``OCEx`` is high, it loads the array output; ``RSTx`` clears it (``RESETMODE``
synchronous or asynchronous) and it powers up cleared. With a 36-bit read on port B
(``DATA_WIDTH_B = 36``, the pseudo-dual-port mode Yosys uses for 36-bit words) the
``DOA`` bits are port B's upper half: they are registered on ``CLKB``/``OCEB`` and
``REGMODE_A`` selects whether they come from that register. A flip-flop is therefore only
replaced when it is exactly such a register:

* same clock net and polarity as the port, and no set/reset (``LSR`` constant inactive):
  the block RAM's reset would also clear the array latch, so a port whose ``RSTx`` is used
  is left alone, and so is a flip-flop with a reset the port does not have;
* powers up to 0 (``REGSET = "RESET"``), as the output register does;
* one clock enable shared by all of the port's flip-flops, not inverted (``CEMUX`` ``CE``
  or ``1``), which becomes ``OCEx``;
* no ``GSR``/``SGSR`` cell in the design: a user global reset would clear the output
  register but not a flip-flop whose ``GSR`` is disabled;
* chip selects unused (``CSx`` constant 0, ``CSDECODE = "0b000"``), ``OCExMUX`` and
  ``RSTxMUX`` not inverted, and the flip-flop not marked ``keep``.

Anything else is left as it is and counted under a reason.
"""

import json
from collections import Counter, defaultdict
from pathlib import Path

from ..atomic import write_text

__all__ = ["pack_outreg", "pack_outreg_file", "read_ports"]

#: Cells that drive the global set/reset network.
_GSR_CELLS = ("GSR", "SGSR")


def _param_int(value):
    """Integer value of a parameter as Yosys's ``write_json`` writes it (bit string)."""
    if isinstance(value, int):
        return value
    text = str(value).strip()
    if text and set(text) <= {"0", "1"}:
        return int(text, 2)
    return int(text)


def _param_str(value):
    """String parameter; ``write_json`` pads strings that look like bits with a space."""
    return str(value).rstrip(" ") if isinstance(value, str) else str(value)


def _truthy(value):
    """An attribute set to a non-zero value (``write_json`` writes ``keep`` as bits)."""
    if value is None:
        return False
    try:
        return _param_int(value) != 0
    except ValueError:
        return bool(str(value).strip())


def _bit(cell, port):
    """The single bit connected to ``port`` (None when unconnected)."""
    bits = cell["connections"].get(port)
    return bits[0] if bits else None


def _const(bit, value):
    return bit is None and value == "0" or bit == value


def read_ports(cell):
    """Read ports of a DP16KD as ``(name, side, regmode params, DO port names)``.

    ``side`` is the letter of the port whose clock, enable and reset register the data. A
    36-bit read on B also owns ``DOA0..17`` (upper half, registered by B, selected by
    ``REGMODE_A``); a 36-bit read on A does not exist in the DP16KD.
    """
    width_b = _param_int(cell["parameters"].get("DATA_WIDTH_B", 18))
    do_a = [f"DOA{i}" for i in range(18)]
    do_b = [f"DOB{i}" for i in range(18)]
    if width_b == 36:
        return [("B", "B", ("REGMODE_A", "REGMODE_B"), do_a + do_b)]
    return [("A", "A", ("REGMODE_A",), do_a), ("B", "B", ("REGMODE_B",), do_b)]


def _loads(module):
    """bit -> list of (cell name or None for a module output, port) reading it."""
    loads = defaultdict(list)
    for name, cell in module["cells"].items():
        directions = cell.get("port_directions", {})
        for port, bits in cell["connections"].items():
            if directions.get(port, "input") != "output":
                for bit in bits:
                    if isinstance(bit, int):
                        loads[bit].append((name, port))
    for port, info in module.get("ports", {}).items():
        if info["direction"] != "input":
            for bit in info["bits"]:
                if isinstance(bit, int):
                    loads[bit].append((None, port))
    return loads


def _port_problem(cell, side):
    """Why a DP16KD port's settings rule out the output register, or None."""
    parameters = cell["parameters"]
    if not _const(_bit(cell, f"RST{side}"), "0") or \
            _param_str(parameters.get(f"RST{side}MUX", f"RST{side}")) != f"RST{side}":
        return "read port has a reset"
    if _param_str(parameters.get(f"CSDECODE_{side}", "0b000")) != "0b000" or not all(
            _const(_bit(cell, f"CS{side}{i}"), "0") for i in range(3)):
        return "chip select in use"
    if _param_str(parameters.get(f"OCE{side}MUX", f"OCE{side}")) != f"OCE{side}":
        return "output enable inverted"
    return None


def _register_signature(ff):
    """What of a flip-flop must equal across one port: clock, polarity, enable."""
    parameters = ff["parameters"]
    cemux = _param_str(parameters.get("CEMUX", "1"))
    enable = "1" if cemux == "1" else _bit(ff, "CE")
    return (_bit(ff, "CLK"), _param_str(parameters.get("CLKMUX", "CLK")), cemux, enable)


def _register_problem(ff):
    """Why a TRELLIS_FF is not a plain register the output register can replace."""
    parameters = ff["parameters"]
    if _truthy(ff.get("attributes", {}).get("keep")):
        return "register marked keep"
    lsr = _bit(ff, "LSR")
    lsrmux = _param_str(parameters.get("LSRMUX", "LSR"))
    if not ((lsrmux == "LSR" and _const(lsr, "0")) or (lsrmux == "INV" and lsr == "1")):
        return "register has a set/reset"
    if _param_str(parameters.get("REGSET", "RESET")) != "RESET":
        return "register initialised to 1"
    cemux = _param_str(parameters.get("CEMUX", "1"))
    if cemux not in ("1", "CE"):
        return "register enable inverted or constant"
    if cemux == "CE" and _bit(ff, "CE") is None:
        return "register enable unconnected"   # nothing defined to give OCE
    return None


def pack_outreg(netlist, top=None):
    """Pack output registers into the DP16KDs of ``netlist`` (a ``write_json`` dict).

    Parameters
    ----------
    netlist : dict
        Yosys JSON netlist after ``synth_ecp5`` (flattened); changed in place.
    top : str or None
        Module to work on; by default the one with the ``top`` attribute, or the only one.

    Returns
    -------
    dict
        ``packed`` (read ports given ``OUTREG``), ``registers`` (flip-flops removed),
        ``ports`` (read ports examined), ``not_packed`` (reason -> count) and ``packed_ports``
        (``"<cell>.<port>"`` names).
    """
    module = _top_module(netlist, top)
    cells = module["cells"]
    report = {"packed": 0, "registers": 0, "ports": 0, "not_packed": Counter(),
              "packed_ports": []}
    brams = [name for name, cell in cells.items() if cell["type"] == "DP16KD"]
    if not brams:
        report["not_packed"] = {}
        return report
    gsr = any(cell["type"] in _GSR_CELLS for cell in cells.values())
    loads = _loads(module)
    for name in brams:
        cell = cells[name]
        for port, side, regmodes, outputs in read_ports(cell):
            report["ports"] += 1
            reason, registers = _examine(cells, loads, cell, side, regmodes, outputs, gsr)
            if reason is not None:
                report["not_packed"][reason] += 1
                continue
            signature = _register_signature(cells[next(iter(registers.values()))])
            for regmode in regmodes:
                cell["parameters"][regmode] = "OUTREG"
            cell["connections"][f"OCE{side}"] = [signature[3]]
            for output, ff_name in registers.items():
                cell["connections"][output] = list(cells[ff_name]["connections"]["Q"])
                del cells[ff_name]
            report["packed"] += 1
            report["registers"] += len(registers)
            report["packed_ports"].append(f"{name}.{port}")
    report["not_packed"] = dict(report["not_packed"])
    return report


def _examine(cells, loads, cell, side, regmodes, outputs, gsr):
    """``(reason, {})`` when a read port cannot be packed, else ``(None, {DO: ff})``."""
    if gsr:
        return "design uses GSR", {}
    for regmode in regmodes:
        if _param_str(cell["parameters"].get(regmode, "NOREG")) != "NOREG":
            return "port already registered", {}
    problem = _port_problem(cell, side)
    if problem is not None:
        return problem, {}
    registers = {}
    for output in outputs:
        bit = _bit(cell, output)
        if not isinstance(bit, int) or not loads.get(bit):
            continue  # unused data bit
        users = loads[bit]
        if len(users) != 1:
            return "data bit has several loads", {}
        ff_name, ff_port = users[0]
        if ff_name is None or cells[ff_name]["type"] != "TRELLIS_FF" or ff_port != "DI":
            return "data bit drives logic, not a register", {}
        registers[output] = ff_name
    if not registers:
        return "read data unused (write-only port)", {}
    signatures = set()
    for ff_name in registers.values():
        problem = _register_problem(cells[ff_name])
        if problem is not None:
            return problem, {}
        signatures.add(_register_signature(cells[ff_name]))
    if len(signatures) != 1:
        return "registers differ in clock or enable", {}
    clock, clkmux, _, _ = signatures.pop()
    bram_clkmux = _param_str(cell["parameters"].get(f"CLK{side}MUX", f"CLK{side}"))
    if clock != _bit(cell, f"CLK{side}") or \
            (clkmux == "INV") != (bram_clkmux == "INV"):
        return "register on another clock", {}
    return None, registers


def _top_module(netlist, top):
    modules = netlist["modules"]
    if top is not None:
        return modules[top]
    tops = [m for m in modules.values() if _truthy(m.get("attributes", {}).get("top"))]
    if len(tops) == 1:
        return tops[0]
    if len(modules) == 1:
        return next(iter(modules.values()))
    raise ValueError("netlist has no single top module; name it")


def pack_outreg_file(source, target, top=None, log=None):
    """Pack the netlist file ``source`` and write the result to ``target`` atomically.

    ``log`` (a path) receives one line per packed port and a summary; returns the report
    of :func:`pack_outreg`.
    """
    netlist = json.loads(Path(source).read_text())
    report = pack_outreg(netlist, top)
    write_text(target, json.dumps(netlist))
    if log is not None:
        lines = [f"packed {port}" for port in report["packed_ports"]]
        lines.append(f"{report['packed']} of {report['ports']} DP16KD read ports packed "
                     f"({report['registers']} flip-flops absorbed)")
        lines += [f"not packed: {count} x {reason}"
                  for reason, count in sorted(report["not_packed"].items())]
        write_text(log, "\n".join(lines) + "\n")
    return report
