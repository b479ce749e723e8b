"""``component.xml``: the core as an IEEE 1685-2014 (IP-XACT) component.

Bus interfaces use the bus definitions every IP-XACT catalogue with AMD/Xilinx IP knows:
``xilinx.com:interface:axis:1.0`` for the two AXI4-Stream ports (abstraction
``axis_rtl``), ``xilinx.com:signal:clock:1.0`` and ``...:reset:1.0`` for the clock and the
active-high reset; ``framing_error`` is a plain port. The configuration the Verilog was
generated for is recorded as the component's parameters (fixed values, not generics: the
Verilog has none), string values quoted as 1685-2014 expressions require.
"""

import xml.etree.ElementTree as ET

from .ports import CLOCK, FRAMING_ERROR, RESET, STREAMS, stream_ports

__all__ = ["NAMESPACE", "SCHEMA_LOCATION", "component_xml"]

NAMESPACE = "http://www.accellera.org/XMLSchema/IPXACT/1685-2014"
SCHEMA_LOCATION = f"{NAMESPACE} {NAMESPACE}/index.xsd"
_XSI = "http://www.w3.org/2001/XMLSchema-instance"
_XILINX = {"vendor": "xilinx.com", "version": "1.0"}


def _tag(name):
    return f"{{{NAMESPACE}}}{name}"


def _add(parent, tag, text=None, **attributes):
    element = ET.SubElement(parent, _tag(tag), attributes)
    if text is not None:
        element.text = str(text)
    return element


def _bus_interface(parent, name, library, bus, mode, port_map, parameters=()):
    """A bus interface: the bus type, its RTL abstraction mapping logical to physical
    ports, the mode (slave/master), and its parameters."""
    interface = _add(parent, "busInterface")
    _add(interface, "name", name)
    _add(interface, "busType", library=library, name=bus, **_XILINX)
    abstraction = _add(_add(interface, "abstractionTypes"), "abstractionType")
    _add(abstraction, "abstractionRef", library=library, name=f"{bus}_rtl", **_XILINX)
    maps = _add(abstraction, "portMaps")
    for logical, physical in port_map:
        port_map_element = _add(maps, "portMap")
        _add(_add(port_map_element, "logicalPort"), "name", logical)
        _add(_add(port_map_element, "physicalPort"), "name", physical)
    _add(interface, mode)
    if parameters:
        _parameters(interface, parameters, prefix=f"BUSIFPARAM_{name}_")


def _parameters(parent, values, prefix="PARAM_"):
    """``parameters`` with one fixed parameter per (name, value); strings quoted."""
    element = _add(parent, "parameters")
    for name, value in values:
        parameter = _add(element, "parameter", parameterId=f"{prefix}{name}",
                         resolve="immediate")
        _add(parameter, "name", name)
        _add(parameter, "value", f'"{value}"' if isinstance(value, str) else value)


def _port(ports, port):
    element = _add(ports, "port")
    _add(element, "name", port.name)
    wire = _add(element, "wire")
    _add(wire, "direction", port.direction)
    if port.width > 1:
        vector = _add(_add(wire, "vectors"), "vector")
        _add(vector, "left", port.width - 1)
        _add(vector, "right", 0)


def component_xml(params, metadata, files, top, vlnv, description):
    """Text of ``component.xml``.

    Parameters
    ----------
    params : StereoParams
        The configuration (fixes the AXI4-Stream data widths).
    metadata : list of (name, value)
        The generation parameters, recorded as the component's parameters.
    files : list of str
        The synthesizable Verilog files, relative to the component file.
    top : str
        The Verilog module.
    vlnv : (vendor, library, name, version)
    description : str
    """
    ET.register_namespace("ipxact", NAMESPACE)
    ET.register_namespace("xsi", _XSI)
    root = ET.Element(_tag("component"), {f"{{{_XSI}}}schemaLocation": SCHEMA_LOCATION})
    for field, value in zip(("vendor", "library", "name", "version"), vlnv):
        _add(root, field, value)
    interfaces = _add(root, "busInterfaces")
    for name, receives in STREAMS:
        _bus_interface(interfaces, name, "interface", "axis", "slave" if receives else "master",
                       [(port.role, port.name) for port in stream_ports(params, name)])
    streams = ":".join(name for name, _ in STREAMS)
    _bus_interface(interfaces, "clk", "signal", "clock", "slave", [(CLOCK.role, CLOCK.name)],
                   [("ASSOCIATED_BUSIF", streams), ("ASSOCIATED_RESET", RESET.name)])
    _bus_interface(interfaces, "rst", "signal", "reset", "slave", [(RESET.role, RESET.name)],
                   [("POLARITY", "ACTIVE_HIGH")])
    model = _add(root, "model")
    view = _add(_add(model, "views"), "view")
    _add(view, "name", "rtl")
    _add(view, "componentInstantiationRef", "verilog")
    instance = _add(_add(model, "instantiations"), "componentInstantiation")
    _add(instance, "name", "verilog")
    _add(instance, "language", "Verilog")
    _add(instance, "moduleName", top)
    _add(_add(instance, "fileSetRef"), "localName", "rtl")
    ports = _add(model, "ports")
    for port in (CLOCK, RESET, *(p for name, _ in STREAMS for p in stream_ports(params, name)),
                 FRAMING_ERROR):
        _port(ports, port)
    file_set = _add(_add(root, "fileSets"), "fileSet")
    _add(file_set, "name", "rtl")
    for path in files:
        file = _add(file_set, "file")
        _add(file, "name", path)
        _add(file, "fileType", "verilogSource")
    _add(root, "description", description)
    _parameters(root, metadata)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode", xml_declaration=True) + "\n"
