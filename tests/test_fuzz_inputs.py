"""No input, however hostile, gets a traceback, a hang, a NaN or a half-written file.

Every bundled scene has its fields mutated (tests/fuzz_strategies.py: extreme numbers, NaN
and inf as TOML spells them, huge integers, strings, wrong types, empty and long arrays,
missing, unknown and duplicated keys, deep nesting, wrong object types) and every option of
every subcommand is given values nobody should type. Each command runs in-process at a small
size (tests/fuzz_runner.py) and must either succeed, exit 0, with complete and finite outputs,
or be refused, exit 2, with one line naming the file and the field (or the option), within
its time limit, leaving no file behind. A failing test lists every case that broke this, with
its command line and the folder holding its scene file.

The examples are derandomised (tests/conftest.py), so every run tries the same ones; set
``MARCHLAB_FUZZ_EXAMPLES`` for more per test, or run ``benchmarks/fuzz_inputs.py`` for the
large run whose table is in docs/robustness.md.
"""

from __future__ import annotations

import copy
import os
import time
import tomllib

import pytest

import fuzz_runner
from fuzz_runner import Case, failure_report, run_case, run_examples
from fuzz_strategies import (BASE, ONLY_REFUSALS, REFUSAL_TIME_LIMIT, SCENE_MUTATIONS, Raw,
                             deep_union_headers, deep_union_inline, fields, option_cases,
                             option_targets, scene_cases, scene_tree, subcommands,
                             toml_document)
from marchlab import bundled_scene_names
from scene_model.shapes import MAX_DEPTH

EXAMPLES = int(os.environ.get("MARCHLAB_FUZZ_EXAMPLES", "0"))
SCENE_EXAMPLES = EXAMPLES or 8        # per kind of mutation, over the six scenes
OPTION_EXAMPLES = EXAMPLES or 2       # per option of a subcommand
TIME_LIMIT = 10.0                     # seconds per case: each is a frame of 8x6 pixels


def assert_every_case_kept_the_promise(results):
    broken = failure_report(results)
    assert not broken, f"{broken.count(chr(10)) + 1} of {len(results)} cases:\n{broken}"


@pytest.mark.parametrize("kind", list(SCENE_MUTATIONS))
def test_a_bundled_scene_with_a_mutated_field_renders_or_is_refused_in_one_line(kind,
                                                                                tmp_path):
    results = run_examples(scene_cases(kind, time_limit=TIME_LIMIT), tmp_path, SCENE_EXAMPLES)
    assert results
    assert_every_case_kept_the_promise(results)


@pytest.mark.parametrize("command, option", option_targets())
def test_a_spoilt_option_succeeds_or_is_refused_in_one_line_naming_it(command, option,
                                                                      tmp_path):
    results = run_examples(option_cases(command, option, time_limit=TIME_LIMIT), tmp_path,
                           OPTION_EXAMPLES)
    assert results
    assert_every_case_kept_the_promise(results)


# --- The inputs that first showed each gap, pinned -------------------------------------------

def in_file(scene: str, *assignments: tuple[tuple, str], tail: str = "") -> str:
    """The bundled ``scene`` as `marchlab show` prints it, with fields set to raw TOML."""
    tree = copy.deepcopy(scene_tree(scene))
    for path, raw in assignments:
        target = tree
        for step in path[:-1]:
            target = target[step]
        target[path[-1]] = Raw(raw)
    return toml_document(tree, tail)


