"""The design-space explorer: quality x logic x memory x clock of a grid of configurations
for one device, every evaluation a task on Dask distributed (:mod:`.engine`).

For each configuration of the grid it measures

- quality: correct matches of the golden model (bit-exact with the core) on the scene,
  clean and under each degraded condition asked for (noise, the Bayer stand-in); with
  F > 0 fractional bits the fractional disparities are scored, and the mean error of the
  correct pixels shows what the fraction gives;
- logic, registers, memory bits, block RAMs and the logic depth from synthesis for the
  device's target, and with place and route (ECP5 parts) nextpnr's Fmax;
- frames per second at the hardware's frame size: Fmax (or the assumed clock without
  place and route) over :func:`~npstereo.hdl.plan_timing.cycles_per_frame`;

and says whether it fits the device (:mod:`npstereo.gen.flow.capacity`); a configuration
whose memories the device cannot hold is told "does not fit (memory N %)" without a
synthesis (:func:`~npstereo.gen.reports.synthesis.memory_refusal`). The points are
then ranked: the Pareto front of quality against logic, and the recommendation (the best
quality that fits the device at the required frame rate).

Every result is cached (:mod:`npstereo.gen.reports.cache`): a synthesis under the key of ``npstereo
report`` (the two commands share their results), a quality measurement under a key of
the configuration, the scene's pixels and the golden model's sources. The client submits
only what the cache does not hold; a worker that finds a result there returns it.
"""

import dataclasses
import hashlib
import itertools
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...golden.quality import evaluate as quality_of, mean_absolute_error
from ...hdl.plan import check_buildable
from ...hdl.plan_timing import cycles_per_frame
from ...params import SGM, ParameterError, StereoParams, UserError
from ..atomic import OutputError
from ..flow.capacity import DEFAULT_DEVICE, device as find_device, fit_message, usage, \
    utilisation
from ..matching import match_images
from ..reports.cache import golden_source_hash, read_result, refused, source_hash, \
    store_result
from ..reports.synthesis import failed_report, lookup, refusal_report, store_report, \
    synthesis_job
from .engine import Task, TaskFailure, run_tasks, shared, task_key

__all__ = ["Grid", "configurations", "scene_digest", "quality_task", "plan_tasks",
           "explore", "pareto_front", "recommend"]


@dataclass(frozen=True)
class Grid:
    """The axes of the sweep (each a tuple of values) and what every point shares.

    ``aggregations`` holds the values as the command line gives them (odd integers, or a
    name such as ``"sgm"`` where :class:`~npstereo.params.StereoParams` accepts one); they
    are passed on unchanged.
    """

    transforms: tuple
    blocks: tuple
    rounds: tuple
    aggregations: tuple
    line_buffers: tuple
    disparities: int
    width: int
    height: int
    lr_threshold: int | None = 3
    #: The device's (:attr:`npstereo.gen.flow.capacity.Device.lut_inputs`), for every
    #: configuration.
    lut_inputs: int = 4
    #: The output options' axes: the 3x3 median off and/or on, fractional bits F.
    medians: tuple = (False,)
    subpixel_bits: tuple = (0,)
    #: SGM's quality options' axes: the fifth path off and/or on, the cost terms (None:
    #: the census cost alone).
    fifth_paths: tuple = (False,)
    cost_terms: tuple = (None,)

    _AXES = (("transforms", "--transform"), ("blocks", "--block"), ("rounds", "--rounds"),
             ("aggregations", "--aggregation"), ("line_buffers", "--line-buffer"),
             ("medians", "--median"), ("subpixel_bits", "--subpixel-bits"),
             ("fifth_paths", "--fifth-path"), ("cost_terms", "--cost-term"))


def _params(grid, transform, block, rounds, aggregation, line_buffer, median, bits, fifth,
            term):
    # The SGM axes do not apply to a box: it is taken once, without them.
    sgm = aggregation == SGM
    fifth, term = fifth and sgm, term if sgm else None
    return StereoParams(transform=transform, block=block, disparities=grid.disparities,
                        rounds=rounds, aggregation=aggregation,
                        lr_threshold=grid.lr_threshold, width=grid.width,
                        height=grid.height, line_buffer=line_buffer,
                        lut_inputs=grid.lut_inputs, median=median, subpixel_bits=bits,
                        cost_term=term, fifth_path=fifth)


