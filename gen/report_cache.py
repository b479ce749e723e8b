"""The result cache of ``npstereo report``: keyed on the generated Verilog and the tools.

A synthesis result depends on the Verilog and the tools, nothing else: keying the cache on
a digest of the Verilog keeps results across HDL changes that generate the same netlist (a
wrapper, a comment) and drops them after any change that does not. Generating a large core
takes up to half a minute, so the digest itself is remembered per HDL source version. A
sweep document committed with the repository can seed the cache of a fresh machine.
"""

import hashlib
import json
from pathlib import Path

from ..hdl.verilog import core_verilog
from ..params import StereoParams
from .atomic import write_text
from .synth import tool_versions

__all__ = ["source_hash", "verilog_digest", "configuration_digest", "design", "cache_key",
           "seed_cache"]

_PACKAGE = Path(__file__).resolve().parent.parent
#: What the generated Verilog is made from: the HDL and the parameter object.
_SOURCES = (_PACKAGE / "hdl", _PACKAGE / "params")


def source_hash():
    """Digest of the HDL sources: the fast path to a configuration's Verilog digest."""
    digest = hashlib.sha256()
    for path in sorted(p for folder in _SOURCES for p in folder.rglob("*.py")):
        digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:16]


def verilog_digest(text):
    """Digest of generated Verilog without its header comment (which names versions)."""
    body = "\n".join(line for line in text.splitlines() if not line.startswith("//"))
    return hashlib.sha256(body.encode()).hexdigest()[:24]


def _digest_memo(params, cache):
    if cache is None:
        return None
    name = hashlib.sha256(f"{source_hash()} {params!r}".encode()).hexdigest()[:24]
    return Path(cache) / "verilog" / f"{name}.txt"


def design(params, cache):
    """``(digest, verilog)`` of ``params``; ``verilog`` is None when the digest came from
    the memo in ``cache`` (a folder, or None for no memo)."""
    memo = _digest_memo(params, cache)
    if memo is not None and memo.exists():
        return memo.read_text().strip(), None
    verilog = core_verilog(params)
    digest = verilog_digest(verilog)
    if memo is not None:
        write_text(memo, digest + "\n")
    return digest, verilog


def configuration_digest(params, cache=None):
    """Digest of the Verilog that ``params`` generates, memoised in ``cache`` per HDL
    source version."""
    return design(params, cache)[0]


def cache_key(params, target, pnr, freq, digest):
    """Key of one result: configuration, target, tools and the Verilog's digest."""
    if target != "ecp5" or not pnr:
        pnr, freq = False, None  # only nextpnr depends on them
    text = json.dumps({"params": repr(params), "target": target, "pnr": pnr, "freq": freq,
                       "tools": tool_versions(), "verilog": digest}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def seed_cache(sweep_json, cache):
    """Put the results of an earlier sweep document into the cache; returns how many.

    A sweep is committed with the repository (docs/resources/sweep.json) but the cache
    lives on one machine: this lets a fresh machine resume the sweep instead of
    synthesising for hours what the document already holds. A result is taken only for
    the same tool versions and the same generated Verilog (``verilog_sha`` of its report;
    a document without it must come from the current HDL sources).
    """
    try:
        document = json.loads(Path(sweep_json).read_text())
    except (OSError, ValueError):
        return 0
    if document.get("tools") != tool_versions():
        return 0
    same_sources = document.get("hdl_sources") == source_hash()
    seeded = 0
    for report in document.get("reports", []):
        params = StereoParams(**report["params"])
        digest = configuration_digest(params, cache)
        if report.get("verilog_sha", digest if same_sources else None) != digest:
            continue
        for target, result in report["results"].items():
            if result.get("status") not in ("ok", "failed"):
                continue
            if target == "ecp5" and "freq" not in result:
                continue  # an older result that did not record its nextpnr settings
            key = cache_key(params, target, result.get("pnr", False), result.get("freq"),
                            digest)
            path = Path(cache) / f"{key}.json"
            if not path.exists():
                stored = {k: v for k, v in result.items() if k != "cached"}
                write_text(path, json.dumps(stored, indent=1))
                seeded += 1
    return seeded
