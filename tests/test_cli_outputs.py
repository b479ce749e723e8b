"""Outputs that cannot be written: every command's ``--out`` (and ``--raw``, ``--json``)
that is unreachable, under a regular file or in a read-only folder is one line on stderr
naming the option and the path, exit code 2, and nothing is written. Also what keeps
``npstereo --help`` fast.
"""

import os
import re
import stat
import tempfile
from pathlib import Path

import pytest
from PIL import Image

from npstereo.gen.atomic import OutputError, write_text
from npstereo.gen.cli.main import COMMANDS, main

#: A path no process can create: /proc takes no new entries.
UNREACHABLE = "/proc/npstereo-nope"


def _writable(folder):
    try:
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


@pytest.fixture
def read_only(tmp_path):
    """A folder no file can be created in: a folder of mode 0555, or for root (whom the
    mode does not stop) /sys, mounted read-only."""
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    yield next((f for f in (folder, Path("/sys")) if f.is_dir() and not _writable(f)), None)
    folder.chmod(0o755)


def _argv(command, tmp_path):
    """``(argv before the output option, [(option, suffix or None for a folder)])``: a
    command that would run but for its outputs."""
    left, right = tmp_path / "left.png", tmp_path / "right.png"
    for image in (left, right):
        Image.new("L", (40, 8)).save(image)
    small = ["--block", "3", "--disparities", "8"]
    return {
        "match": ([command, str(left), str(right), *small], [("--out", ".png"),
                                                               ("--raw", ".npy")]),
        "eval": ([command, "--synthetic", *small], [("--json", ".json")]),
        "paper": ([command, "--synthetic", "--blocks", "3", "--disparities", "8"],
                  [("--out", None)]),
        "demo": ([command, "--no-hardware"], [("--out", None)]),
        "verilog": ([command, *small, "--width", "16", "--height", "4"], [("--out", ".v")]),
        "ip": ([command, *small, "--width", "16", "--height", "4"], [("--out", None)]),
        "cosim": ([command, "--simulator", "amaranth", "--synthetic", *small, "--crop", "16x4"],
                  [("--out", None)]),
        "report": ([command, *small, "--width", "16", "--height", "4"], [("--json", ".json")]),
        "prove": ([command, "--block", "3", "--disparities", "2", "--rounds", "1"],
                  [("--out", None)]),
        "explore": ([command, "--synthetic", "--transform", "census", *small[:2],
                     "--disparities", "8", "--width", "32", "--height", "8", "--device",
                     "ecp5-25k"], [("--out", None)]),
        "board": ([command, "ulx3s-85f", *small], [("--out", None)]),
    }[command]


def _files(root):
    return sorted(root.rglob("*"))


def _assert_one_line(capsys, argv, option, value, root):
    before = _files(root)
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("npstereo: error: "), captured.err
    assert f"{option} {value}" in lines[0], lines[0]
    assert "Traceback" not in captured.err + captured.out
    assert _files(root) == before


def _cases(tmp_path, read_only):
    """Output paths of each kind: the file or folder named as it would be written."""
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    cases = [Path(UNREACHABLE) / "deeper", a_file / "below"]
    if read_only is not None:
        cases.append(read_only / "inside")
    return cases


@pytest.mark.parametrize("command", list(COMMANDS))
def test_unwritable_outputs_are_one_line(command, tmp_path, read_only, capsys):
    argv, outputs = _argv(command, tmp_path)
    fine = tmp_path / "fine"
    for option, suffix in outputs:
        # The other outputs of the command are fine, so the error is this option's.
        others = [arg for o, s in outputs if o != option
                  for arg in (o, str(fine / f"x{s or ''}"))]
        for place in _cases(tmp_path, read_only):
            value = str(place) + (suffix or "")
            _assert_one_line(capsys, argv + others + [option, value], option, value, tmp_path)
        assert not fine.exists()


def test_report_paper_out_is_checked(tmp_path, capsys):
    """``report --paper`` writes its sweep into ``--out`` (without --paper it is unused)."""
    value = f"{UNREACHABLE}/resources"
    _assert_one_line(capsys, ["report", "--paper", "--out", value], "--out", value, tmp_path)


def test_the_atomic_writer_names_the_file(tmp_path):
    """What the early checks cannot foresee (a disk that fills up, a folder that goes
    away) still ends as one line naming the file, and leaves nothing behind."""
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    for target in (a_file / "x.txt", Path(UNREACHABLE) / "x.txt", tmp_path):
        with pytest.raises(OutputError, match=f"^cannot write {re.escape(str(target))}: "):
            write_text(target, "text")
    assert _files(tmp_path) == [a_file]


def test_help_loads_no_heavy_library(libraries_loaded):
    """``npstereo --help`` lists the commands without importing any of them: none of the
    libraries they pull in (each of these takes a quarter to over a second to import)."""
    code, output, loaded = libraries_loaded(["--help"], {
        "matplotlib", "distributed", "dask", "amaranth", "cocotb", "tqdm", "PIL"})
    assert code == 0 and "explore" in output
    assert loaded == "[]"


@pytest.mark.parametrize("umask", [0o022, 0o077])
def test_outputs_get_the_mode_of_a_new_file(tmp_path, umask):
    """A written file is readable as a plainly created one would be (mkstemp's 0600 left a
    generated core unreadable to the user's other tools); broken variant: the writer
    without its chmod leaves 0600, which the umask 022 case rejects."""
    old = os.umask(umask)
    try:
        write_text(tmp_path / "core.v", "module m; endmodule\n")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "core.v").stat().st_mode) == 0o666 & ~umask
