"""Lint of generated Verilog: ``verilator --lint-only -Wall`` with the project's waivers."""

import subprocess

from ..hdl.verilog import TOP_NAME
from .tools import VERILATOR_WAIVERS, require, tool_env

__all__ = ["LINT_WAIVERS", "lint"]

#: Beyond ``sim.tools.VERILATOR_WAIVERS``: Amaranth declares every register with its reset
#: value as initializer (the FPGA power-up state) and also assigns it in the clocked
#: process, which -Wall reports as PROCASSINIT on every register; intended, not a bug.
LINT_WAIVERS = ["-Wno-PROCASSINIT"]


def lint(path):
    """``verilator --lint-only -Wall`` of a Verilog file; returns (ok, messages).

    Uses the project's Verilator and waivers (:data:`LINT_WAIVERS` on top of the shared
    ones); a missing Verilator raises :class:`~npstereo.params.UserError`.
    """
    command = [require("verilator"), "--lint-only", "-Wall", *VERILATOR_WAIVERS,
               *LINT_WAIVERS, "--top-module", TOP_NAME, str(path)]
    result = subprocess.run(command, env=tool_env(), capture_output=True, text=True,
                            check=False)
    return result.returncode == 0, result.stderr
