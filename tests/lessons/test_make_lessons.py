"""``make lessons`` serves the lessons from this machine only."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_make_lessons_opens_jupyterlab_on_the_lessons_bound_to_127_0_0_1():
    if shutil.which("make") is None:
        pytest.skip("no make here")
    # Run from `make test`, the inner make would inherit the outer one's flags and print
    # "Entering directory" lines: a clean environment, and the command found by its text.
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MAKELEVEL", "MFLAGS")}
    result = subprocess.run(["make", "--no-print-directory", "-n", "-W", "pyproject.toml",
                             "lessons"], cwd=ROOT, capture_output=True, text=True, timeout=60,
                            env=env)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if "jupyter lab" in line)
    text = " ".join(lines[start:start + 2])
    assert "jupyter lab" in text and "--ip=127.0.0.1" in text
    assert "root_dir=lessons" in text and "--allow-root" in text


def test_jupyterlab_is_in_the_lessons_extra():
    import tomllib
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    assert any(requirement.startswith("jupyterlab") for requirement in extras["lessons"])
    assert any(requirement.startswith("jupyter-rfb") for requirement in extras["lessons"])
