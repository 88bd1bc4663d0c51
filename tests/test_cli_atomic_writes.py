"""Writing an output never leaves a half-written file (`scene_model.files.write_atomically`).

A failed render or a failed PNG encoding keeps the previous file and leaves no temporary file;
the payload goes to a temporary file in the same folder that is renamed over the target only
when complete; written files get ordinary permissions, or keep those of the file replaced.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from PIL import Image
from cli_helpers import assert_one_line_error, leftovers, run_cli

from scene_model.files import write_atomically


def test_failed_render_leaves_the_existing_output_untouched_and_no_temp_file(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text('[[objects]]\ntype = "sphere"\nradius = -1.0\n')
    out = tmp_path / "out.png"
    out.write_bytes(b"the previous picture")
    code, _, _ = run_cli(capsys, "render", scene, "-o", out, "--size", "4x3")
    assert code == 2
    assert out.read_bytes() == b"the previous picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "out.png"]


def test_png_encoding_failure_keeps_the_old_file_and_leaves_no_temp_file(tmp_path, capsys,
                                                                         monkeypatch):
    def broken_save(self, fp, format=None, **params):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(Image.Image, "save", broken_save)
    out = tmp_path / "out.png"
    out.write_bytes(b"the previous picture")
    code, _, err = run_cli(capsys, "render", "classroom", "-o", out, "--size", "4x3")
    assert_one_line_error(code, err)
    assert str(out) in err
    assert out.read_bytes() == b"the previous picture"
    assert leftovers(tmp_path) == []


class FailingFile:
    """A file object whose write fails half way, like a full disk."""

    def __init__(self, real):
        self.real = real

    def write(self, payload):
        self.real.write(payload[:len(payload) // 2])
        raise OSError(28, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.real.close()


def test_write_atomically_removes_its_temp_file_when_the_payload_write_fails(tmp_path,
                                                                             monkeypatch):
    target = tmp_path / "image.png"
    target.write_bytes(b"old")
    real_fdopen = os.fdopen
    monkeypatch.setattr("scene_model.files.os.fdopen",
                        lambda fd, *args, **kw: FailingFile(real_fdopen(fd, *args, **kw)))
    with pytest.raises(OSError):
        write_atomically(target, b"new contents" * 100)
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["image.png"]


def test_write_atomically_renames_a_complete_temp_file_over_the_target(tmp_path, monkeypatch):
    target = tmp_path / "image.png"
    target.write_bytes(b"old")
    payload = b"new contents" * 100
    seen = {}
    real_replace = os.replace

    def spying_replace(src, dst):
        # At the moment of the rename the target is still whole and old, the temp file whole
        # and new, and both are in the same folder (so the rename is atomic).
        seen.update(src=Path(src), dst=Path(dst), target_then=target.read_bytes(),
                    temp_then=Path(src).read_bytes())
        real_replace(src, dst)

    monkeypatch.setattr("scene_model.files.os.replace", spying_replace)
    write_atomically(target, payload)
    assert seen["dst"] == target and seen["src"].parent == tmp_path
    assert seen["src"].name.startswith(".image.png.") and seen["src"].name.endswith(".tmp")
    assert seen["target_then"] == b"old" and seen["temp_then"] == payload
    assert target.read_bytes() == payload
    assert sorted(p.name for p in tmp_path.iterdir()) == ["image.png"]


def test_written_files_get_ordinary_permissions_or_keep_the_old_ones(tmp_path):
    """A new file gets 0666 less the umask like open(); a replaced file keeps its mode."""
    umask = os.umask(0o022)
    try:
        fresh = tmp_path / "fresh.png"
        write_atomically(fresh, b"new")
        assert fresh.stat().st_mode & 0o777 == 0o644
        kept = tmp_path / "kept.png"
        kept.write_bytes(b"old")
        kept.chmod(0o640)
        write_atomically(kept, b"new")
        assert kept.stat().st_mode & 0o777 == 0o640 and kept.read_bytes() == b"new"
    finally:
        os.umask(umask)


def test_write_together_touches_no_target_when_one_temporary_fails(tmp_path):
    """The second file cannot be written (its folder is missing): the first keeps its old
    contents, and no temporary file is left."""
    from scene_model.files import write_together
    first = tmp_path / "first.gif"
    first.write_bytes(b"old")
    second = tmp_path / "missing-folder" / "second.csv"
    with pytest.raises(FileNotFoundError) as caught:
        write_together({first: b"new", second: b"rows"})
    assert caught.value.filename == str(second)            # the user's path, not a temporary
    assert first.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["first.gif"]


def test_write_together_refuses_a_folder_as_a_target_before_renaming_anything(tmp_path):
    from scene_model.files import write_together
    (tmp_path / "DIR").mkdir()
    with pytest.raises(IsADirectoryError) as caught:
        write_together({tmp_path / "ok.gif": b"gif", tmp_path / "DIR": b"csv"})
    assert caught.value.filename == str(tmp_path / "DIR")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["DIR"]


def test_write_together_writes_every_file_whole(tmp_path):
    from scene_model.files import write_together
    payloads = {tmp_path / f"{name}.bin": name.encode() * 1000 for name in ("a", "b", "c")}
    write_together(payloads)
    assert {p: p.read_bytes() for p in payloads} == payloads
    assert leftovers(tmp_path) == []
