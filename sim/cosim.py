"""Co-simulation runs: frames through a simulated core, compared with the golden model.

The parent side of the run protocol: build the model (:mod:`.build`, cached), write a plan
and the frames with their golden output words into a fresh run directory, start the
simulator through cocotb's Python runner and read back what the cocotb test module
(:mod:`.cocotb_tests`) found. Amaranth's own simulator (:mod:`.amaranth_run`) runs the
same whole-frame comparison without Verilog. Every run returns a :class:`RunResult`.
"""

import contextlib
import dataclasses
import json
import os
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..golden.pipeline import disparity_map
from ..hdl.stream import WordCodec
from ..hdl.verilog import TOP_NAME, core_verilog
from .amaranth_run import run_amaranth
from .build import CosimError, build
from .frames import Comparison, compare_frame, decode_map
from .harness import HARNESS_TOP, PERIOD_NS, RESET_CYCLES, harness_verilog, stimulus_text

__all__ = ["SIMULATORS", "CosimError", "RunResult", "golden_words", "run_stream",
           "run_frame"]

#: What a frame can run on: two Verilog simulators under cocotb, and Amaranth's simulator
#: on the Amaranth design (no Verilog; slow, small crops only).
SIMULATORS = ("verilator", "icarus", "amaranth")

TEST_MODULE = "npstereo.sim.cocotb_tests"


@dataclass
class RunResult:
    """What one simulation found: one comparison per checked frame, plus figures."""

    frames: list                        # (label, Comparison)
    cycles: int | None = None           # first input to last output beat (whole frames)
    seconds: float = 0.0                # simulation time
    build_seconds: float = 0.0          # building the model; 0 when it was cached
    run_dir: Path | None = None         # the simulator's run directory (logs, plan)
    disparity: np.ndarray | None = field(default=None, repr=False)  # the hardware's map

    @property
    def ok(self):
        return bool(self.frames) and all(comp.ok for _, comp in self.frames)

    @property
    def mismatches(self):
        return sum(comp.mismatches for _, comp in self.frames)

    def message(self):
        bad = [f"{label}: {comp.message()}" for label, comp in self.frames if not comp.ok]
        return "; ".join(bad) if bad else "bit-exact"


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


def _watch(path, progress, done):
    """Report the count the cocotb test writes to ``path`` until ``done`` is set."""
    seen = 0
    while not done.wait(0.5):
        with contextlib.suppress(OSError, ValueError):
            now = int(path.read_text() or 0)
            if now > seen:
                progress(now - seen)
                seen = now


def _run(model, test, plan, arrays, progress=None, files=None):
    """Run the cocotb ``test`` on ``model`` with ``plan``; the frames' comparisons."""
    runs = model.directory / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    run_dir = Path(tempfile.mkdtemp(prefix=f"{test}-", dir=runs))
    np.savez(run_dir / "data.npz", **arrays)
    for name, text in (files or {}).items():
        (run_dir / name).write_text(text)
    plan = {**plan, "data": "data.npz", "result": "result.json", "progress": "progress.txt"}
    (run_dir / "plan.json").write_text(json.dumps(plan))
    log = run_dir / "sim.log"
    done = threading.Event()
    watcher = None
    if progress is not None:
        watcher = threading.Thread(target=_watch, args=(run_dir / "progress.txt", progress,
                                                        done), daemon=True)
        watcher.start()
    start = time.perf_counter()
    try:
        with _outside_pytest():
            model.runner().test(
                test_module=TEST_MODULE, hdl_toplevel=model.top, testcase=test,
                hdl_toplevel_lang="verilog", build_dir=model.sim_dir, test_dir=run_dir,
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
              for record in data["frames"]]
    return RunResult(frames, data.get("cycles"), seconds, model.seconds, run_dir)


def golden_words(left, right, params):
    """Input words and expected output words of one frame pair."""
    golden = disparity_map(left, right, params).disparity
    codec = WordCodec(params)
    return codec.pack_pixels(left, right), codec.pack_disparity(golden)


def _quiet_cycles(params):
    # Longer than the core's latency (a few lines of R cycles per pixel) under traffic; the
    # aggregation window's rows count (none for SGM, whose latency is in clocks).
    window = 2 * params.agg_radius + 1
    return 4 * (params.block + window + 4) * params.width * params.rounds + 2000