RENDER = ("render", "scene.toml", "-o", "out.npz", "--size", "8x6")
SIMULATE = ("simulate", "bounce", "-o", "out.gif", "--size", "8x6", "--backend", "numpy")
FIRST_SEEN = {
    # id: (argv, scene.toml or None, must it be refused?)
    "max_steps beyond int64 by --set": (
        ("render", "classroom", "-o", "out.npz", "--size", "8x6",
         "--set", "render.max_steps=9223372036854775808"), None, False),
    "max_steps of 10**30 in a file": (
        RENDER, in_file("classroom", (("render", "max_steps"), "1" + "0" * 30)), False),
    "seconds and fps of 1e308": (SIMULATE + ("--seconds", "1e308", "--fps", "1e308"), None, False),
    "a union 200 deep, inline": (
        RENDER, in_file("classroom", (("objects",), f"[{deep_union_inline(200, 'red')}]")),
        False),
    "a union 500 deep, in headers": (
        RENDER, toml_document({k: v for k, v in scene_tree("csg").items() if k != "objects"},
                              deep_union_headers(500, "clay")), False),
    "compare --save into a file": (
        ("compare", "classroom", "--a", "numpy", "--b", "numpy", "--size", "16x12",
         "--save", "a_file"), None, False),
    "10000 x 10000 pixels": (("render", "classroom", "-o", "out.png", "--size", "10000x10000"),
                             None, False),
    "a billion steps of 1e-300 to 1e308": (
        ("render", "repetition", "-o", "out.npz", "--size", "8x6", "--set",
         "render.max_steps=1000000000", "render.epsilon=1e-300", "render.max_distance=1e308"),
        None, False),
    "a billion frames per second": (SIMULATE + ("--fps", "1e9", "--seconds", "0.01"), None, False),
    "a billion seconds": (SIMULATE + ("--seconds", "1e9"), None, False),
    "dt of 1e-300": (SIMULATE + ("--seconds", "0.05", "--set", "physics.dt=1e-300"), None, False),
    "dt of 1e308": (SIMULATE + ("--seconds", "0.05", "--set", "physics.dt=1e308"), None, False),
    "camera at 1e308": (RENDER, in_file("classroom", (("camera", "position"),
                                                      "[1e308, 1e308, 1e308]")), False),
    "camera looking at 1e308": (RENDER, in_file("classroom", (("camera", "look_at"),
                                                              "[1e308, 1e308, 1e308]")), False),
    "a light at 1e308": (RENDER, in_file("classroom", (("lights", 0, "position"),
                                                       "[1e308, 1e308, 1e308]")), False),
    "a light at 1e300 in float32": (
        RENDER + ("--precision", "float32"),
        in_file("classroom", (("lights", 0, "position"), "[1e300, 1e300, 1e300]")), False),
    "normal_step of 1e308": (RENDER, in_file("classroom", (("render", "normal_step"), "1e308")),
                             False),
    "surface_offset of 1e308": (RENDER, in_file("classroom", (("render", "surface_offset"),
                                                              "1e308")), False),
    "simulate --csv into a folder": (SIMULATE + ("--seconds", "0.05", "--csv", "a_folder"),
                                     None, False),
    "bench accuracy -o under a file": (
        ("bench", "accuracy", "--quick", "-o", "a_file/r.md", "--size", "160x120"), None, True),
    # found by the first large run of benchmarks/fuzz_inputs.py
    "a scene name of 300 characters": (("render", "x" * 300, "-o", "out.png", "--size", "8x6"),
                                       None, True),
    "compare --save of 300 characters": (
        ("compare", "classroom", "--a", "numpy", "--b", "numpy", "--size", "8x6",
         "--save", "x" * 300), None, True),
    "bench accuracy --repeat beyond int64": (
        ("bench", "accuracy", "--quick", "-o", "r.md", "--size", "160x120",
         "--repeat", str(2 ** 63)), None, True),
    "bench accuracy --images ''": (
        ("bench", "accuracy", "--quick", "-o", "r.md", "--size", "160x120", "--images", ""),
        None, True),
    "a union 64 deep beside other objects, drawn in one union with them": (
        RENDER + ("--backend", "gpu"),
        in_file("classroom", (("objects", 3), deep_union_inline(MAX_DEPTH - 1, "red"))), False),
    # accepted today, and meaningless: each must be refused in one line
    "epsilon of 1e308": (RENDER, in_file("classroom", (("render", "epsilon"), "1e308")), True),
    "max_distance of 1e-300": (RENDER, in_file("classroom", (("render", "max_distance"),
                                                             "1e-300")), True),
    "toon_bands of 10**30": (RENDER, in_file("repetition", (("render", "toon_bands"),
                                                            "1" + "0" * 30)), True),
    "gamma of 1e-300": (RENDER, in_file("classroom", (("render", "gamma"), "1e-300")), True),
    "a point light attenuated by 1/0": (
        RENDER, in_file("classroom", (("lights", 0, "constant"), "0.0"),
                        (("lights", 0, "linear"), "0.0"), (("lights", 0, "quadratic"), "0.0")),
        True),
    "a body of radius 1e308": (
        ("simulate", "scene.toml", *SIMULATE[2:], "--seconds", "0.05"),
        in_file("bounce", (("bodies", 0, "radius"), "1e308")), True),
    "a body of radius 1e-300": (
        ("simulate", "scene.toml", *SIMULATE[2:], "--seconds", "0.05"),
        in_file("bounce", (("bodies", 0, "radius"), "1e-300")), True),
    "a field of view written as a string": (
        RENDER, in_file("classroom", (("camera", "fov"), '"50"')), True),
    # found by a run of benchmarks/fuzz_inputs.py with --seed 2711 (the refusals named no file)
    "a scene file of triangle meshes on the gpu backend": (
        RENDER + ("--backend", "gpu"), in_file("meshes"), True),
    "a scene file of triangle meshes in float32": (
        RENDER + ("--precision", "float32"), in_file("meshes"), True),
    "a scene file of triangle meshes compared on two sphere tracers": (
        ("compare", "scene.toml", "--a", "numpy", "--b", "gpu", "--size", "16x12"),
        in_file("meshes"), True),
    "a scene file of SDF objects on the raster backend": (
        RENDER + ("--backend", "raster"), in_file("classroom"), True),
    # found by a run with --seed 5151: a view window of 100 million pixels ran (the display
    # gave a smaller one), where render refuses that size
    "a view window of 10000 x 10000 pixels": (
        ("view", "classroom", "--frames", "1", "--size", "10000x10000"), None, True),
}


