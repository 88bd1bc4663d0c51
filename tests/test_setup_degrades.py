"""`make system-packages` never stops the set-up: a package it cannot install is named, with
the reason, in one line, and make goes on (exit 0), so `make demo` still installs marchlab and
renders with the NumPy reference.

Each case runs the real Makefile target with PATH limited to a folder of the tools its recipe
uses, where `id`, `sudo` and `apt-get` are stand-ins: not root without sudo, no apt-get, and an
apt-get that fails as it does offline. The package asked for never exists, so nothing is
installed for real.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
REAL_TOOLS = ("sh", "dpkg-query", "grep", "mktemp", "tail", "rm", "env", "cat")
MISSING = "marchlab-no-such-package"

pytestmark = pytest.mark.skipif(shutil.which("make") is None or shutil.which("dpkg-query") is None,
                                reason="needs make and a Debian system (dpkg-query)")


def run_target(tmp_path, fakes: dict[str, str]) -> subprocess.CompletedProcess:
    """``make system-packages`` with only REAL_TOOLS and the shell scripts ``fakes`` on PATH."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for tool in REAL_TOOLS:
        (bin_dir / tool).symlink_to(shutil.which(tool))
    for name, script in fakes.items():
        (bin_dir / name).write_text(f"#!/bin/sh\n{script}\n")
        (bin_dir / name).chmod(0o755)
    return subprocess.run([shutil.which("make"), "--no-print-directory", "-C", str(ROOT),
                           "system-packages", f"SYSTEM_PACKAGES={MISSING}"],
                          env={"PATH": str(bin_dir), "HOME": os.environ.get("HOME", "/")},
                          capture_output=True, text=True, timeout=60)


def assert_one_line_and_going_on(result, reason: str) -> None:
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if line.startswith("marchlab:")]
    assert lines == [f"marchlab: cannot install {MISSING} ({reason}): going on without them"] \
        or lines == [f"marchlab: could not install {MISSING} ({reason}): going on without them"], \
        result.stdout
    assert result.stderr == ""


def test_not_root_and_no_sudo_names_the_package_and_goes_on(tmp_path):
    result = run_target(tmp_path, {"id": "echo 1000"})
    assert_one_line_and_going_on(result, "not root, and no sudo")


def test_no_apt_get_names_the_package_and_goes_on(tmp_path):
    result = run_target(tmp_path, {"id": "echo 0"})
    assert_one_line_and_going_on(result, "no apt-get")


def test_apt_get_failing_offline_gives_its_last_line_and_goes_on(tmp_path):
    offline = "echo 'W: Failed to fetch http://deb.debian.org/ (no network)'; " \
              "echo 'E: Unable to locate package x' >&2; exit 100"
    result = run_target(tmp_path, {"id": "echo 0", "apt-get": offline})
    assert "installing system packages: " + MISSING in result.stdout
    assert_one_line_and_going_on(result, "E: Unable to locate package x")
