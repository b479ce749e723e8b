"""Worker process that runs a Yosys script in native Yosys (PyPI ``pyosys``).

``python -m npstereo.gen.flow.yosys_worker SCRIPT`` runs the commands of ``SCRIPT`` (one per
line, as :mod:`npstereo.gen.flow.yosys` writes them) on one design in this process and logs
to standard output, which the caller sends to ``yosys.log``.

Why a process of its own: libyosys runs in the calling process and cannot be interrupted,
and a Yosys ``ERROR`` ends the whole process (``log_error`` exits, it raises nothing in
Python). In a worker the caller keeps its timeout (it kills the worker's process group,
ABC included) and reads the failure from the exit code and the log.

The last line of the log is ``Time spent: ...`` like the one the ``yosys`` executable
prints, but per script command: libyosys does not expose the per-pass times the
executable sums up.
"""

import argparse
import os
import sys
import time

__all__ = ["main", "abc_executable"]


def abc_executable(ys):
    """Path of the ``yosys-abc`` that libyosys will start, checked to be executable.

    The wheel ships ``yosys-abc`` next to ``libyosys.so`` and ``pyosys/__init__.py``
    points Yosys at it; a wheel unpacked without the executable bit (or an install that
    lost the file) would only fail deep inside ``abc9``, so it is checked first.
    """
    path = ys.Globals.yosys_abc_executable or getattr(sys, "_pyosys_abc", "")
    if not path or not os.path.isfile(path) or not os.access(path, os.X_OK):
        raise SystemExit(f"ERROR: yosys-abc not found or not executable ({path or 'unset'});"
                         " reinstall it with pip install --force-reinstall pyosys")
    ys.Globals.yosys_abc_executable = path
    return path


def _commands(script_text):
    """Script lines without blank and comment lines (each is one Yosys command).

    A ``#`` later in a line is left to Yosys's own command parser, which knows quoting.
    """
    return [line.strip() for line in script_text.splitlines()
            if line.strip() and not line.strip().startswith("#")]


def _time_summary(times):
    """``Time spent:`` line in the format of the ``yosys`` executable, per command."""
    total = sum(seconds for _, seconds in times) or 1e-9
    ranked = sorted(times, key=lambda item: -item[1])
    parts = [f"{100 * seconds / total:.0f}% 1x {command} ({seconds:.0f} sec)"
             for command, seconds in ranked if seconds >= 0.01 * total]
    return "Time spent: " + ", ".join(parts)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m npstereo.gen.flow.yosys_worker",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("script", help="Yosys script, one command per line")
    args = parser.parse_args(argv)
    try:
        from pyosys import libyosys as ys
    except ImportError as error:
        print(f"ERROR: native Yosys is missing ({error}): pip install pyosys", flush=True)
        return 3
    with open(args.script, encoding="utf-8") as handle:
        commands = _commands(handle.read())
    print(ys.Globals.yosys_version_str, flush=True)
    print(f"yosys-abc: {abc_executable(ys)}", flush=True)
    design = ys.Design()
    times = []
    for command in commands:
        started = time.monotonic()
        # An ERROR inside run_pass exits this process with status 1 after logging it.
        ys.run_pass(command, design)
        times.append((command, time.monotonic() - started))
    print(_time_summary(times), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
