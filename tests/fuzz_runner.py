"""Run one ``marchlab`` command line in-process and judge how it ended: the referee of the
fuzzing test (tests/test_fuzz_inputs.py) and of its larger run (benchmarks/fuzz_inputs.py).

The promise under test (README, "A mistake in a scene file or an option ..."): a command
either succeeds, exit 0, with complete and finite outputs, or is refused, exit 2, with exactly
one line on stderr naming the file and the field, or the option; never a traceback, never a
hang, never a partial or temporary file. `run_case` runs a `Case` in a folder of its own,
under a time limit (SIGALRM) and a memory limit (RLIMIT_AS, so that a render of 10,000 x
10,000 pixels ends in a MemoryError here instead of exhausting a shared machine), and says
which of `OUTCOMES` it reached.
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
import os
import re
import resource
import shlex
import signal
import sys
import time
import tomllib
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from marchlab.cli import main

ROOT = Path(__file__).resolve().parent.parent

# What a case can come to; the first two keep the promise.
OUTCOMES = ("rendered", "refused", "traceback", "hang", "partial file", "non-finite output",
            "warning", "bad error line", "not refused")
PASSED = ("rendered", "refused")

MEMORY_LIMIT = 3 << 30        # bytes a case may add to the process's address space


@dataclass(frozen=True)
class Case:
    """One command line to try, and what a refusal of it must name.

    Attributes
    ----------
    kind : str
        The kind of mutation, a row of the outcome table ("huge integer", "--size", ...).
    argv : tuple of str
        The arguments after ``marchlab``; paths are relative to the case's folder.
    what : str
        The mutation in words, e.g. ``objects[1].radius = 1e308``.
    names : tuple of str
        A refusal must name at least one of these: the option, its value, a field.
    file : str
        When set, a refusal must name this file too (the mutated scene file).
    scene_text : str or None
        The TOML written to ``scene.toml`` in the case's folder before the run.
    must_refuse : bool
        Succeeding is a failure too (a value no reading can accept, on a command too slow to
        run in full here).
    time_limit : float
        Seconds before the case counts as a hang.
    """
    kind: str
    argv: tuple[str, ...]
    what: str
    names: tuple[str, ...] = ()
    file: str = ""
    scene_text: str | None = None
    must_refuse: bool = False
    time_limit: float = 10.0

    def command(self) -> str:
        """The command line as a shell would take it (with ``scene.toml`` as written)."""
        return shlex.join(["marchlab", *self.argv])


@dataclass(frozen=True)
class Result:
    outcome: str        # one of OUTCOMES
    detail: str         # one line: the exception and where, the stderr, the file at fault
    seconds: float


class Hang(BaseException):
    """Raised by the alarm in a case that ran past its time limit (a BaseException, so that
    no ``except Exception`` on the way can swallow it)."""


# Files every case folder holds before the run, for options to point at.
FIXTURES = {"a_file": b"not a scene\n", "empty.toml": b"", "binary.toml": b"\xff\xfe\x00\x81",
            "not_toml.toml": b"[camera\nfov = \n"}
FOLDERS = ("a_folder",)


def run_case(case: Case, folder: Path) -> Result:
    """Run ``marchlab *case.argv`` in ``folder`` (created) and judge it."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, payload in FIXTURES.items():
        (folder / name).write_bytes(payload)
    for name in FOLDERS:
        (folder / name).mkdir(exist_ok=True)
    if case.scene_text is not None:
        (folder / "scene.toml").write_text(case.scene_text, encoding="utf-8")
    before = snapshot(folder)
    out, err = io.StringIO(), io.StringIO()
    code, error = None, None
    start = time.perf_counter()
    with in_folder(folder), memory_limit(MEMORY_LIMIT), cli_recursion_limit(), \
            warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                signal.signal(signal.SIGALRM, _alarm)
                signal.setitimer(signal.ITIMER_REAL, case.time_limit)
                try:
                    code = main(list(case.argv))
                finally:
                    signal.setitimer(signal.ITIMER_REAL, 0)
        except SystemExit as exit_:                      # argparse's usage errors
            code = exit_.code
        except BaseException as exc:                     # what the promise rules out
            error = exc
    seconds = time.perf_counter() - start
    outcome, detail = judge(case, folder, before, code, error, out.getvalue(), err.getvalue(),
                            caught)
    return Result(outcome, detail, seconds)


def _alarm(signum, frame):
    raise Hang()


@contextlib.contextmanager
def in_folder(folder: Path):
    """Run with ``folder`` as the working directory and ``sys.argv`` as the CLI would see it."""
    cwd, argv = os.getcwd(), sys.argv
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(cwd)
        sys.argv = argv


