"""One core as a package for the user's flow: its Verilog, the FuseSoC core, the IP-XACT
component and the Platform Designer component, in one folder.

Everything is generated in memory first (elaboration, the golden model of the test
frame), then written file by file, each atomically (:mod:`npstereo.gen.atomic`): a
configuration the hardware refuses leaves nothing behind.
"""

import dataclasses
import re
from importlib.metadata import version

from ...hdl.verilog import TOP_NAME, core_verilog, header
from ...params import UserError
from ..atomic import write_text
from .fusesoc import core_text
from .ipxact import component_xml
from .platform_designer import hw_tcl
from .testbench import EXPECTED, STIMULUS, TB_TOP, testbench_files

__all__ = ["CORE_FILE", "COMPONENT_FILE", "HW_TCL_FILE", "VERILOG_FILE", "default_vlnv",
           "parse_vlnv", "metadata", "package_files", "write_package"]

VERILOG_FILE = f"{TOP_NAME}.v"
CORE_FILE = "npstereo.core"
COMPONENT_FILE = "component.xml"
HW_TCL_FILE = f"{TOP_NAME}_hw.tcl"

#: What FuseSoC and IP-XACT accept in one part of a VLNV (vendor, library, name, version).
_VLNV_PART = re.compile(r"^[A-Za-z0-9_.+-]+$")


def default_vlnv():
    return f"npstereo:stereo:{TOP_NAME}:{version('npstereo')}"


def parse_vlnv(text):
    """``vendor:library:name:version`` as a 4-tuple, or a one-line error."""
    parts = text.split(":")
    if len(parts) != 4 or not all(_VLNV_PART.match(part) for part in parts):
        raise UserError(f"--vlnv must be VENDOR:LIBRARY:NAME:VERSION, each of letters, "
                        f"digits and _.+-, not {text!r}")
    return tuple(parts)


def metadata(params):
    """(name, value) of every generation parameter the configuration sets, and the
    generator's version: what the components record."""
    values = [(name, value) for name, value in dataclasses.asdict(params).items()
              if value is not None]
    if params.lr_threshold is None:
        values.append(("lr_check", "off"))
    return [("npstereo_version", version("npstereo")), *values]


def package_files(params, vlnv):
    """{file name: text} of the package of ``params`` named ``vlnv`` (a 4-tuple)."""
    description = (f"npstereo stereo core {params.describe()} (AXI4-Stream video in and "
                   "out)")
    meta = metadata(params)
    files = {VERILOG_FILE: core_verilog(params)}
    bench = testbench_files(params)
    files.update(bench)
    sources = [name for name in bench if name.endswith(".v")]
    comments = ["npstereo core package: " + description,
                *(line.removeprefix("// ") for line in header(params).splitlines())]
    files[CORE_FILE] = core_text(":".join(vlnv), description, [VERILOG_FILE], sources,
                                 [STIMULUS, EXPECTED], TOP_NAME, TB_TOP, comments)
    files[COMPONENT_FILE] = component_xml(params, meta, [VERILOG_FILE], TOP_NAME, vlnv,
                                          description)
    files[HW_TCL_FILE] = hw_tcl(params, meta, [VERILOG_FILE], TOP_NAME, vlnv[3], description)
    return files


def write_package(out, params, vlnv):
    """Write the package into the folder ``out``; returns the paths written."""
    files = package_files(params, vlnv)
    paths = []
    for name, text in files.items():
        write_text(out / name, text)
        paths.append(out / name)
    return paths