def configurations(grid):
    """The validated configurations of ``grid``, in grid order, and the combinations
    skipped (one line each).

    A value that no combination accepts (block 4, rounds that do not divide D, an
    aggregation window too wide for the frame) is a one-line :class:`ParameterError`; a
    combination of values that others accept, but not together (SGM's default penalties
    with a transform whose costs are too narrow for them), is skipped and named. The SGM
    axes (fifth path, cost terms) apply to the SGM configurations, a box is taken once
    without them; asked for in a grid without SGM they are a one-line
    :class:`UserError`. An
    empty axis, or a grid whose every combination is skipped, is a one-line
    :class:`UserError`.
    """
    for axis, option in Grid._AXES:
        if not getattr(grid, axis):
            raise UserError(f"the grid is empty: {option} has no values")
    _check_sgm_axes(grid)
    chosen, skipped, errors = [], [], {}
    valid = set()
    for combination in itertools.product(*(getattr(grid, axis) for axis, _ in Grid._AXES)):
        try:
            params = _params(grid, *combination)
            check_buildable(params)
        except ParameterError as error:
            skipped.append(f"{combination}: {error}")
            for axis_index, value in enumerate(combination):
                errors.setdefault((axis_index, value), error)
            continue
        valid.update(enumerate(combination))
        if params not in chosen:
            chosen.append(params)
    # A value no combination accepts is wrong on its own (block 4, rounds that divide no
    # D, SGM penalties too wide for every transform of the grid): its one-line error.
    for axis_index, (axis, _) in enumerate(Grid._AXES):
        for value in getattr(grid, axis):
            if (axis_index, value) not in valid:
                raise errors[axis_index, value]
    if not chosen:
        raise UserError(f"the grid is empty: no valid configuration ({skipped[0]})")
    return chosen, skipped


def _check_sgm_axes(grid):
    """The fifth path and the cost terms are SGM's: a grid that asks for them needs sgm
    among its aggregations (one line, as the other commands say it)."""
    given = (["--fifth-path on"] if True in grid.fifth_paths else []) + [
        f"--cost-term {term}" for term in grid.cost_terms if term is not None]
    if given and SGM not in grid.aggregations:
        verb = "is an SGM option: it needs" if len(given) == 1 else \
            "are SGM options: they need"
        raise UserError(f"{' and '.join(given)} {verb} sgm among the --aggregation values")


def scene_digest(left, right, truth):
    """Digest of a scene's pixels and ground truth: part of every quality key."""
    digest = hashlib.sha256()
    for array in (left, right, truth):
        array = np.ascontiguousarray(array)
        digest.update(f"{array.dtype}{array.shape}".encode() + array.tobytes())
    return digest.hexdigest()[:24]


def _golden(params):
    """What the golden model's result depends on: not the frame size, not the buffer, not
    the LUTs the arithmetic is arranged for."""
    return dataclasses.replace(params, width=None, height=None, line_buffer="auto",
                               lut_inputs=4)


def _quality_path(cache, key):
    return Path(cache) / "quality" / f"{key}.json"


def quality_task(scene, params, cache, key):
    """On a worker: correct matches of ``params`` on one conditioned scene, ``(left,
    right, ground truth)``.

    Returns the metrics of :func:`npstereo.golden.quality.evaluate` (of the fractional
    disparities with F > 0), ``mean_error`` (:func:`~npstereo.golden.quality.
    mean_absolute_error`, None when no pixel is correct), ``seconds`` and ``cached``; the
    result is stored in the shared ``cache`` when the worker can write
    there (the client stores it too).
    """
    path = None if cache is None else _quality_path(cache, key)
    if path is not None:
        found = read_result(path)
        if found is not None:
            return found
    left, right, truth = scene
    start = time.perf_counter()
    disparity = match_images(left, right, params, threads=1)
    error = mean_absolute_error(disparity, truth, params.disparities)
    result = dict(quality_of(disparity, truth, params.disparities).as_dict(),
                  mean_error=None if np.isnan(error) else round(error, 4),
                  seconds=round(time.perf_counter() - start, 3), cached=False)
    if path is not None:
        try:
            store_result(path, result)
        except (OSError, OutputError):
            pass  # a remote worker that does not share the client's folder
    return result


@dataclass
class _Plan:
    """What a run needs: tasks to submit and the results the cache already holds."""

    tasks: list
    quality: dict     # (configuration index, condition label) -> result
    synthesis: dict   # configuration index -> report
    owners: dict      # task key -> (kind, configuration index, condition label)
    aliases: dict     # (configuration index, condition label) -> quality key of another