def run_stream(simulator, params, frames, steps, core_text=None, seed=1, build_root=None,
               optimize=False, libraries=None):
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
        See :func:`.build.build`; cocotbext-axi, not the model, limits the speed here.
    libraries : dict, optional
        File name -> Verilog of further sources: the cell models of a gate-level
        ``core_text`` (a mapped netlist with the core's ports).

    Returns
    -------
    RunResult
        One comparison per checked frame.
    """
    core_text = core_verilog(params) if core_text is None else core_text
    model = build(simulator, {"core.v": core_text, **(libraries or {})}, TOP_NAME,
                  build_root, optimize)
    arrays = {}
    for index, (left, right) in enumerate(frames):
        arrays[f"in{index}"], arrays[f"out{index}"] = golden_words(left, right, params)
    plan = {"params": dataclasses.asdict(params), "steps": steps, "seed": seed,
            "quiet_cycles": _quiet_cycles(params)}
    return _run(model, "stream_test", plan, arrays)


def run_frame(simulator, params, left, right, core_text=None, idle=0.0, backpressure=0.0,
              progress=None, build_root=None, golden=None, optimize=True, libraries=None):
    """One whole frame through the simulated core, compared with the golden map.

    Under Verilator and Icarus the frame runs through the Verilog harness of
    :mod:`.harness` (no per-pixel Python); under ``amaranth`` through Amaranth's simulator
    (no Verilog; ``idle`` and ``backpressure`` must be 0 there).

    Parameters
    ----------
    simulator : str
        One of :data:`SIMULATORS`.
    params : StereoParams
        With the frame's width and height.
    left, right : (H, W) uint8
        The frame.
    core_text : str, optional
        Verilog of the core; generated from ``params`` when omitted.
    idle, backpressure : float
        Probability of an idle input cycle and of a cycle without ``m_axis_tready``.
    progress : callable, optional
        ``progress(n)`` with the number of further output pixels received, from a helper
        thread, about every half second.
    golden : (H, W) int16, optional
        The golden map of the frame; computed when omitted.
    optimize : bool
        See :func:`.build.build`.
    libraries : dict, optional
        Cell models of a gate-level ``core_text``, as for :func:`run_stream`.

    Returns
    -------
    RunResult
        With ``cycles`` and the hardware's ``disparity`` map.
    """
    if simulator not in SIMULATORS:
        raise ValueError(f"simulator must be one of {', '.join(SIMULATORS)}")
    if golden is None:
        golden = disparity_map(left, right, params).disparity
    expected = WordCodec(params).pack_disparity(golden)
    if simulator == "amaranth":
        if idle or backpressure:
            raise ValueError("the amaranth run streams without idle cycles or backpressure")
        start = time.perf_counter()
        data, tuser, tlast, cycles = run_amaranth(params, left, right, progress)
        comparison = compare_frame(expected, data, tuser, tlast, params)
        return RunResult([("frame 0", comparison)], cycles, time.perf_counter() - start,
                         disparity=decode_map(data, params))
    core_text = core_verilog(params) if core_text is None else core_text
    sources = {"core.v": core_text, **(libraries or {}),
               "harness.v": harness_verilog(params, idle, backpressure)}
    model = build(simulator, sources, HARNESS_TOP, build_root, optimize, harness=True)
    pixels = params.width * params.height
    # Generous: R cycles per pixel, random traffic, and a few lines of latency.
    budget = int(pixels * params.rounds / max(0.05, (1 - idle) * (1 - backpressure)) * 2
                 + _quiet_cycles(params) * 4)
    plan = {"params": dataclasses.asdict(params), "period_ns": PERIOD_NS, "reset_cycles": RESET_CYCLES, "timeout_cycles": budget,
            "progress_cycles": max(4096, budget // 200)}
    # The harness reads stim.hex from its working directory, the run directory.
    result = _run(model, "harness_test", plan, {"out0": expected}, progress,
                  {"stim.hex": stimulus_text(WordCodec(params), left, right)})
    result.disparity = np.load(result.run_dir / "disparity.npy")
    return result
