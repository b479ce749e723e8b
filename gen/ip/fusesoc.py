"""``npstereo.core``: the package as a FuseSoC CAPI2 core, and the generator core.

The core has three filesets (the synthesizable Verilog, the testbench, the testbench's
data files) and three targets (Edalize's flow API): ``default`` (the Verilog, for a user's core that depends
on this one), ``lint`` (Verilator ``--lint-only -Wall`` with the project's waivers, each
named in :mod:`npstereo.sim.tools` and :mod:`npstereo.sim.lint`) and ``sim`` (Icarus
runs the self-checking testbench of :mod:`.testbench`: one frame, bit for bit).

The generator core registers ``npstereo`` as a FuseSoC generator (``generators:``
section): a user's core asks for a configuration in its ``generate:`` section and FuseSoC
runs the generator script, which writes this package (:mod:`.generator`).

Strings are written as JSON strings, which YAML reads as double-quoted scalars: no value
can change the file's structure.
"""

import json

from ...sim.lint import LINT_WAIVERS
from ...sim.build import ICARUS_ARGS
from ...sim.tools import VERILATOR_WAIVERS

__all__ = ["LINT_OPTIONS", "core_text", "generator_core_text"]

#: Verilator's options in the ``lint`` target: every warning on, less the waivers.
LINT_OPTIONS = ["-Wall", *VERILATOR_WAIVERS, *LINT_WAIVERS]


def _s(value):
    return json.dumps(str(value))


def _list(values):
    return "[" + ", ".join(_s(value) for value in values) + "]"


def core_text(vlnv, description, rtl, testbench, data, top, tb_top, comments):
    """Text of the CAPI2 core.

    Parameters
    ----------
    vlnv : str
        ``vendor:library:name:version``.
    rtl, testbench : list of str
        Verilog files, relative to the core file.
    data : list of str
        Files the testbench reads from its working directory (copied there).
    top, tb_top : str
        The core's and the testbench's module.
    comments : list of str
        Lines put at the top of the file (the generation parameters).
    """
    head = "".join(f"# {line}\n" for line in comments)
    data_files = "".join(f"      - {_s(name)}: {{copyto: {_s(name)}}}\n" for name in data)
    return f"""\
CAPI=2:
{head}
name: {_s(vlnv)}
description: {_s(description)}

filesets:
  rtl:
    files: {_list(rtl)}
    file_type: verilogSource
  tb:
    files: {_list(testbench)}
    file_type: verilogSource
  tb_data:
    files:
{data_files}    file_type: user

targets:
  default:
    filesets: [rtl]
    toplevel: {_s(top)}
  lint:
    description: "Verilator --lint-only -Wall; the waivers are documented in docs/integration.md"
    flow: lint
    flow_options:
      tool: verilator
      verilator_options: {_list(LINT_OPTIONS)}
    filesets: [rtl]
    toplevel: {_s(top)}
  sim:
    description: "One frame through the core under Icarus, compared with the golden model bit for bit"
    flow: sim
    flow_options:
      tool: icarus
      iverilog_options: {_list(ICARUS_ARGS)}
    filesets: [rtl, tb, tb_data]
    toplevel: {_s(tb_top)}
"""


def generator_core_text(vlnv, interpreter, script):
    """Text of the core that registers the ``npstereo`` generator: FuseSoC runs
    ``interpreter script GAPI-FILE`` in the folder the generated core goes to."""
    return f"""\
CAPI=2:
# The npstereo core generator, written by `npstereo ip --fusesoc-generator`.
# A core that depends on this one asks for a configuration in its generate: section
# (parameters: those of `npstereo ip`, see docs/integration.md).

name: {_s(vlnv)}
description: "npstereo: streaming stereo-vision cores generated from parameters"

generators:
  npstereo:
    interpreter: {_s(interpreter)}
    command: {_s(script)}
    description: "Writes an npstereo core package (Verilog, CAPI2 core, IP-XACT, Platform Designer) for the parameters given"
"""