def plan_tasks(configs, scenes, dev, pnr, freq, timeout, cache, engine):
    """Tasks for everything the cache does not hold.

    ``scenes`` maps a condition label to ``(left, right, truth)``. Quality tasks come
    first (seconds each), then the syntheses, cheap ones first.
    """
    cache_text = None if cache is None else str(cache)
    plan = _Plan([], {}, {}, {}, {})
    golden_sources = golden_source_hash()
    for label, (left, right, truth) in scenes.items():
        digest = scene_digest(left, right, truth)
        scene = shared((left, right, truth), f"scene-{digest}")
        for index, params in enumerate(configs):
            golden = _golden(params)
            key = task_key("quality", repr(golden), digest, golden_sources)
            found = None if cache is None else read_result(_quality_path(cache, key))
            if found is not None:
                plan.quality[(index, label)] = found
            elif key in plan.owners:  # two configurations with one golden result
                plan.aliases[(index, label)] = key
            else:
                plan.owners[key] = ("quality", index, label)
                plan.tasks.append(Task(key, quality_task, (scene, golden, cache_text, key),
                                       f"quality {label}: {params.describe()}"))
    order = sorted(range(len(configs)), key=lambda i: (configs[i].transform == "ext-census",
                                                       configs[i].block))
    hardware_sources = source_hash()
    for index in order:
        params = configs[index]
        # The device's memory is checked here, not by the synthesis task: the task checks
        # an ECP5 synthesis against the 85k whatever the part (_ecp5_part), and a Cyclone V
        # one against the A9, not the EP2S180.
        found = (refusal_report(params, dev.target, dev)
                 or lookup(params, (dev.target,), pnr, freq, cache, _ecp5_part(dev, pnr)))
        if found is not None:
            plan.synthesis[index] = found
            continue
        key = task_key("synthesis", repr(params), dev.target, pnr, freq, timeout, engine,
                       _ecp5_part(dev, pnr), hardware_sources)
        plan.owners[key] = ("synthesis", index, None)
        plan.tasks.append(Task(key, synthesis_job,
                               (params, (dev.target,), pnr, freq, timeout, cache_text,
                                engine, _ecp5_part(dev, pnr)),
                               f"synthesis {dev.target}: {params.describe()}"))
    return plan


def _ecp5_part(dev, pnr):
    """The ECP5 part nextpnr places on. Synthesis alone does not depend on the part: its
    result is cached once for every part (checked against the LFE5U-85F as ``npstereo
    report`` checks it) and :func:`_point` measures it against ``dev``."""
    return dev.name if dev.target == "ecp5" and pnr else DEFAULT_DEVICE


def explore(client, configs, scenes, dev, pnr=False, freq=150.0, timeout=None, cache=None,
            engine=None, clock=100.0, min_fps=None):
    """Evaluate every configuration of ``configs`` on ``client``'s cluster (None: only
    when the cache holds everything) and rank them.

    Returns
    -------
    dict
        ``points`` (one per configuration, in order), ``pareto`` (indices of the front),
        ``recommendation`` (an index or None) with ``recommendation_reason``, and
        ``tasks``: ``submitted`` (count), ``computed`` (labels of the evaluations done in
        this run), ``failed``.
    """
    dev = find_device(dev) if isinstance(dev, str) else dev
    plan = plan_tasks(configs, scenes, dev, pnr, freq, timeout, cache, engine)
    computed, failed = [], []

    def finished(task, result, write):
        kind, index, label = plan.owners[task.key]
        if isinstance(result, TaskFailure):
            failed.append(f"{task.label}: {result.message}")
            write(f"{task.label}: failed ({result.message})")
            result = ({"status": "failed", "message": result.message} if kind == "quality"
                      else failed_report(task.args[0], task.args[1], result.message))
        if kind == "quality":
            plan.quality[(index, label)] = result
            if cache is not None and "correct" in result:
                store_result(_quality_path(cache, task.key), result)
            fresh = not result.get("cached", True)
        else:
            plan.synthesis[index] = result
            store_report(result, cache, pnr, freq, _ecp5_part(dev, pnr))
            fresh = any(not r.get("cached", True) for r in result["results"].values())
            target = result["results"][dev.target]
            write(f"{task.label}: {target['status']}"
                  + (f" ({target['message']})" if target.get("message") else ""))
        if fresh:
            computed.append(task.label)

    if plan.tasks:
        if client is None:
            raise ValueError("tasks to run but no client")
        run_tasks(client, plan.tasks, "explore", on_result=finished)
    for (index, label), key in plan.aliases.items():
        _, source, _ = plan.owners[key]
        plan.quality[(index, label)] = plan.quality[(source, label)]
    points = [_point(params, index, scenes, plan, dev, pnr, clock)
              for index, params in enumerate(configs)]
    front = pareto_front(points)
    for index in front:
        points[index]["pareto"] = True
    choice, reason = recommend(points, min_fps)
    return {"points": points, "pareto": front, "recommendation": choice,
            "recommendation_reason": reason,
            "tasks": {"submitted": len(plan.tasks), "computed": computed,
                      "failed": failed}}


