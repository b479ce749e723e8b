"""One external tool run: an argument list in a process group of its own, a deadline, and
a watch on its progress."""

import os
import signal
import subprocess
import time
from pathlib import Path

__all__ = ["run_tool", "INTERRUPTED"]

#: How :func:`run_tool`'s failure starts for a tool stopped by a signal from outside (a
#: user's ``kill``, the kernel's out-of-memory killer): not the design's failure, so its
#: result is not one to keep.
INTERRUPTED = "interrupted"

#: Seconds between looks at a running tool's log (:func:`run_tool`'s ``watch``).
_WATCH_SECONDS = 5.0


def run_tool(command, cwd, deadline, log_name, watch=None, name=None, env=None):
    """Run one tool; returns None or a one-line failure description (starting with
    :data:`INTERRUPTED` when a signal from outside stopped it).

    The tool runs in a process group of its own so that a timeout kills what it started
    too (native Yosys starts ``yosys-abc`` processes that would outlive their parent).
    Its standard output and error go to ``log_name`` in ``cwd``. ``deadline`` is a
    ``time.monotonic()`` value or None; past it the failure is ``timeout``. ``watch``, if
    given, is called every few seconds while the tool runs; a string it returns stops the
    tool and is returned as the failure. ``name`` is the tool in a failure (default: the
    executable's name). ``env``: the tool's environment (default: this process's).
    """
    with open(Path(cwd) / log_name, "wb") as log:
        process = subprocess.Popen(command, cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                                   start_new_session=True, env=env)
        try:
            while True:
                remaining = None if deadline is None else deadline - time.monotonic()
                if remaining is not None and remaining <= 0:
                    _kill_group(process)
                    return "timeout"
                step = remaining if watch is None else min(_WATCH_SECONDS,
                                                           remaining or _WATCH_SECONDS)
                try:
                    returncode = process.wait(timeout=step)
                    break
                except subprocess.TimeoutExpired:
                    verdict = None if watch is None else watch()
                    if verdict is not None:
                        _kill_group(process)
                        return verdict
        except BaseException:
            _kill_group(process)
            raise
    if returncode < 0:
        return (f"{INTERRUPTED}: {name or Path(command[0]).name} stopped by signal "
                f"{-returncode}")
    if returncode != 0:
        text = (Path(cwd) / log_name).read_text(errors="replace").splitlines()
        errors = ([line.strip() for line in text if "ERROR" in line]
                  or [line.strip() for line in text if line.strip()][-1:] or ["no output"])
        return f"{name or Path(command[0]).name} exit {returncode}: {errors[0][:200]}"
    return None


def _kill_group(process):
    """Kill the tool and every process it started (its own process group)."""
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    process.wait()
