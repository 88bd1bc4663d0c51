"""How the CLI tests run ``marchlab``, shared by tests/test_cli*.py and tests/gpu/test_gpu_cli.py.

``pythonpath = ["tests"]`` (pyproject.toml) makes this importable from every test folder.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from marchlab.cli import main


def run_cli(capsys, *argv) -> tuple[int, str, str]:
    """``marchlab ARGV`` in-process: (exit code, stdout, stderr)."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit_:                     # argparse exits on a usage error
        code = exit_.code
    out, err = capsys.readouterr()
    return code, out, err


def run_marchlab(*argv, cwd) -> subprocess.CompletedProcess:
    """The real ``marchlab`` command in a subprocess (the console script if installed)."""
    script = shutil.which("marchlab", path=str(Path(sys.executable).parent))
    command = [script] if script else [sys.executable, "-m", "marchlab.cli"]
    return subprocess.run(command + [str(a) for a in argv], cwd=cwd, capture_output=True,
                          text=True, timeout=120)


def leftovers(folder: Path) -> list[str]:
    """Temporary files a writer left behind (write_atomically names them .NAME.*.tmp)."""
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".tmp"))


def assert_one_line_error(code: int, err: str) -> None:
    """Exit code 2 and exactly one line on stderr, no traceback."""
    assert code == 2
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert err.startswith("marchlab"), err
    assert "Traceback" not in err
