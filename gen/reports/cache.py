"""The result cache of ``npstereo report``: keyed on the generated Verilog and the tools.

A synthesis result depends on the Verilog and the tools, nothing else: keying the cache on
a digest of the Verilog keeps results across HDL changes that generate the same netlist (a
wrapper, a comment) and drops them after any change that does not. Generating a large core
takes up to half a minute, so the digest itself is remembered per HDL source version. A
sweep document committed with the repository can seed the cache of a fresh machine.
"""

import dataclasses
import hashlib
import json
from pathlib import Path

from ...hdl.verilog import core_verilog
from ...params import StereoParams
from ..atomic import write_text
from ..flow.capacity import DEFAULT_DEVICE
from ..flow.nextpnr import Placement
from ..flow.tools import tool_versions

__all__ = ["source_hash", "golden_source_hash", "verilog_digest", "configuration_digest",
           "design", "memoised_digest", "cache_key", "seed_cache", "earlier_reports",
           "read_result", "store_result", "incomplete", "refused"]

#: The npstereo package's folder (this file is npstereo/gen/reports/cache.py).
_PACKAGE = Path(__file__).resolve().parents[2]
#: What the generated Verilog is made from: the HDL and the parameter object.
_SOURCES = (_PACKAGE / "hdl", _PACKAGE / "params")
#: What a disparity map is made from: the golden model and the parameter object.
_GOLDEN_SOURCES = (_PACKAGE / "golden", _PACKAGE / "params")


def _sources_digest(folders):
    digest = hashlib.sha256()
    for path in sorted(p for folder in folders for p in folder.rglob("*.py")):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]


#: The HDL sources as this process imported them (above, with core_verilog): hashed once,
#: not at every call, so that a long sweep whose sources are edited on disk meanwhile
#: does not file the Verilog of the code it runs under the digest of the edited files
#: (a memo written so named a stale netlist as the new one's).
_SOURCE_HASH = _sources_digest(_SOURCES)


def source_hash():
    """Digest of the HDL sources this process runs: the fast path to a configuration's
    Verilog digest."""
    return _SOURCE_HASH


def golden_source_hash():
    """Digest of the golden model's sources: part of the key of every quality result."""
    return _sources_digest(_GOLDEN_SOURCES)


def verilog_digest(text):
    """Digest of generated Verilog without its header comment (which names versions)."""
    body = "\n".join(line for line in text.splitlines() if not line.startswith("//"))
    return hashlib.sha256(body.encode()).hexdigest()[:24]


def _digest_memo(params, cache):
    if cache is None:
        return None
    name = hashlib.sha256(f"{source_hash()} {params!r}".encode()).hexdigest()[:24]
    return Path(cache) / "verilog" / f"{name}.txt"


def memoised_digest(params, cache):
    """The Verilog digest of ``params`` from the memo in ``cache``, or None (nothing is
    generated)."""
    memo = _digest_memo(params, cache)
    if memo is not None and memo.exists():
        return memo.read_text().strip()
    return None


def design(params, cache):
    """``(digest, verilog)`` of ``params``; ``verilog`` is None when the digest came from
    the memo in ``cache`` (a folder, or None for no memo)."""
    digest = memoised_digest(params, cache)
    if digest is not None:
        return digest, None
    memo = _digest_memo(params, cache)
    verilog = core_verilog(params)
    digest = verilog_digest(verilog)
    if memo is not None:
        write_text(memo, digest + "\n")
    return digest, verilog


def configuration_digest(params, cache=None):
    """Digest of the Verilog that ``params`` generates, memoised in ``cache`` per HDL
    source version."""
    return design(params, cache)[0]