@contextlib.contextmanager
def memory_limit(extra: int):
    """Let the process map at most ``extra`` more bytes while inside (Linux only)."""
    try:
        with open("/proc/self/status") as status:
            size = next(int(line.split()[1]) * 1024 for line in status
                        if line.startswith("VmSize:"))
        soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    except (OSError, StopIteration):
        yield
        return
    limit = size + extra if hard == resource.RLIM_INFINITY else min(size + extra, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@contextlib.contextmanager
def cli_recursion_limit(frames: int = 1000):
    """Give the command the ``frames`` of Python recursion it has as a process of its own.

    Hypothesis raises the limit while it runs a test; without this, a scene nested deeper
    than the real command can read would get through to code (and C libraries) below.
    """
    depth, frame = 0, sys._getframe()
    while frame is not None:
        depth, frame = depth + 1, frame.f_back
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(depth + frames)
    try:
        yield
    finally:
        sys.setrecursionlimit(limit)


def snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file under ``folder``: relative path -> (size, mtime in ns)."""
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in folder.rglob("*") if p.is_file()}


# --- Judging ---------------------------------------------------------------------------------

def judge(case, folder, before, code, error, out, err, caught) -> tuple[str, str]:
    """The outcome of a finished case and one line of detail."""
    if isinstance(error, Hang):
        return "hang", f"ran past {case.time_limit:g} s, in {where(error)}"
    if error is not None:
        message = one_line(str(error))[:160]
        return "traceback", f"{type(error).__name__}: {message} (in {where(error)})"
    after = snapshot(folder)
    written = sorted(p for p in after if before.get(p) != after[p])
    temporary = [p for p in written if p.endswith(".tmp")]
    if temporary:
        return "partial file", f"left {', '.join(temporary)} (exit {code})"
    warned = [f"{w.category.__name__}: {one_line(str(w.message))[:100]}" for w in caught]
    finished = code == 0 or (code == 1 and case.argv[0] == "compare"
                             and out.rstrip().endswith("gates)"))   # a failed gate: exit 1
    if finished:
        for path in written:
            problem = output_problem(folder / path)
            if problem:
                return ("non-finite output" if "NaN" in problem or "inf" in problem
                        else "partial file"), f"{path}: {problem}"
        problem = stdout_problem(case.argv, out)
        if problem:
            return "non-finite output", problem
        if case.must_refuse:
            return "not refused", f"exit {code}"
        if warned:
            return "warning", warned[0]
        # marchlab.cli.main sums warnings up in lines of its own; one saying that the
        # arithmetic went out of range means a range let an absurd value through.
        stray = [line for line in err.splitlines()
                 if line and (not line.startswith("marchlab: ") or "out of range" in line)]
        if stray:
            return "warning", one_line(stray[0])[:160]
        return "rendered", ""
    if code != 2:
        return "bad error line", f"exit code {code!r}; stderr {err[-200:]!r}"
    if written:
        return "partial file", f"wrote {', '.join(written)} and exited 2: {one_line(err)[:120]}"
    if warned:
        return "warning", warned[0]
    problem = error_line_problem(case, err)
    if problem:
        return "bad error line", problem
    return "refused", err.strip()


def error_line_problem(case: Case, err: str) -> str | None:
    """What is wrong with the stderr of a refusal, or None: it must be exactly one line,
    marchlab's own, naming ``case.file`` (if set) and one of ``case.names``."""
    if not (err.endswith("\n") and err.count("\n") == 1 and err.startswith("marchlab")):
        return f"not one line of marchlab's: {err[:300]!r}"
    if case.file and case.file not in err:
        return f"does not name {case.file}: {err.strip()}"
    if case.names and not any(name in err for name in case.names):
        return f"names none of {', '.join(map(repr, case.names[:6]))}: {err.strip()}"
    return None


def output_problem(path: Path) -> str | None:
    """Why a file a command wrote is incomplete or holds non-finite numbers, else None."""
    suffix = path.suffix.lower()
    try:
        if suffix in (".png", ".gif"):
            from PIL import Image, ImageSequence
            with Image.open(path) as image:
                for frame in ImageSequence.Iterator(image):
                    frame.load()
        elif suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                return npz_problem({key: data[key] for key in data.files})
        elif suffix == ".csv":
            with open(path, newline="") as handle:
                for row in list(csv.reader(handle))[1:]:
                    if any(not math.isfinite(float(cell)) for cell in row):
                        return f"a non-finite number (NaN or inf) in row {row}"
        elif suffix in (".md", ".toml"):
            if not path.read_text(encoding="utf-8").strip():
                return "empty"
    except Exception as err:          # anything that cannot be read back is incomplete
        return f"cannot be read back ({type(err).__name__}: {one_line(str(err))[:100]})"
    return None


def npz_problem(arrays: dict) -> str | None:
    """NaN anywhere, or inf anywhere but a depth where nothing was hit."""
    hit = arrays.get("hit")
    for name, array in arrays.items():
        if not np.issubdtype(array.dtype, np.floating):
            continue
        if np.isnan(array).any():
            return f"NaN in {name}"
        infinite = np.isinf(array)
        if name == "depth" and hit is not None and hit.shape == array.shape:
            infinite &= hit.astype(bool)
        if infinite.any():
            return f"inf in {name}"
    return None


NON_FINITE_WORD = re.compile(r"(?<![\w.])[-+]?(nan|inf)(?![\w.])")
FLOAT_LITERAL = re.compile(r"(?<![\w.])\d+(?:\.\d*)?[eE][-+]?\d+")
FLOAT32_MAX = float(np.finfo(np.float32).max)


def stdout_problem(argv, out: str) -> str | None:
    """Non-finite numbers a command printed: in the TOML of ``show``, the table of ``compare``,
    or the code of ``shader`` (a literal beyond float32, which the compiler makes inf)."""
    command = argv[0] if argv else ""
    if command == "show":
        try:
            data = tomllib.loads(out)
        except tomllib.TOMLDecodeError as err:
            return f"show printed TOML that does not load back: {err}"
        bad = [repr(v) for v in leaves(data) if isinstance(v, float) and not math.isfinite(v)]
        return f"show printed {bad[0]}" if bad else None
    if command == "compare":
        words = [m.group(0) for m in NON_FINITE_WORD.finditer(out) if "nan" in m.group(0)]
        return f"compare printed {words[0]}" if words else None
    if command == "shader":
        code = re.sub(r"//[^\n]*|/\*.*?\*/", "", out, flags=re.DOTALL)
        words = [m.group(0) for m in NON_FINITE_WORD.finditer(code)]
        if words:
            return f"shader wrote {words[0]}"
        if "float64" not in argv:
            big = [m.group(0) for m in FLOAT_LITERAL.finditer(code)
                   if float(m.group(0)) > FLOAT32_MAX]
            if big:
                return f"shader wrote {big[0]}, which is inf in float32"
    return None


def leaves(tree):
    """Every scalar of a parsed TOML tree."""
    if isinstance(tree, dict):
        for value in tree.values():
            yield from leaves(value)
    elif isinstance(tree, list):
        for value in tree:
            yield from leaves(value)
    else:
        yield tree


def where(error: BaseException) -> str:
    """The innermost frame of this repository's code a traceback went through."""
    frames = traceback.extract_tb(error.__traceback__)
    ours = [f for f in frames if f.filename.startswith(str(ROOT)) and
            "/tests/" not in f.filename and ".venv" not in f.filename]
    if not (ours or frames):
        return "?"
    frame = (ours or frames)[-1]
    path = Path(frame.filename)
    name = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path.name
    return f"{name}:{frame.lineno} {frame.name}"


def one_line(text: str) -> str:
    return " ".join(text.split())


# --- Many cases ----------------------------------------------------------------------------

def run_examples(strategy, folder: Path, max_examples: int, seed: int | None = None,
                 on_result=None) -> list[tuple[Case, Result, Path]]:
    """Draw up to ``max_examples`` cases from ``strategy`` and run each in a folder of its own
    under ``folder``; every result is kept (none stops the run), so a test can list them all.

    Hypothesis draws the cases (with the active profile's derandomisation, or from ``seed``);
    it does not shrink them: a hang would cost its time limit at every step of shrinking.
    """
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as with_seed

    results = []

    @settings(max_examples=max_examples, phases=[Phase.explicit, Phase.generate],
              deadline=None, database=None, suppress_health_check=list(HealthCheck),
              **({"derandomize": False} if seed is not None else {}))
    @given(strategy)
    def run(case):
        where = folder / f"case{len(results):05d}"
        result = run_case(case, where)
        results.append((case, result, where))
        if on_result:
            on_result(case, result)

    (with_seed(seed)(run) if seed is not None else run)()
    return results


def failure_report(results) -> str:
    """One line per case that broke the promise: outcome, mutation, command, detail, folder."""
    return "\n".join(f"{r.outcome}: [{c.kind}] {c.what} :: {c.command()[:200]} -> {r.detail} "
                     f"({where})" for c, r, where in results if r.outcome not in PASSED)
