"""Logic depth of the worst register-to-register path of a technology-mapped netlist.

Place and route gives the real clock, but not for a design that does not fit the ECP5 and
not for the Cyclone V (no open place and route). The depth of the deepest path between two
registers, in LUT levels, is the timing figure that exists for every synthesis result: it
is read from the netlist Yosys writes after technology mapping (``write_json``), at a cost
of seconds, with no placement.

How a path is counted (``docs/synthesis-flow.md``):

* A path starts at a register or block-RAM output (flip-flop ``Q``, ``DP16KD``/M10K read
  data, the stored side of a LUT RAM) and ends at any register or RAM input other than
  the clock (data, enable, reset, address). Paths from or to top-level ports are left out:
  they are unconstrained I/O.
* Every LUT passed counts one level (``LUT4``, ``MISTRAL_ALUT2..6``, ``MISTRAL_NOT``; a
  LUT-RAM read through its read address; a DSP block).
* The ECP5 wide-function multiplexers ``PFUMX``/``L6MUX21`` count one level only when
  entered through their select input (a signal from the routing): their data inputs come
  from the LUTs in the same slice, so a LUT5/6 built from LUT4s counts as one level, the
  way a Cyclone V ALUT6 does.
* A carry chain counts one level where the path enters it (the carry cell's LUT), plus a
  fraction per further carry cell passed on the dedicated carry wire: the cell's carry
  delay divided by the delay of one LUT level with its routing. With the delays below, a
  32-bit ECP5 adder (16 ``CCU2C``) is 1 + 15 x 0.071 = 2.1 levels; a 32-bit Cyclone V
  adder (32 ``MISTRAL_ALUT_ARITH``) is 1 + 31 x 0.036 = 2.1 levels. Counting each carry
  cell as a level would make a counter look like 16 LUTs deep, which its delay is not.
"""


__all__ = ["CARRY_WEIGHT", "logic_depth"]

# Delays (ns) behind the carry weights. Carry, per carry cell on the dedicated carry wire:
# ECP5 CCU2C (two bits) FCI->FCO 0.071 ns in nextpnr-ecp5 0.11's timing model (default
# speed grade, as its critical-path reports show it); Cyclone V MISTRAL_ALUT_ARITH (one
# bit) CI->CO 36 ps in Yosys 0.70's share/intel_alm/common/alm_sim.v (there is no open
# Cyclone V timing model besides it). One LUT level: a LUT plus one short routed
# connection, 1.0 ns on both: ECP5 LUT4 0.24-0.45 ns in nextpnr's reports plus about
# 0.6 ns of routing (nextpnr's short connections in our reports: 0.13-1.6 ns); Cyclone V
# ALUT6 0.4-0.6 ns (alm_sim.v) plus about 0.45 ns. The routing part is an assumption: the
# real one depends on placement, which is exactly what this figure does without.
_LEVEL_NS = {"ecp5": 1.0, "cyclonev": 1.0}
_CARRY_NS = {"ecp5": 0.071, "cyclonev": 0.036}

#: Levels added per carry cell passed on the carry wire, per target.
CARRY_WEIGHT = {target: round(_CARRY_NS[target] / _LEVEL_NS[target], 3)
                for target in _LEVEL_NS}

# Per cell type: ``start`` outputs (clock-to-out, level 0), ``end`` inputs (path ends),
# and combinational ``arcs`` (inputs, outputs, kind) with kind "lut" (one level),
# "carry" (CARRY_WEIGHT) or "free" (no level: inside the slice).
_CLOCKS = {"CLK", "CLKA", "CLKB", "CLK1", "WCK", "CLKR", "CLKW"}
_ECP5 = {
    "LUT4": {"arcs": [({"A", "B", "C", "D"}, {"Z"}, "lut")]},
    "PFUMX": {"arcs": [({"ALUT", "BLUT"}, {"Z"}, "free"), ({"C0"}, {"Z"}, "lut")]},
    "L6MUX21": {"arcs": [({"D0", "D1"}, {"Z"}, "free"), ({"SD"}, {"Z"}, "lut")]},
    "CCU2C": {"arcs": [({"A0", "B0", "C0", "D0", "A1", "B1", "C1", "D1"},
                        {"S0", "S1", "COUT"}, "lut"),
                       ({"CIN"}, {"S0", "S1", "COUT"}, "carry")]},
    "TRELLIS_FF": {"start": {"Q"}, "end": "*"},
    "DP16KD": {"start": "*", "end": "*"},
    "PDPW16KD": {"start": "*", "end": "*"},
    "TRELLIS_DPR16X4": {"start": {"DO"}, "end": {"DI", "WAD", "WRE"},
                        "arcs": [({"RAD"}, {"DO"}, "lut")]},
}
_CYCLONEV = {
    **{f"MISTRAL_ALUT{n}": {"arcs": [("*", {"Q"}, "lut")]} for n in range(2, 7)},
    "MISTRAL_NOT": {"arcs": [("*", {"Q"}, "lut")]},
    "MISTRAL_ALUT_ARITH": {"arcs": [({"A", "B", "C", "D0", "D1"}, {"SO", "CO"}, "lut"),
                                    ({"CI"}, {"SO", "CO"}, "carry")]},
    "MISTRAL_FF": {"start": {"Q"}, "end": "*"},
    "MISTRAL_M10K": {"start": "*", "end": "*"},
    "MISTRAL_MLAB": {"start": {"B1DATA"}, "end": {"A1ADDR", "A1DATA", "A1EN"},
                     "arcs": [({"B1ADDR"}, {"B1DATA"}, "lut")]},
    "MISTRAL_CLKBUF": {"arcs": [("*", "*", "free")]},
}
_MODELS = {"ecp5": _ECP5, "cyclonev": _CYCLONEV}
# Cells without ports that matter for timing.
_IGNORED = {"$scopeinfo"}