def cache_key(params, target, pnr, freq, digest, device=DEFAULT_DEVICE,
              placement=Placement()):
    """Key of one result: configuration, target, tools and the Verilog's digest, and for
    ECP5 place and route the clock constraint, the part and the placer's choices (the
    LFE5U-85F's results at nextpnr's own choices keep the key they had before other parts,
    seeds, weights and the router's weights could be chosen)."""
    if target != "ecp5" or not pnr:
        pnr, freq, device, placement = False, None, DEFAULT_DEVICE, Placement()  # nextpnr's
    # ``auto`` is the line buffer it chooses: a single report with the default and the
    # paper sweep's explicit choice are one netlist, and one result.
    params = dataclasses.replace(params, line_buffer=params.stored_rows)
    key = {"params": repr(params), "target": target, "pnr": pnr, "freq": freq,
           "tools": tool_versions(), "verilog": digest}
    if device != DEFAULT_DEVICE:
        key["device"] = device
    key.update({name: value for name, value in placement.fields().items()
                if value is not None and value is not False})
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:24]


def read_result(path):
    """A cached result (a dict marked ``cached``), or None when there is none."""
    path = Path(path)
    if not path.exists():
        return None
    return dict(json.loads(path.read_text()), cached=True)


def store_result(path, result):
    """Cache ``result`` at ``path`` atomically, without its ``cached`` mark; a complete
    result already there is kept (results under one key are equal)."""
    path = Path(path)
    existing = read_result(path)
    if existing is None or incomplete(existing):
        write_text(path, json.dumps({k: v for k, v in result.items() if k != "cached"},
                                    indent=1))


def incomplete(result):
    """Whether a cached ECP5 result predates the count of carry chains: its LUT
    utilisation leaves out the four LUT sites nextpnr packs into every chain
    (:mod:`npstereo.gen.flow.capacity`), so its synthesis is run again, without place and
    route."""
    return result.get("target") == "ecp5" and result.get("logic") is not None and \
        "carry_chains" not in result


def refused(result):
    """Whether ``result`` is a verdict given without synthesis: the device cannot hold the
    core's memories (:func:`.synthesis.memory_refusal`). It is never stored: giving it
    again costs nothing, and a stored one would outlive a change of the device table."""
    return result.get("synthesised") is False


def earlier_reports(sweep_json, cache):
    """The reports of an earlier sweep document that hold for the current tools and HDL:
    same tool versions and the same generated Verilog (``verilog_sha`` of the report; a
    document without it must come from the current HDL sources). A list of
    ``(params, digest, report)``; empty when there is no such document."""
    try:
        document = json.loads(Path(sweep_json).read_text())
    except (OSError, ValueError):
        return []
    if document.get("tools") != tool_versions():
        return []
    same_sources = document.get("hdl_sources") == source_hash()
    holding = []
    for report in document.get("reports", []):
        if "verilog_sha" in report and report["verilog_sha"] is None:
            continue  # every target refused for its memory: nothing to hold, nothing to
            # generate the digest of (the Verilog of a core too big for any device)
        params = StereoParams(**report["params"])
        digest = configuration_digest(params, cache)
        if report.get("verilog_sha", digest if same_sources else None) == digest:
            holding.append((params, digest, report))
    return holding


def seed_cache(sweep_json, cache):
    """Put the results of an earlier sweep document into the cache; returns how many.

    A sweep is committed with the repository (docs/resources/sweep.json) but the cache
    lives on one machine: this lets a fresh machine resume the sweep instead of
    synthesising for hours what the document already holds. Only what
    :func:`earlier_reports` finds still holds is taken.
    """
    seeded = 0
    for params, digest, report in earlier_reports(sweep_json, cache):
        for target, result in report["results"].items():
            # "does not fit" is an answer like "ok": without it a fresh machine would
            # synthesise the largest cores again for an hour to learn what it says.
            if result.get("status") not in ("ok", "failed", "does not fit") or refused(result):
                continue
            if target == "ecp5" and "freq" not in result:
                continue  # an older result that did not record its nextpnr settings
            # Keyed by the choices the result was placed with (recorded since they could
            # be chosen), not the flow's default for the core, which may be other ones.
            key = cache_key(params, target, result.get("pnr", False), result.get("freq"),
                            digest, placement=Placement.recorded(result))
            path = Path(cache) / f"{key}.json"
            if not path.exists():
                store_result(path, result)
                seeded += 1
    return seeded
