"""``marchlab view``'s bad input is one line and exit code 2, before any window opens."""

import os
import subprocess
import sys

import pytest


def _view(*arguments, env=None):
    return subprocess.run([sys.executable, "-m", "marchlab.cli", "view", *arguments],
                          capture_output=True, text=True, timeout=60, env=env)


@pytest.mark.parametrize("arguments, problem", [
    (["nosuch"], "nosuch: no such file or bundled scene"),
    (["classroom", "--screenshot", "a.jpg", "--frames", "2"], "a screenshot is a .png"),
    (["classroom", "--screenshot", "a.png"], "give --frames N too"),
    (["classroom", "--screenshot", "", "--frames", "2"], "--screenshot: an empty path"),
    (["classroom", "--frames", "0"], "expected a whole number from 1"),
    (["classroom", "--script", "absent.toml"], "absent.toml: cannot read the script"),
])
def test_bad_input_is_one_line_and_exit_code_2(tmp_path, arguments, problem):
    result = _view(*arguments)
    assert result.returncode == 2
    assert problem in result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr


def test_no_display_is_one_line_saying_how_to_fix_it():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = _view("classroom", env=env)
    assert result.returncode == 2
    assert "no display" in result.stderr and "xvfb-run" in result.stderr
    assert result.stderr.count("\n") == 1