@pytest.mark.parametrize("name", list(FIRST_SEEN))
def test_each_input_that_first_showed_a_gap_keeps_the_promise(name, tmp_path):
    argv, scene_text, must_refuse = FIRST_SEEN[name]
    names = ["--set", "--size", "--seconds", "--fps", "--save", "--csv", "--output", "--images",
             "--repeat", "x" * 300, "a_file",
             "a_folder", "physics.dt", "render", "objects", "camera", "lights", "bodies",
             "--backend", "--precision", "--a", "--b"]
    case = Case(name, argv, name, tuple(names), "scene.toml" if scene_text else "",
                scene_text, must_refuse,
                REFUSAL_TIME_LIMIT if " ".join(argv[:2]) in ONLY_REFUSALS else TIME_LIMIT)
    assert_every_case_kept_the_promise([(case, run_case(case, tmp_path / "case"), tmp_path)])


# --- The fuzzer's own checks: it reaches everything, and its referee can say no ------------

def test_every_subcommand_has_a_command_line_to_spoil():
    assert set(BASE) == set(subcommands())


@pytest.mark.parametrize("scene", bundled_scene_names())
def test_the_toml_emitter_writes_every_bundled_scene_back_unchanged(scene):
    tree = scene_tree(scene)
    assert len(fields(tree)) > 100
    assert tomllib.loads(toml_document(tree)) == tree


def referee(monkeypatch, tmp_path, behaviour, **case):
    """The outcome `run_case` gives a stand-in for ``marchlab.cli.main``."""
    monkeypatch.setattr(fuzz_runner, "main", behaviour)
    defaults = dict(kind="test", argv=("render", "x"), what="", names=("--size",),
                    time_limit=0.5)
    return run_case(Case(**{**defaults, **case}), tmp_path / "case").outcome


def test_the_referee_reports_a_hang_a_traceback_and_a_partial_file(monkeypatch, tmp_path):
    def spin(argv):
        while True:
            time.sleep(0.01)

    def crash(argv):
        raise OverflowError("Python int too large to convert to C long")

    def half_write(argv):
        open(".out.png.abc.tmp", "wb").close()
        print("marchlab: error: --size: too large", file=__import__("sys").stderr)
        return 2

    start = time.perf_counter()
    assert referee(monkeypatch, tmp_path, spin) == "hang"
    assert time.perf_counter() - start < 5
    assert referee(monkeypatch, tmp_path, crash) == "traceback"
    assert referee(monkeypatch, tmp_path, half_write) == "partial file"


def test_the_referee_wants_one_line_naming_the_option_and_finite_outputs(monkeypatch,
                                                                        tmp_path):
    import sys

    import numpy as np

    def refuse(text):
        def run(argv):
            print(text, file=sys.stderr, end="")
            return 2
        return run

    def write_nan(argv):
        np.savez("out.npz", color=np.full((2, 2, 3), np.nan))
        return 0

    assert referee(monkeypatch, tmp_path, refuse("marchlab: error: --size: bad\n")) == "refused"
    assert referee(monkeypatch, tmp_path, refuse("marchlab: error: bad\n")) == "bad error line"
    assert referee(monkeypatch, tmp_path,
                   refuse("warning\nmarchlab: error: --size: bad\n")) == "bad error line"
    assert referee(monkeypatch, tmp_path, write_nan) == "non-finite output"


def test_the_referee_counts_a_warning_line_on_success_unless_it_is_marchlabs_own_note(
        monkeypatch, tmp_path):
    import sys

    def succeed_saying(text):
        def run(argv):
            print(text, file=sys.stderr)
            return 0
        return run

    arithmetic = ("marchlab: warning: numbers went out of range in the arithmetic (overflow "
                  "encountered in multiply): some values may be inf or NaN")
    assert referee(monkeypatch, tmp_path, succeed_saying(arithmetic)) == "warning"
    assert referee(monkeypatch, tmp_path, succeed_saying("186 warnings generated.")) == "warning"
    assert referee(monkeypatch, tmp_path,
                   succeed_saying("marchlab: note: 1/fps is not a multiple of dt")) == "rendered"
