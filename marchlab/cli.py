"""The ``marchlab`` command: render scenes, list and print them, print a scene's generated
shader, compare two backends pixel by pixel, simulate a scene's bodies into an animation, and
compute a scene's independent ground truth.

This module is the parser (`build_parser`: every command, option and default) and `main`;
what each command does is in `marchlab.commands`. A user error (a bad file, field, size or
option, a job over its budget) ends with one line on stderr and exit code 2, Ctrl-C with one
line and exit code 130; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings

from scene_model.camera import MAX_SIDE
from scene_model.camera_paths import PRESETS
from scene_model.errors import MarchlabError
from scene_model.frame import AOVS

from .commands import (cmd_animate, cmd_bench_accuracy, cmd_compare, cmd_render, cmd_scenes,
                       cmd_shader, cmd_show, cmd_simulate, cmd_truth, cmd_view)
from .doctor import add_parser as add_doctor_parser
from .render import BACKENDS, PRECISIONS

DASHED_VALUE_OPTIONS = ("--size", "--seconds", "--fps", "--resolution")
# reference_cpu.truth.METHODS, written out so that the CLI loads no backend until it runs one
# (tests/truth/test_truth_cli.py keeps the two equal).
TRUTH_METHODS = ("analytic", "embree")
MAX_RESOLUTION = 512    # a 517^3 float64 grid is already 1.1 GB


def add_animation_parser(sub, name: str, func, text: str) -> None:
    """``marchlab simulate`` and ``marchlab animate``: the same options, one path (a scene
    without bodies simply has none to step)."""
    p = sub.add_parser(name, help=text)
    p.add_argument("scene", help="bundled scene name (e.g. bounce) or a .toml path")
    p.add_argument("-o", "--output", help="output file, .gif or .mp4 (default: SCENE.gif)")
    p.add_argument("--seconds", type=positive_number, default=5.0,
                   help="length of the animation in seconds of scene time (default: 5)")
    p.add_argument("--fps", type=positive_number, default=30.0,
                   help="frames per second of the animation (default: 30); the physics "
                        "time step stays the scene's [physics] dt")
    p.add_argument("--size", type=parse_size, default=(320, 240), metavar="WxH",
                   help="frame size in pixels (default: 320x240)")
    p.add_argument("--backend", choices=list(BACKENDS), default=None,
                   help="renderer (default: gpu if it can run here, else numpy)")
    p.add_argument("--mark-lights", action="store_true",
                   help="mark each point and spot light the camera sees with a small dot")
    p.add_argument("--camera-path", choices=PRESETS, default=None,
                   help="move the camera over the animation: once round what it looks at "
                        "(turntable), half way in and back (dolly), up and back down "
                        "(crane), or past it from left to right (flyby)")
    p.add_argument("--csv", metavar="FILE",
                   help="also write the trajectory: one row per frame and body")
    p.add_argument("--save-state", metavar="FILE",
                   help="also write the world's full state at the last frame to FILE (.npz): "
                        "positions, velocities, spins, time, random generator, warm start")
    p.add_argument("--load-state", metavar="FILE",
                   help="start from a state saved with --save-state for the same scene "
                        "instead of the scene's bodies; the run carries on bit for bit, its "
                        "frames and CSV times starting at the saved time")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set physics.dt=0.001 "
                        "bodies[0].restitution=0.9")
    add_allow_large(p)
    p.set_defaults(func=func)

def node_path(text: str) -> tuple[int, ...]:
    """``"2"`` -> (2,), ``"2.0"`` -> (2, 0): a node of the scene's objects, for --outline."""
    try:
        path = tuple(int(part) for part in text.split("."))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an object path such as 2 or 2.0")
    if any(i < 0 for i in path):
        raise argparse.ArgumentTypeError(f"{text!r}: object indices start at 0")
    return path


def add_allow_large(parser) -> None:
    """The ``--allow-large`` flag of every command that estimates its work first."""
    parser.add_argument("--allow-large", action="store_true",
                        help="go ahead with a job beyond the budget (too many pixels, ray "
                             "steps, frames, physics steps or meshing cells: see "
                             "marchlab/budget.py), which is otherwise refused")


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (and exit code 2, as argparse does)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def parse_size(text: str) -> tuple[int, int]:
    """``"640x480"`` -> (640, 480)."""
    try:
        width, height = (int(part) for part in text.lower().split("x"))
    except ValueError:
        width = height = 0
    if not (1 <= width <= MAX_SIDE and 1 <= height <= MAX_SIDE):
        raise argparse.ArgumentTypeError(
            f"expected WIDTHxHEIGHT with positive integers up to {MAX_SIDE}, e.g. 640x480 "
            f"(got {text!r})")
    return width, height


def positive_number(text: str) -> float:
    """``"2.5"`` -> 2.5, refusing zero, negative and non-finite numbers."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number (got {text!r})")
    return value


def integer_in(low: int, high: int | None, expected: str):
    """An argparse type: an integer from ``low`` to ``high`` (None: no upper limit), else
    "expected ``expected``"."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = low - 1
        if not (low <= value and (high is None or value <= high)):
            raise argparse.ArgumentTypeError(f"expected {expected} (got {text!r})")
        return value
    return parse