def _point(params, index, scenes, plan, dev, pnr, clock):
    report = plan.synthesis[index]
    result = report["results"][dev.target]
    point = {"params": dataclasses.asdict(params), "label": _label(params),
             "quality": {label: plan.quality[(index, label)] for label in scenes},
             "synthesis": result, "cycles_per_frame": cycles_per_frame(params),
             "pareto": False}
    # Figures exist after a synthesis that finished ("ok", "does not fit"); a core refused
    # for its memory was not synthesised and has only its memory bits.
    synthesised = result["status"] in ("ok", "does not fit") and not refused(result)
    if refused(result):
        point.update(logic=None, registers=None, memory_bits=result["memory_bits"],
                     block_rams=None, logic_levels=None, used=None, utilisation=None,
                     fits=False, verdict=result["message"])
    elif synthesised:
        used = usage(result, dev)
        point.update(logic=used[dev.logic_resource.name], registers=result["registers"],
                     memory_bits=result["memory_bits"], block_rams=result["block_rams"],
                     logic_levels=result.get("logic_levels"), used=used,
                     utilisation=utilisation(result, dev))
        verdict = fit_message(point["utilisation"])
        point.update(fits=verdict is None, verdict=verdict or "fits")
    else:
        point.update(logic=None, registers=None, memory_bits=None, block_rams=None,
                     logic_levels=None, used=None, utilisation=None, fits=None,
                     verdict=f"synthesis {result['status']}: {result.get('message', '')}")
    fmax = result.get("fmax_mhz") if pnr else None
    basis_clock, basis = (fmax, "nextpnr Fmax") if pnr else (clock, "assumed clock")
    point.update(fmax_mhz=fmax, fps_clock_mhz=basis_clock, fps_basis=basis,
                 frames_per_second=None if basis_clock is None or not synthesised
                 else basis_clock * 1e6 / point["cycles_per_frame"])
    return point


def _label(params):
    buffer = "" if params.line_buffer == "auto" else f" {params.line_buffer}"
    options = ((f" +{params.cost_term}" if params.cost_term else "")
               + (" fifth path" if params.fifth_path else "")
               + (" median" if params.median else "")
               + (f" F={params.subpixel_bits}" if params.subpixel_bits else ""))
    return (f"{params.transform} {params.block}x{params.block} R={params.rounds} "
            f"A={params.aggregation}{buffer}{options}")


def _clean(point):
    """Clean correct matches (%) of a point, or None."""
    first = next(iter(point["quality"].values()))
    return first.get("correct")


def pareto_front(points):
    """Indices of the points no other point beats: at least as many correct matches
    (clean) with at most as much logic, and better in one (ties: the first kept)."""
    candidates = [(i, p["logic"], _clean(p)) for i, p in enumerate(points)
                  if p["logic"] is not None and _clean(p) is not None]
    front = []
    for i, logic, quality in candidates:
        beaten = any((l2 <= logic and q2 >= quality and (l2 < logic or q2 > quality))
                     or (l2 == logic and q2 == quality and j < i)
                     for j, l2, q2 in candidates if j != i)
        if not beaten:
            front.append(i)
    return sorted(front, key=lambda i: points[i]["logic"])


def recommend(points, min_fps=None):
    """``(index, reason)`` of the best configuration that fits the device (and reaches
    ``min_fps`` frames per second): most correct matches, then least logic, then least
    memory; ``(None, reason)`` when none qualifies."""
    fitting = [i for i, p in enumerate(points) if p["fits"] and _clean(p) is not None]
    if not fitting:
        return None, "no configuration fits the device"
    if min_fps is not None:
        fast = [i for i in fitting if (points[i]["frames_per_second"] or 0) >= min_fps]
        if not fast:
            best = max(fitting, key=lambda i: points[i]["frames_per_second"] or 0)
            return None, (f"no configuration that fits reaches {min_fps:g} frames/s "
                          f"(fastest: {points[best]['label']}, "
                          f"{points[best]['frames_per_second'] or 0:.1f} frames/s)")
        fitting = fast
    best = max(fitting, key=lambda i: (_clean(points[i]), -points[i]["logic"],
                                       -points[i]["memory_bits"]))
    rate = "" if min_fps is None else f" at >= {min_fps:g} frames/s"
    return best, f"most correct matches among the {len(fitting)} that fit{rate}"
