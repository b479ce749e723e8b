"""The synthesis report of one configuration: its figures on each target, through the
result cache (:mod:`.cache`), with the cycles per frame and the frame rate they give.

:func:`synthesis_report` synthesises what the cache does not hold; :func:`lookup` reads a
report from the cache alone; :func:`synthesis_job` is a report as a task of a sweep (it
never raises) and :func:`store_report` files a worker's results in the client's cache.

A target whose device cannot hold the core's memories, by their bits or (ECP5) by the
block RAMs Yosys would map them to (:func:`memory_refusal`), is not synthesised: its result
says "does not fit (memory N %)" at once, from the parameters alone. Such a verdict costs nothing to give again and is never cached.
"""

import dataclasses
import time
from pathlib import Path

from ...hdl.plan_memories import memory_bits
from ...hdl.plan_timing import cycles_per_frame
from ...hdl.verilog import TOP_NAME, core_verilog
from ...params import StereoParams
from ..flow.block_rams import core_block_rams
from ..flow.capacity import DEFAULT_DEVICE, fit_message, memory_fit_message, target_device
from ..flow.nextpnr import Placement
from ..flow.synthesise import synthesise
from .cache import cache_key, design, incomplete, memoised_digest, read_result, refused, \
    store_result

__all__ = ["synthesis_report", "lookup", "store_report", "failed_report", "synthesis_job",
           "memory_refusal", "refusal_report"]


def _path(cache, params, target, pnr, freq, digest, device, placement=Placement()):
    key = cache_key(params, target, pnr, freq, digest, device, placement.for_core(params))
    return Path(cache) / f"{key}.json"


def _report(params, digest, results):
    return {"params": dataclasses.asdict(params), "verilog_sha": digest,
            "cycles_per_frame": cycles_per_frame(params),
            "expected_memory_bits": memory_bits(params), "results": results}


def memory_refusal(params, target, dev):
    """The result of ``target`` for ``params`` when ``dev`` (a
    :class:`~npstereo.gen.flow.capacity.Device`) cannot hold the core's memories, else None.

    Status ``does not fit`` with the message of
    :func:`~npstereo.gen.flow.capacity.memory_fit_message`, ``memory_bits`` the
    architecture's, ``expected_block_rams`` the DP16KD its memories take on an ECP5 part
    (:func:`~npstereo.gen.flow.block_rams.core_block_rams`; None on the others), the figures
    only synthesis gives None, ``device`` the device checked and ``synthesised`` False
    (:func:`~.cache.refused`). Nothing is generated or synthesised: the bits and blocks
    follow from the parameters.
    """
    started = time.monotonic()
    bits = memory_bits(params)
    blocks = core_block_rams(params) if dev.target == "ecp5" else None
    message = memory_fit_message(bits, dev, blocks)
    if message is None:
        return None
    unknown = dict.fromkeys(("logic", "logic_unit", "registers", "block_rams",
                             "block_ram_kind", "lut_rams", "dsps", "ffram_bits",
                             "logic_levels", "utilisation", "frames_per_second"))
    return dict(target=target, status="does not fit", message=message, device=dev.name,
                memory_bits=bits, expected_block_rams=blocks, fmax_mhz=None, fits=False,
                synthesised=False, **unknown,
                seconds=round(time.monotonic() - started, 1), cached=False)


def refusal_report(params, target, dev):
    """The report of ``params`` on ``target`` alone when ``dev`` cannot hold its memories
    (:func:`memory_refusal`; no Verilog digest, nothing was generated), else None."""
    result = memory_refusal(params, target, dev)
    return None if result is None else _report(params, None, {target: result})


def _refusals(params, targets, device):
    """:func:`memory_refusal` of each target on the device it is checked against, by
    target (only the refused ones)."""
    found = {t: memory_refusal(params, t, target_device(t, device)) for t in targets}
    return {t: result for t, result in found.items() if result is not None}


#: Statuses of results that are not cached: a longer ``--timeout`` or a run left alone
#: may give another.
UNKEPT = ("timeout", "interrupted")


