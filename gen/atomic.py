"""Atomic output files: written to a temporary file beside the target, then renamed.

A crash or an error half-way leaves the previous file (or nothing), never a torn one.
"""

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "write_bytes", "write_text"]


@contextlib.contextmanager
def atomic_path(target, suffix=None):
    """Yield a temporary path; on success it is renamed to ``target``, on error removed.

    ``suffix`` defaults to the target's own, for tools that choose a format by extension.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix or target.suffix,
                               dir=target.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_bytes(target, data):
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)


def write_text(target, text):
    with atomic_path(target) as tmp:
        tmp.write_text(text)
