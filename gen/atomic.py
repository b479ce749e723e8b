"""Atomic output files: written to a temporary file beside the target, then renamed.

A crash or an error half-way leaves the previous file (or nothing), never a torn one. A
file that cannot be written (its folder cannot be created, is read-only, the disk is full)
is an :class:`OutputError` naming it, which the command line prints as one line.
"""

import contextlib
import os
import tempfile
from pathlib import Path

from ..params import UserError

__all__ = ["OutputError", "atomic_path", "write_bytes", "write_text"]


class OutputError(UserError):
    """An output file that cannot be written."""


def _new_file_mode():
    """The mode ``open()`` gives a new file, 0666 less the umask: ``mkstemp`` makes 0600,
    which would leave a generated core unreadable to the user's other tools and team."""
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def _failed(target, error):
    return OutputError(f"cannot write {target}: {error.strerror or error}")


@contextlib.contextmanager
def atomic_path(target, suffix=None):
    """Yield a temporary path; on success it is renamed to ``target``, on error removed.

    ``suffix`` defaults to the target's own, for tools that choose a format by extension.
    An ``OSError`` on the way (creating the folder or the file, writing, renaming) is
    raised as an :class:`OutputError`.
    """
    target = Path(target)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=suffix or target.suffix,
                                   dir=target.parent)
    except OSError as error:
        raise _failed(target, error) from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _new_file_mode())
        os.replace(tmp, target)
    except BaseException as error:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(error, OSError):
            raise _failed(target, error) from error
        raise


def write_bytes(target, data):
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)


def write_text(target, text):
    with atomic_path(target) as tmp:
        tmp.write_text(text)