def synthesis_report(params, targets, pnr=False, freq=150.0, timeout=None, cache=None,
                     engine=None, device=DEFAULT_DEVICE, placement=Placement()):
    """Synthesis figures of one configuration for each target, with cycles and frame rate.

    Results that are ``ok`` or ``failed`` are cached in ``cache`` (a folder) when given;
    timeouts and tools stopped by a signal from outside are not (:data:`UNKEPT`), so a
    longer ``--timeout`` or a run left alone retries them. A memory count that differs
    from the architecture's (:func:`~npstereo.hdl.plan_memories.memory_bits`) is noted in the
    result's message. ``device``: the ECP5 part placed on (:mod:`npstereo.gen.flow.capacity`).
    A target whose device cannot hold the core's memories (the ECP5 part, or
    :data:`~npstereo.gen.flow.capacity.CYCLONEV_DEVICE`) gets :func:`memory_refusal`'s
    result before anything is generated; when every target does, no Verilog is generated
    (``verilog_sha`` None). ``placement``: nextpnr's choices
    (:class:`~npstereo.gen.flow.nextpnr.Placement`), with the flow's own where it leaves a
    choice open (:meth:`~npstereo.gen.flow.nextpnr.Placement.for_core`), those set part of
    the cache key.
    """
    placement = placement.for_core(params)
    results = _refusals(params, targets, device)
    if len(results) == len(targets):
        return _report(params, None, {t: results[t] for t in targets})
    cycles = cycles_per_frame(params)
    expected_bits = memory_bits(params)
    digest, verilog = design(params, cache)
    for target in targets:
        if target in results:
            continue
        path = None if cache is None else _path(cache, params, target, pnr, freq, digest,
                                                device, placement)
        cached = None if path is None else read_result(path)
        if cached is not None and incomplete(cached):
            verilog = core_verilog(params) if verilog is None else verilog
            cached = _completed(cached, verilog, path, timeout, engine, device)
        if cached is not None:
            results[target] = cached
            continue
        if verilog is None:
            verilog = core_verilog(params)
        result = synthesise(verilog, target, TOP_NAME, pnr=pnr, freq=freq, timeout=timeout,
                            engine=engine, device=device, placement=placement)
        if target == "ecp5":
            result.update(pnr=pnr, freq=freq)
            if device != DEFAULT_DEVICE:
                result["device"] = device
        if result["status"] == "ok" and result["memory_bits"] != expected_bits:
            result["message"] = (f"memory bits {result['memory_bits']} differ from the "
                                 f"architecture's {expected_bits}")
        if result.get("fmax_mhz"):
            result["frames_per_second"] = result["fmax_mhz"] * 1e6 / cycles
        if path is not None and result["status"] not in UNKEPT:
            store_result(path, result)
        results[target] = dict(result, cached=False)
    return _report(params, digest, {t: results[t] for t in targets})


def _completed(cached, verilog, path, timeout, engine, device):
    """A cached ECP5 result that predates the count of carry chains, with the count and
    the utilisation and verdict that follow from it: synthesised again, not placed (place
    and route figures are the netlist's, which has not changed). Stored in place of the
    old one; left as it was if the synthesis does not finish."""
    fresh = synthesise(verilog, "ecp5", TOP_NAME, timeout=timeout, engine=engine,
                       device=device)
    if "carry_chains" not in fresh:
        return cached
    result = dict(cached, carry_chains=fresh["carry_chains"],
                  utilisation=fresh["utilisation"], fits=fresh["fits"])
    if result["status"] == "does not fit":
        result["message"] = fit_message(result["utilisation"]) or result["message"]
    store_result(path, result)
    return dict(result, cached=False)


def lookup(params, targets, pnr=False, freq=150.0, cache=None, device=DEFAULT_DEVICE,
           partial=False):
    """The report :func:`synthesis_report` would give, from ``cache`` alone (nothing
    generated or synthesised), or None when any of it is not there. With ``partial``: the
    targets that are there, or None when none is. A target refused for its memory
    (:func:`memory_refusal`) is always there: its verdict needs no cache."""
    refusals = _refusals(params, targets, device)
    rest = [t for t in targets if t not in refusals]
    digest = None if cache is None or not rest else memoised_digest(params, cache)
    results = {t: refusals.get(t) or (
        None if digest is None else read_result(_path(cache, params, t, pnr, freq, digest,
                                                      device)))
        for t in targets}
    if partial:
        results = {t: r for t, r in results.items() if r is not None}
        return _report(params, digest, results) if results else None
    if any(r is None or incomplete(r) for r in results.values()):
        return None
    return _report(params, digest, results)


def store_report(report, cache, pnr, freq, device=DEFAULT_DEVICE):
    """Put the cacheable results of a report that a worker computed into ``cache`` (the
    client's copy: a remote worker may not share this file system)."""
    if cache is None or not report.get("verilog_sha"):
        return
    params = StereoParams(**report["params"])
    for target, result in report["results"].items():
        if result["status"] not in UNKEPT and not result.get("cached") and not refused(result):
            store_result(_path(cache, params, target, pnr, freq, report["verilog_sha"],
                               device), result)


def failed_report(params, targets, message):
    """The report of a configuration whose evaluation crashed: every target failed."""
    return {"params": dataclasses.asdict(params), "cycles_per_frame": None,
            "expected_memory_bits": memory_bits(params),
            "results": {t: {"target": t, "status": "failed", "fmax_mhz": None,
                            "message": message[:200]} for t in targets}}


def synthesis_job(params, targets, pnr, freq, timeout, cache, engine,
                  device=DEFAULT_DEVICE, placement=Placement()):
    """One sweep cell on a worker; never raises, so the sweep goes on.

    The worker uses the shared cache when it can write there (a remote worker may not
    see the client's folder: the client then keeps the results).
    """
    if cache is not None:
        try:
            Path(cache).mkdir(parents=True, exist_ok=True)
        except OSError:
            cache = None
    try:
        return synthesis_report(params, targets, pnr, freq, timeout, cache, engine, device,
                                placement)
    except Exception as error:  # a crash in generation is a cell's result, not the sweep's
        return failed_report(params, targets, f"{type(error).__name__}: {error}")