def _top(netlist):
    modules = netlist["modules"]
    for module in modules.values():
        if str(module.get("attributes", {}).get("top", "0")).strip("0 ") not in ("",):
            return module
    if len(modules) == 1:
        return next(iter(modules.values()))
    raise ValueError("netlist has no top module")


def _ports(selection, directions, direction):
    names = [p for p, d in directions.items() if d == direction or
             (direction == "input" and d == "inout")]
    if selection == "*":
        return set(names)
    return set(selection or ()) & set(names)


def logic_depth(netlist, target):
    """Deepest register-to-register path of a mapped netlist, in LUT levels.

    Parameters
    ----------
    netlist : dict
        Yosys ``write_json`` netlist after ``synth_ecp5``/``synth_intel_alm`` (flattened).
    target : str
        ``ecp5`` or ``cyclonev``: selects the cell timing classes and the carry weight.

    Returns
    -------
    dict
        ``levels`` (float, rounded to 0.1; 0 when registers feed registers directly,
        None when the design has no register-to-register path), ``luts`` and
        ``carry_cells`` on that path, ``from``/``to`` (``"<cell> (<type>.<port>)"``),
        ``cells`` (the path's combinational cells, in order) and ``unmodelled`` (cell types
        treated conservatively as one LUT level from every input to every output).
    """
    model = _MODELS[target]
    weight = {"lut": 1.0, "free": 0.0, "carry": CARRY_WEIGHT[target]}
    module = _top(netlist)
    cells = module["cells"]
    start_bits = {}            # bit -> (cell, port): a path may start here at level 0
    driver_arcs = {}           # bit -> list of (cell, kind, input bits)
    end_points = []            # (bit, cell, port)
    unmodelled = set()
    for name, cell in cells.items():
        kind = cell["type"]
        if kind in _IGNORED:
            continue
        directions = cell.get("port_directions", {})
        spec = model.get(kind)
        if spec is None:
            unmodelled.add(kind)
            spec = {"arcs": [("*", "*", "lut")]}
        connections = cell["connections"]
        for port in _ports(spec.get("start"), directions, "output"):
            for bit in connections.get(port, []):
                if isinstance(bit, int):
                    start_bits[bit] = (name, port)
        for port in _ports(spec.get("end"), directions, "input") - _CLOCKS:
            for bit in connections.get(port, []):
                if isinstance(bit, int):
                    end_points.append((bit, name, port))
        for inputs, outputs, arc_kind in spec.get("arcs", []):
            in_bits = [bit for port in _ports(inputs, directions, "input") - _CLOCKS
                       for bit in connections.get(port, []) if isinstance(bit, int)]
            for port in _ports(outputs, directions, "output"):
                for bit in connections.get(port, []):
                    if isinstance(bit, int):
                        driver_arcs.setdefault(bit, []).append((name, arc_kind, in_bits))
    arrival, via = _arrivals(start_bits, driver_arcs, weight)
    best = None
    for bit, name, port in end_points:
        level = arrival.get(bit)
        if level is not None and (best is None or level > best[0] + 1e-9):
            best = (level, bit, name, port)
    if best is None:
        return {"levels": None, "luts": 0, "carry_cells": 0, "from": None, "to": None,
                "cells": [], "unmodelled": sorted(unmodelled)}
    level, bit, end_cell, end_port = best
    path = []
    while bit in via:
        name, kind, bit = via[bit]
        path.append((name, kind))
    path.reverse()
    start_cell, start_port = start_bits[bit]
    kinds = [kind for _, kind in path]
    return {"levels": round(level, 1), "luts": kinds.count("lut"),
            "carry_cells": kinds.count("carry"),
            "from": f"{start_cell} ({cells[start_cell]['type']}.{start_port})",
            "to": f"{end_cell} ({cells[end_cell]['type']}.{end_port})",
            "cells": [name for name, _ in path], "unmodelled": sorted(unmodelled)}


def _arrivals(start_bits, driver_arcs, weight):
    """Longest arrival (levels) of every bit reachable from a start point.

    Iterative depth-first evaluation (designs have paths far deeper than Python's
    recursion limit would allow for a recursive one). A bit driven only from top-level
    inputs or constants has no arrival. A register output starts at 0, and where it also
    has a combinational arc (a LUT RAM read through its address) the later arrival wins.
    A combinational loop (none in a synthesised synchronous design) is cut where it
    closes.
    """
    arrival, via = {}, {}
    done, active = set(), set()
    for root in list(driver_arcs) + list(start_bits):
        stack = [root]
        while stack:
            bit = stack[-1]
            if bit in done:
                stack.pop()
                continue
            if bit in driver_arcs and bit not in active:
                active.add(bit)
                stack.extend(b for _, _, ins in driver_arcs[bit] for b in ins
                             if b not in done and b not in active)
                continue
            stack.pop()
            active.discard(bit)
            done.add(bit)
            if bit in start_bits:
                arrival[bit] = 0.0
            for name, kind, ins in driver_arcs.get(bit, ()):
                for source in ins:
                    if arrival.get(source) is None:
                        continue
                    candidate = arrival[source] + weight[kind]
                    if arrival.get(bit) is None or candidate > arrival[bit] + 1e-9:
                        arrival[bit] = candidate
                        via[bit] = (name, kind, source)
    return arrival, via
