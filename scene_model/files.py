"""Writing files so that a crash or a bad input never leaves a half-written one behind."""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path


def write_atomically(path: str | os.PathLike, payload: bytes) -> None:
    """Write ``payload`` to a temporary file beside ``path``, then rename it into place.

    The rename is atomic on POSIX, so readers see either the old file or the whole new one.
    An `OSError` names ``path``, never the temporary file.
    """
    write_together({path: payload})


def write_together(payloads: Mapping[str | os.PathLike, bytes]) -> None:
    """Write several files as one output: every payload to a temporary file beside its
    target first, then each temporary renamed into place.

    If any temporary cannot be written (a full disk, a folder where a file should go), no
    target is touched and every temporary is removed, so a command's outputs appear all
    together or not at all. An `OSError` names the user's path, never a temporary file's.
    """
    written: dict[Path, str] = {}
    try:
        for path, payload in payloads.items():
            path = Path(path)
            written[path] = _named(path, _write_temporary, path, payload)
        for path, tmp in written.items():
            _named(path, os.replace, tmp, path)
            written[path] = ""
    finally:
        for tmp in written.values():
            if tmp:
                os.unlink(tmp)


def _write_temporary(path: Path, payload: bytes) -> str:
    """A temporary file beside ``path`` holding ``payload`` (with the mode ``path`` will
    have); its name."""
    if path.is_dir():                         # os.replace would fail only after the others
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    mode = _mode_for(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, mode)                   # mkstemp makes files private (0600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
    except BaseException:
        os.unlink(tmp)
        raise
    return tmp


def _named(path: Path, function, *args, **kwargs):
    """``function(*args, **kwargs)``, with an `OSError` re-raised naming ``path``."""
    try:
        return function(*args, **kwargs)
    except OSError as err:
        if err.errno is None or err.filename == str(path):
            raise
        raise type(err)(err.errno, err.strerror, str(path)) from None


def _mode_for(path: Path) -> int:
    """The permissions the file should end with: those of the file it replaces, else the
    ones a plain ``open(path, "w")`` would give (0666 less the umask)."""
    try:
        return path.stat().st_mode & 0o777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
