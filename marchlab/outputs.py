"""A command's outputs: checked before any work starts, written together at the end.

A command that would compute for a minute and then fail to write its file has wasted the
minute, and one that writes its first file and fails on its second has left half an answer.
So every command names all its outputs up front and `check_outputs` tries each the way the
write will (is it a folder, is its folder a file, can a file be made there), before the work;
the results are then written by `scene_model.files.write_together`, every temporary first
and every rename after. Errors name the user's path.
"""

from __future__ import annotations

import os
from pathlib import Path

from scene_model.errors import MarchlabError


def check_outputs(files=(), folders=()) -> None:
    """Raise `MarchlabError` (naming the path) unless every path of ``files`` can be written
    as a file and every path of ``folders`` can hold files; None paths are skipped.

    A missing parent folder is fine if it can be made: writing makes it.
    """
    seen: dict[Path, str] = {}
    for path, kind in [(f, "file") for f in files] + [(d, "folder") for d in folders]:
        if path is None:
            continue
        path = Path(path)
        key = Path(os.path.abspath(path))
        if key in seen:
            raise MarchlabError(f"{path}: named twice as an output")
        seen[key] = kind
        try:
            _check_output(path, kind)
        except OSError as err:      # a name the system refuses (too long, ...)
            raise MarchlabError(f"{path}: cannot write there: {err.strerror}") from None


def _check_output(path: Path, kind: str) -> None:
    """Raise `MarchlabError` unless ``path`` can be written as a ``kind`` ("file"/"folder")."""
    if kind == "file":
        if path.is_dir():
            raise MarchlabError(f"{path}: is a folder (give a file name)")
        _check_folder(path, path.parent)
    else:
        if path.exists() and not path.is_dir():
            raise MarchlabError(f"{path}: is a file, not a folder")
        _check_folder(path, path)


def _check_folder(path: Path, folder: Path) -> None:
    """``folder`` (where ``path`` goes) exists and is writable, or can be made in the
    nearest folder above it that exists."""
    existing = folder
    while not existing.exists():
        if existing.is_symlink():
            raise MarchlabError(f"{path}: {existing} is a broken link")
        if existing.parent == existing:
            break
        existing = existing.parent
    if not existing.is_dir():
        raise MarchlabError(f"{path}: {existing} is not a folder")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise MarchlabError(f"{path}: cannot write in {existing}/ (permission denied)")


def make_folders(*paths) -> None:
    """Make the folder of every file of ``paths`` (None skipped), naming the file if that
    fails."""
    for path in paths:
        if path is None:
            continue
        try:
            Path(path).parent.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise MarchlabError(f"{path}: cannot make its folder: {err.strerror}") from None
