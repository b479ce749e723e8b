"""The synthesis report of one configuration: its figures on each target, through the
result cache (:mod:`.cache`), with the cycles per frame and the frame rate they give.

:func:`synthesis_report` synthesises what the cache does not hold; :func:`lookup` reads a
report from the cache alone; :func:`synthesis_job` is a report as a task of a sweep (it
never raises) and :func:`store_report` files a worker's results in the client's cache.
"""

import dataclasses
from pathlib import Path

from ...hdl.plan import cycles_per_frame, memory_bits
from ...hdl.verilog import TOP_NAME, core_verilog
from ...params import StereoParams
from ..flow.capacity import DEFAULT_DEVICE, fit_message
from ..flow.synthesise import synthesise
from .cache import cache_key, design, incomplete, memoised_digest, read_result, store_result

__all__ = ["synthesis_report", "lookup", "store_report", "failed_report", "synthesis_job"]


def _path(cache, params, target, pnr, freq, digest, device):
    return Path(cache) / f"{cache_key(params, target, pnr, freq, digest, device)}.json"


def _report(params, digest, results):
    return {"params": dataclasses.asdict(params), "verilog_sha": digest,
            "cycles_per_frame": cycles_per_frame(params),
            "expected_memory_bits": memory_bits(params), "results": results}


def synthesis_report(params, targets, pnr=False, freq=150.0, timeout=None, cache=None,
                     engine=None, device=DEFAULT_DEVICE):
    """Synthesis figures of one configuration for each target, with cycles and frame rate.

    Results that are ``ok`` or ``failed`` are cached in ``cache`` (a folder) when given;
    timeouts are not, so a longer ``--timeout`` retries them. A memory count that differs
    from the architecture's (:func:`~npstereo.hdl.plan.memory_bits`) is noted in the
    result's message. ``device``: the ECP5 part placed on (:mod:`npstereo.gen.flow.capacity`).
    """
    results = {}
    cycles = cycles_per_frame(params)
    expected_bits = memory_bits(params)
    digest, verilog = design(params, cache)
    for target in targets:
        path = None if cache is None else _path(cache, params, target, pnr, freq, digest,
                                                device)
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
                            engine=engine, device=device)
        if target == "ecp5":
            result.update(pnr=pnr, freq=freq)
            if device != DEFAULT_DEVICE:
                result["device"] = device
        if result["status"] == "ok" and result["memory_bits"] != expected_bits:
            result["message"] = (f"memory bits {result['memory_bits']} differ from the "
                                 f"architecture's {expected_bits}")
        if result.get("fmax_mhz"):
            result["frames_per_second"] = result["fmax_mhz"] * 1e6 / cycles
        if path is not None and result["status"] != "timeout":
            store_result(path, result)
        results[target] = dict(result, cached=False)
    return _report(params, digest, results)


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
    targets that are there, or None when none is."""
    digest = None if cache is None else memoised_digest(params, cache)
    if digest is None:
        return None
    results = {t: read_result(_path(cache, params, t, pnr, freq, digest, device))
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
        if result["status"] != "timeout" and not result.get("cached"):
            store_result(_path(cache, params, target, pnr, freq, report["verilog_sha"],
                               device), result)


def failed_report(params, targets, message):
    """The report of a configuration whose evaluation crashed: every target failed."""
    return {"params": dataclasses.asdict(params), "cycles_per_frame": None,
            "expected_memory_bits": memory_bits(params),
            "results": {t: {"target": t, "status": "failed", "fmax_mhz": None,
                            "message": message[:200]} for t in targets}}


def synthesis_job(params, targets, pnr, freq, timeout, cache, engine,
                  device=DEFAULT_DEVICE):
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
        return synthesis_report(params, targets, pnr, freq, timeout, cache, engine, device)
    except Exception as error:  # a crash in generation is a cell's result, not the sweep's
        return failed_report(params, targets, f"{type(error).__name__}: {error}")