# marching-cubes cells of `marchlab truth`; timed frames of `marchlab bench accuracy`
grid_resolution = integer_in(2, MAX_RESOLUTION, f"an integer from 2 to {MAX_RESOLUTION}")
positive_int = integer_in(1, None, "a positive integer")


def _attach_dashed_values(argv: list[str]) -> list[str]:
    """Write ``--size -5x5`` as ``--size=-5x5`` (and ``--fps -1`` as ``--fps=-1``).

    argparse takes a value starting with "-" for an option, and would answer "expected one
    argument" instead of saying what is wrong with the value.
    """
    out = []
    for arg in map(str, argv):
        if out and out[-1] in DASHED_VALUE_OPTIONS and arg.startswith("-"):
            out[-1] = f"{out[-1]}={arg}"
        else:
            out.append(arg)
    return out


def build_parser() -> Parser:
    parser = Parser(prog="marchlab", description="Sphere-tracing teaching toolkit.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)

    p = sub.add_parser("render", help="render a scene to a PNG or .npz file")
    p.add_argument("scene", help="bundled scene name (see `marchlab scenes`) or a .toml path")
    p.add_argument("-o", "--output", help="output file, .png or .npz (default: SCENE.png)")
    p.add_argument("--size", type=parse_size, default=(640, 480), metavar="WxH",
                   help="image size in pixels (default: 640x480)")
    p.add_argument("--backend", choices=list(BACKENDS), default=None,
                   help="renderer (default: numpy, the reference; numpy-raster for a scene of "
                        "triangle meshes)")
    p.add_argument("--precision", choices=PRECISIONS, default=None,
                   help="floating-point precision of the arithmetic (default: the backend's: "
                        "float64 for numpy, float32 for gpu)")
    p.add_argument("--aov", choices=AOVS, default="color",
                   help="buffer written to a PNG (an .npz holds them all)")
    p.add_argument("--outline", type=node_path, action="append", default=[], metavar="PATH",
                   help="outline an object as the viewer outlines its selection: its index "
                        "in [[objects]] (2), or a child's path (2.0); may be repeated")
    p.add_argument("--mark-lights", action="store_true",
                   help="mark each point and spot light the camera sees with a small dot")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set render.max_steps=64 camera.fov=40")
    add_allow_large(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("scenes", help="list the bundled scenes")
    p.set_defaults(func=cmd_scenes)

    p = sub.add_parser("show", help="print a scene as TOML (a start for your own)")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    p.set_defaults(func=cmd_show)

    p = sub.add_parser("shader", help="print the shader generated for a scene")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--dialect", default="glsl",
                   choices=["glsl", "glsl-compute", "opencl", "opencl-packets"],
                   help="glsl (the gpu backend's fragment shader), glsl-compute (the same as "
                        "the compute shader it runs on a hardware GPU), opencl (the same as an "
                        "OpenCL kernel, one ray per work-item) or opencl-packets (the kernel "
                        "the opencl backend runs: 16 rays per work-item as vectors); "
                        "default: glsl")
    p.add_argument("--precision", default="float32", choices=["float32", "float64"],
                   help="what `real` means (float64: opencl only); default: float32")
    p.add_argument("--numbered", action="store_true",
                   help="number the lines, as compiler messages do")
    p.add_argument("--path-labels", action="store_true",
                   help="the program the equivalence suite compiles: it also computes each "
                        "pixel's path label (docs/equivalence.md)")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    p.set_defaults(func=cmd_shader)

    p = sub.add_parser("compare", help="render a scene with two backends and compare them "
                                       "pixel by pixel (exit 1 if a gate fails)")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--a", default=None, choices=list(BACKENDS),
                   help="the reference backend (default: numpy, or numpy-raster for a scene "
                        "of triangle meshes)")
    p.add_argument("--b", default=None, choices=list(BACKENDS),
                   help="the backend checked against it (default: gpu, or raster for a scene "
                        "of triangle meshes)")
    p.add_argument("--a-precision", choices=PRECISIONS, default=None,
                   help="precision of a (default: float32 when b is float32, else a's own)")
    p.add_argument("--b-precision", choices=PRECISIONS, default=None)
    p.add_argument("--size", type=parse_size, default=(160, 120), metavar="WxH",
                   help="image size in pixels (default: 160x120)")
    p.add_argument("--save", metavar="DIR",
                   help="also write both images, an amplified difference and the error mask")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    add_allow_large(p)
    p.set_defaults(func=cmd_compare)

    for name, func, text in (
            ("simulate", cmd_simulate, "step a scene's [[bodies]] with the physics module and "
                                       "render them into an animated GIF (or .mp4)"),
            ("animate", cmd_animate, "render a scene over time into an animated GIF (or "
                                     ".mp4): its [[keyframes]], [orbit], kinematic objects "
                                     "and bodies, any backend")):
        add_animation_parser(sub, name, func, text)

    p = sub.add_parser("truth", help="compute a scene's ground truth without sphere tracing "
                                     "(depth, normal and hit images to an .npz file)")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--method", choices=TRUTH_METHODS, default="analytic",
                   help="analytic: exact float64 intersections (spheres, boxes, planes and "
                        "their unions); embree: any bounded scene, meshed and ray-cast in "
                        "float32 (default: analytic)")
    p.add_argument("-o", "--output", help="output .npz file (default: SCENE-truth.npz)")
    p.add_argument("--size", type=parse_size, default=(640, 480), metavar="WxH",
                   help="image size in pixels (default: 640x480)")
    p.add_argument("--resolution", type=grid_resolution, default=128, metavar="N",
                   help="embree: marching-cubes cells across each meshed shape (default: 128)")
    add_allow_large(p)
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set camera.fov=40")
    p.set_defaults(func=cmd_truth)

    p = sub.add_parser("view", help="open a live window onto a scene: fly around it, edit it, "
                                    "play its physics, check it against the reference")
    p.add_argument("scene", help="bundled scene name (see `marchlab scenes`) or a .toml path")
    p.add_argument("--size", type=parse_size, default=(960, 720), metavar="WxH",
                   help="window size in pixels (default: 960x720)")
    p.add_argument("--frames", type=integer_in(1, 100_000, "a whole number from 1 to 100000"),
                   help="draw this many frames (after the --script), then close")
    p.add_argument("--screenshot", metavar="PATH",
                   help="with --frames: write the 3D view alone (no panels) at the window's "
                        "size (--size, or less where the display is smaller) as PNG when the "
                        "window closes")
    p.add_argument("--script", metavar="FILE",
                   help="replay the input actions of a TOML script, one per frame "
                        "(docs/viewer.md)")
    p.set_defaults(func=cmd_view)

    p = sub.add_parser("bench", help="measure the backends (see also benchmarks/)")
    bench = p.add_subparsers(dest="bench", required=True, parser_class=Parser)
    q = bench.add_parser("accuracy", help="sweep epsilon, max_steps, relaxation, culling and "
                                          "normals on every backend: time against error "
                                          "(writes a Markdown report and PNG plots)")
    q.add_argument("-o", "--output", default="out/speed-vs-error.md",
                   help="the report (default: out/speed-vs-error.md; `make speed-vs-error` "
                        "regenerates the documentation's copy, docs/speed-vs-error.md)")
    q.add_argument("--images", default=None, metavar="DIR",
                   help="folder for the plots (default: images/ beside the report)")
    q.add_argument("--size", type=parse_size, default=(160, 120), metavar="WxH",
                   help="image size in pixels (default: 160x120)")
    q.add_argument("--repeat", type=positive_int, default=3, metavar="N",
                   help="timed frames per configuration (default: 3)")
    q.add_argument("--quick", action="store_true",
                   help="two scenes (one per kind of truth, coarse Embree grid), two settings: "
                        "check that the report can be made")
    add_allow_large(q)
    q.set_defaults(func=cmd_bench_accuracy)
    add_doctor_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; its exit code: 0, 1 (a comparison failed a gate), 2 (a user error,
    one line on stderr) or 130 (interrupted with Ctrl-C, one line, nothing half-written).

    Warnings raised while the command runs (NumPy's "overflow encountered in multiply", a
    library's) are not printed as they come, several lines each, but summed up in one line
    of marchlab's own when the command succeeds (`warning_lines`).
    """
    try:
        args = build_parser().parse_args(
            _attach_dashed_values(sys.argv[1:] if argv is None else argv))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            code = args.func(args) or 0
    except MarchlabError as err:
        print(f"marchlab: error: {err}", file=sys.stderr)
        return 2
    except MemoryError as err:      # past the budget with --allow-large, or a crowded machine
        detail = " ".join(str(err).split()) or "no detail"
        print(f"marchlab: error: out of memory ({detail}); ask for a smaller job",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("marchlab: interrupted", file=sys.stderr)
        return 130
    for line in warning_lines(caught):
        print(line, file=sys.stderr)
    return code


# Warnings meant for the people who write code, not for those who run it.
DEVELOPER_WARNINGS = (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                      ResourceWarning)


def warning_lines(caught: list[warnings.WarningMessage]) -> list[str]:
    """What a user is told of the warnings a command raised: one line for all of NumPy's
    floating-point warnings (values out of range somewhere in the arithmetic), one line
    for each other distinct warning, none for those meant for developers."""
    arithmetic, others = {}, {}         # dicts as ordered sets of the distinct messages
    for w in caught:
        text = " ".join(str(w.message).split())
        if issubclass(w.category, DEVELOPER_WARNINGS):
            continue
        if issubclass(w.category, RuntimeWarning) and " encountered in " in text:
            arithmetic[text] = None
        else:
            others[text] = None
    lines = []
    if arithmetic:
        lines.append("marchlab: warning: numbers went out of range in the arithmetic ("
                     + "; ".join(arithmetic) + "): some values may be inf or NaN; "
                     "check the magnitudes in the scene")
    lines += [f"marchlab: warning: {text}" for text in others]
    return lines


if __name__ == "__main__":
    sys.exit(main())
