"""The ``marchlab`` command: render scenes, list and print them, print a scene's generated
shader, compare two backends pixel by pixel, simulate a scene's bodies into an animation, and
compute a scene's independent ground truth.

A user error (a bad file, field, size or option) ends with one line on stderr and exit code 2;
anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import io
import math
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from scene_model.camera import MAX_SIDE
from scene_model.errors import MarchlabError, SceneError
from scene_model.files import write_atomically
from scene_model.frame import AOVS
from scene_model.scene import rendered_scene, scene_at
from scene_model.scenefile import bundled_scene_names, load_scene, scene_to_toml

from .render import BACKENDS, PRECISIONS, backend_problem, render

OUTPUT_SUFFIXES = (".png", ".npz")
DASHED_VALUE_OPTIONS = ("--size", "--seconds", "--fps", "--resolution")
# reference_cpu.truth.METHODS, written out so that the CLI loads no backend until it runs one
# (tests/truth/test_truth_cli.py keeps the two equal).
TRUTH_METHODS = ("analytic", "embree")
MAX_RESOLUTION = 512    # a 517^3 float64 grid is already 1.1 GB


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
    p.add_argument("--backend", choices=list(BACKENDS), default="numpy",
                   help="renderer (default: numpy, the reference)")
    p.add_argument("--precision", choices=PRECISIONS, default=None,
                   help="floating-point precision of the arithmetic (default: the backend's: "
                        "float64 for numpy, float32 for gpu)")
    p.add_argument("--aov", choices=AOVS, default="color",
                   help="buffer written to a PNG (an .npz holds them all)")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set render.max_steps=64 camera.fov=40")
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("scenes", help="list the bundled scenes")
    p.set_defaults(func=cmd_scenes)

    p = sub.add_parser("show", help="print a scene as TOML (a start for your own)")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    p.set_defaults(func=cmd_show)

    p = sub.add_parser("shader", help="print the shader generated for a scene")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--dialect", default="glsl", choices=["glsl", "opencl", "opencl-packets"],
                   help="glsl (the gpu backend's fragment shader), opencl (the same as an "
                        "OpenCL kernel, one ray per work-item) or opencl-packets (the kernel "
                        "the opencl backend runs: 16 rays per work-item as vectors); "
                        "default: glsl")
    p.add_argument("--precision", default="float32", choices=["float32", "float64"],
                   help="what `real` means (float64: opencl only); default: float32")
    p.add_argument("--numbered", action="store_true",
                   help="number the lines, as compiler messages do")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    p.set_defaults(func=cmd_shader)

    p = sub.add_parser("compare", help="render a scene with two backends and compare them "
                                       "pixel by pixel (exit 1 if a gate fails)")
    p.add_argument("scene", help="bundled scene name or a .toml path")
    p.add_argument("--a", default="numpy", choices=list(BACKENDS),
                   help="the reference backend (default: numpy)")
    p.add_argument("--b", default="gpu", choices=list(BACKENDS),
                   help="the backend checked against it (default: gpu)")
    p.add_argument("--a-precision", choices=PRECISIONS, default=None,
                   help="precision of a (default: float32 when b is float32, else a's own)")
    p.add_argument("--b-precision", choices=PRECISIONS, default=None)
    p.add_argument("--size", type=parse_size, default=(160, 120), metavar="WxH",
                   help="image size in pixels (default: 160x120)")
    p.add_argument("--save", metavar="DIR",
                   help="also write both images, an amplified difference and the error mask")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE")
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("simulate", help="step a scene's [[bodies]] with the physics module and "
                                        "render them into an animated GIF (or .mp4)")
    p.add_argument("scene", help="bundled scene name (e.g. bounce) or a .toml path")
    p.add_argument("-o", "--output", help="output file, .gif or .mp4 (default: SCENE.gif)")
    p.add_argument("--seconds", type=positive_number, default=5.0,
                   help="simulated time in seconds (default: 5)")
    p.add_argument("--fps", type=positive_number, default=30.0,
                   help="frames per second of the animation (default: 30); the physics "
                        "time step stays the scene's [physics] dt")
    p.add_argument("--size", type=parse_size, default=(320, 240), metavar="WxH",
                   help="frame size in pixels (default: 320x240)")
    p.add_argument("--backend", choices=list(BACKENDS), default=None,
                   help="renderer (default: gpu if it can run here, else numpy)")
    p.add_argument("--csv", metavar="FILE",
                   help="also write the trajectory: one row per frame and body")
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set physics.dt=0.001 "
                        "bodies[0].restitution=0.9")
    p.set_defaults(func=cmd_simulate)

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
    p.add_argument("--set", action="extend", nargs="+", default=[], metavar="FIELD=VALUE",
                   help="override scene fields, e.g. --set camera.fov=40")
    p.set_defaults(func=cmd_truth)

    p = sub.add_parser("bench", help="measure the backends (see also benchmarks/)")
    bench = p.add_subparsers(dest="bench", required=True, parser_class=Parser)
    q = bench.add_parser("accuracy", help="sweep epsilon, max_steps, relaxation, culling and "
                                          "normals on every backend: time against error "
                                          "(writes a Markdown report and PNG plots)")
    q.add_argument("-o", "--output", default="docs/speed-vs-error.md",
                   help="the report (default: docs/speed-vs-error.md)")
    q.add_argument("--images", default=None, metavar="DIR",
                   help="folder for the plots (default: images/ beside the report)")
    q.add_argument("--size", type=parse_size, default=(160, 120), metavar="WxH",
                   help="image size in pixels (default: 160x120)")
    q.add_argument("--repeat", type=positive_int, default=3, metavar="N",
                   help="timed frames per configuration (default: 3)")
    q.add_argument("--quick", action="store_true",
                   help="two scenes (one per kind of truth, coarse Embree grid), two settings: "
                        "check that the report can be made")
    q.set_defaults(func=cmd_bench_accuracy)
    return parser



def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(_attach_dashed_values(sys.argv[1:] if argv is None else argv))
    try:
        return args.func(args) or 0
    except MarchlabError as err:
        print(f"marchlab: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("marchlab: interrupted", file=sys.stderr)
        return 130


def cmd_render(args) -> int:
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}.png")
    if output.suffix.lower() not in OUTPUT_SUFFIXES:
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} "
                            "(use .png or .npz)")
    scene = load_scene(args.scene, args.set)
    width, height = args.size
    start = time.perf_counter()
    with progress_bar(width * height) as progress:
        frame = render(scene, width, height, backend=args.backend, precision=args.precision,
                       progress=progress)
    seconds = time.perf_counter() - start
    try:
        output.parent.mkdir(parents=True, exist_ok=True)
        frame.save(output, aov=args.aov)
    except OSError as err:
        raise MarchlabError(f"{output}: cannot write: {err.strerror}") from None
    print(f"wrote {output} ({width}x{height}, {args.backend} {frame.precision}, "
          f"{seconds:.2f} s)")
    return 0


@contextmanager
def progress_bar(total: int, unit: str = "px"):
    """A progress callback drawing a bar on stderr, shown only on a terminal after 1 s."""
    if not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm
    with tqdm(total=total, unit=unit, unit_scale=unit == "px", delay=1.0, leave=False,
              file=sys.stderr) as bar:
        yield lambda done, _total: bar.update(done - bar.n)


def cmd_scenes(args) -> int:
    names = bundled_scene_names()
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {load_scene(name).description}")
    return 0


def cmd_show(args) -> int:
    print(scene_to_toml(load_scene(args.scene, args.set)), end="")
    return 0


def cmd_shader(args) -> int:
    scene = load_scene(args.scene, args.set)
    from gpu_shader.generate import generate     # no OpenGL needed to generate
    source = generate(rendered_scene(scene), 640, 480, dialect=args.dialect,
                      precision=args.precision).source
    if args.numbered:
        lines = source.splitlines()
        width = len(str(len(lines)))
        source = "".join(f"{i:>{width}}  {line}\n" for i, line in enumerate(lines, 1))
    print(source, end="")
    return 0


def cmd_compare(args) -> int:
    from .compare import compare_frames, failures, gates_against, write_difference_images
    scene = load_scene(args.scene, args.set)
    width, height = args.size
    b_precision = args.b_precision or BACKENDS[args.b].precisions[0]
    a_precision = args.a_precision or (
        b_precision if b_precision in BACKENDS[args.a].precisions else None)
    # Path labels tell the gates where either image may jump (marchlab.compare).
    a = render(scene, width, height, backend=args.a, precision=a_precision, path_labels=True)
    b = render(scene, width, height, backend=args.b, precision=b_precision, path_labels=True)
    c = compare_frames(a, b, epsilon=scene.render.epsilon)
    gates = gates_against(a.precision)
    failed = failures(c, gates)
    print(f"{args.scene}: {args.b} {b.precision} against {args.a} {a.precision}, "
          f"{width}x{height}")
    rows = c.rows()
    name_width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"  {name:<{name_width}}  {value}")
    if args.save:
        for path in write_difference_images(a, b, gates, Path(args.save)):
            print(f"wrote {path}")
    for line in failed:
        print(f"FAIL {line}")
    print("PASS" if not failed else f"FAIL ({len(failed)} gates)")
    return 1 if failed else 0


def cmd_simulate(args) -> int:
    from physics import PhysicsError
    from .animation import FORMATS, gif_bytes, mp4_problem, write_mp4
    from .simulation import frame_plan, physics_settings, simulate_scene
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}.gif")
    kind = output.suffix.lower()
    if kind not in FORMATS:
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} "
                            "(use .gif or .mp4)")
    if kind == ".mp4" and mp4_problem():
        raise MarchlabError(f"{output}: {mp4_problem()}")
    scene = load_scene(args.scene, args.set)
    if not scene.bodies:
        raise MarchlabError(f"{args.scene}: has no [[bodies]] to simulate")
    backend = args.backend or ("gpu" if backend_problem("gpu") is None else "numpy")
    if args.backend and backend_problem(backend):
        raise MarchlabError(f"the {backend} backend cannot run here: {backend_problem(backend)}")

    # The step is the scene's fixed dt; the frame rate only says how often to look.
    dt = physics_settings(scene).dt
    plan = frame_plan(dt, args.fps, args.seconds)
    if not plan.exact:
        print(f"marchlab: note: 1/fps = {1 / args.fps:.6g} s is not a multiple of dt = "
              f"{dt:.6g} s; a frame every {plan.record_every} steps ({plan.frame_seconds:.6g} s "
              "of simulated time)", file=sys.stderr)
    start = time.perf_counter()
    try:
        trajectory = simulate_scene(scene, plan)
    except SceneError as err:
        raise err.in_file(args.scene) from None
    except PhysicsError as err:
        raise MarchlabError(f"{args.scene}: physics: {err}") from None

    width, height = args.size
    images = render_frames(scene, trajectory.positions, width, height, backend)

    try:
        for path in (output, Path(args.csv) if args.csv else None):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
        if kind == ".gif":
            write_atomically(output, gif_bytes(images, plan.frame_seconds))
        else:
            write_mp4(output, images, 1 / plan.frame_seconds)
        if args.csv:
            write_atomically(args.csv, trajectory_csv(trajectory))
    except OSError as err:
        raise MarchlabError(f"{err.filename or output}: cannot write: {err.strerror}") from None
    seconds = time.perf_counter() - start
    print(f"wrote {output} ({plan.frames} frames of {width}x{height} from t = 0 to "
          f"{plan.steps * dt:.6g} s, {plan.steps} steps of dt = {dt:.6g} s, {backend}, "
          f"{seconds:.2f} s)")
    if args.csv:
        print(f"wrote {args.csv} ({len(trajectory.times)} records of "
              f"{trajectory.positions.shape[1]} bodies)")
    return 0


def cmd_truth(args) -> int:
    import numpy as np
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}-truth.npz")
    if output.suffix.lower() != ".npz":
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} (use .npz)")
    scene = load_scene(args.scene, args.set)
    from reference_cpu.truth import ground_truth
    width, height = args.size
    start = time.perf_counter()
    try:
        truth = ground_truth(scene, width, height, method=args.method,
                             resolution=args.resolution)
    except SceneError as err:
        raise err.in_file(args.scene) from None
    seconds = time.perf_counter() - start
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **truth.arrays())
    try:
        output.parent.mkdir(parents=True, exist_ok=True)
        write_atomically(output, buffer.getvalue())
    except OSError as err:
        raise MarchlabError(f"{output}: cannot write: {err.strerror}") from None
    print(f"wrote {output} ({width}x{height}, {args.method}: {int(truth.hit.sum())} of "
          f"{width * height} pixels hit, error bound {truth.error_bound:.3g}, measured "
          f"|sdf| max {truth.measured_error:.3g}, p99 {truth.measured_error_p99:.3g}; "
          f"{seconds:.2f} s)")
    return 0


def cmd_bench_accuracy(args) -> int:
    from .accuracy_report import run
    output = Path(args.output)
    if output.suffix.lower() != ".md":
        raise MarchlabError(f"{output}: the report is Markdown (use a .md file)")
    images = Path(args.images) if args.images else output.parent / "images"
    command = " ".join(["marchlab", "bench", "accuracy"] + sys.argv[3:]) if len(
        sys.argv) > 2 else "marchlab bench accuracy"
    try:
        written = run(output, images, args.size, args.repeat, command, args.quick,
                      echo=lambda line: print(line, file=sys.stderr, flush=True))
    except OSError as err:
        raise MarchlabError(f"{err.filename or output}: cannot write: {err.strerror}") from None
    for path in written:
        print(f"wrote {path}")
    return 0


def render_frames(scene, positions, width: int, height: int, backend: str) -> list:
    """One 8-bit RGB image (H, W, 3) per row of ``positions`` (T, N, 3), with a progress bar.

    Only the bodies' positions change from frame to frame, so the GPU backend compiles its
    program for the first frame and reuses it for the others.
    """
    images = []
    with progress_bar(len(positions), unit="frame") as progress:
        for index, centres in enumerate(positions):
            frame = render(scene_at(scene, centres), width, height, backend=backend)
            images.append(frame.image("color"))
            if progress:
                progress(index + 1, len(positions))
    return images


def trajectory_csv(trajectory) -> bytes:
    """The bytes `physics.Trajectory.to_csv` writes (so the file can be written atomically)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "trajectory.csv"
        trajectory.to_csv(path)
        return path.read_bytes()


if __name__ == "__main__":
    sys.exit(main())
