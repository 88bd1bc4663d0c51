"""What each ``marchlab`` command does, once `marchlab.cli` has parsed its arguments.

One function per command, ``cmd_NAME(args) -> exit code``: each loads the scene, calls the
toolkit (`marchlab.render`, `marchlab.compare`, `marchlab.simulation`, the ground truth, the
accuracy report) and writes or prints the result. A user error raises `MarchlabError`, which
`marchlab.cli.main` turns into one line on stderr; backends are imported only when a command
needs one.

A command that writes files checks them all before it starts (`marchlab.outputs`), estimates
its work against the budget (`marchlab.budget`, lifted by ``--allow-large``), shows a
progress bar on a terminal while it works (`progress_bar`), and writes its files together
at the end, so an error or Ctrl-C leaves nothing half-written.
"""

from __future__ import annotations

import io
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

from scene_model.errors import MarchlabError, SceneError
from scene_model.files import write_atomically, write_together
from scene_model.frame import png_bytes
from scene_model.scene import rendered_scene, scene_at
from scene_model.scenefile import bundled_scene_names, scene_to_toml
from scene_model.scenefile import load_scene as read_scene
from scene_model.timeline import check_keyframes

from .budget import (COMMAND_LINE, MAX_BENCH_RAY_STEPS, check, check_animation, check_image,
                     check_render, check_truth)
from .outputs import check_outputs, make_folders
from .render import BACKENDS, backend_problem, check_backend, reference_backend, render

OUTPUT_SUFFIXES = (".png", ".npz")


def refuse_empty_paths(args, *options: str) -> None:
    """Refuse an option given as an empty path (``-o ''``): a slip, never a wish for the
    default name or for the current folder."""
    for option in options:
        value = getattr(args, option.lstrip("-"), None)
        if value is not None and not value.strip():
            raise MarchlabError(f"{option}: an empty path (name a file or a folder)")


def given(scene: str, *options: tuple[str, str | None]) -> str:
    """``scene: --flag value ...`` for the options given a value, the start of a refusal."""
    typed = " ".join(f"{flag} {value}" for flag, value in options if value)
    return f"{scene}: {typed}" if typed else scene


@contextmanager
def about_options(options: str):
    """Begin a refusal raised inside with the ``options`` it is about (``--size 10000x10000``),
    so that its one line names what the user typed and can change."""
    try:
        yield
    except MarchlabError as err:
        raise type(err)(f"{options}: {err}") from None


def cmd_render(args) -> int:
    """``marchlab render``: one frame of a scene to a PNG (one buffer) or an .npz (all)."""
    refuse_empty_paths(args, "--output")
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}.png")
    if output.suffix.lower() not in OUTPUT_SUFFIXES:
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} "
                            "(use .png or .npz)")
    drawn = [flag for flag, on in (("--mark-lights", args.mark_lights),
                                    ("--outline", args.outline)) if on]
    if drawn and output.suffix.lower() != ".png":
        raise MarchlabError(f"{output}: {drawn[0]} draws on a picture: write a .png")
    check_outputs(files=[output])
    scene = load_scene(args.scene, args.set)
    # A backend that cannot draw this scene: the refusal names the file and what was typed.
    with about_options(given(args.scene, ("--backend", args.backend),
                             ("--precision", args.precision))):
        args.backend = args.backend or reference_backend(scene)
        check_backend(scene, args.backend, args.precision)
    selected = outlined_ids(scene, args.outline)
    width, height = args.size
    with about_options(f"--size {width}x{height}"):
        check_render(scene, width, height, allow_large=args.allow_large, lift=COMMAND_LINE)
    start = time.perf_counter()
    with progress_bar(width * height) as progress:
        frame = render(scene, width, height, backend=args.backend, precision=args.precision,
                       progress=progress, allow_large=args.allow_large)
    seconds = time.perf_counter() - start
    make_folders(output)
    try:
        if drawn:
            write_atomically(output, png_bytes(drawn_image(frame, scene, args.aov, selected,
                                                           args.mark_lights)))
        else:
            frame.save(output, aov=args.aov)
    except OSError as err:
        raise MarchlabError(f"{output}: cannot write: {err.strerror}") from None
    print(f"wrote {output} ({width}x{height}, {args.backend} {frame.precision}, "
          f"{seconds:.2f} s)")
    return 0


def outlined_ids(scene, paths) -> tuple[int, ...]:
    """The object ids of the primitives under each node path of ``--outline`` (a path that
    leads nowhere is a one-line error naming it)."""
    from scene_model.editing import primitive_ids
    ids = []
    for path in paths:
        try:
            ids += primitive_ids(scene, path)
        except SceneError as err:
            raise MarchlabError(f"--outline {'.'.join(map(str, path))}: {err}") from None
    return tuple(ids)


def drawn_image(frame, scene, aov: str, selected=(), mark: bool = False):
    """The picture of ``frame``'s ``aov`` as the live view draws it: the ``selected`` ids
    outlined (`gpu_shader.display.overlay_image`), the lights marked if ``mark``."""
    from gpu_shader.display import overlay_image
    from .light_marks import mark_lights
    image = overlay_image(frame, aov, selected)
    return mark_lights(image, scene, frame) if mark else image


@contextmanager
def progress_bar(total: int, unit: str = "px"):
    """A progress callback drawing a bar on stderr, shown only on a terminal after 1 s."""
    if not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm
    with tqdm(total=total, unit=unit, unit_scale=unit == "px", delay=1.0, leave=False,
              file=sys.stderr) as bar:
        def report(done, total):
            if total != bar.total:          # a job that learns its size as it goes
                bar.total = total
            bar.update(done - bar.n)
        yield report


def cmd_scenes(args) -> int:
    """``marchlab scenes``: the bundled scenes, one line each with its description."""
    names = bundled_scene_names()
    width = max(map(len, names))
    for name in names:
        print(f"{name:<{width}}  {load_scene(name).description}")
    return 0


def cmd_show(args) -> int:
    """``marchlab show``: the scene, overrides applied, as the TOML of a scene file."""
    print(scene_to_toml(load_scene(args.scene, args.set)), end="")
    return 0


def cmd_shader(args) -> int:
    """``marchlab shader``: the program generated for a scene, as a backend compiles it."""
    scene = load_scene(args.scene, args.set)
    from gpu_shader.generate import generate     # no OpenGL needed to generate
    program = generate(rendered_scene(scene), 640, 480, dialect=args.dialect,
                       precision=args.precision, path_labels=args.path_labels)
    sources = [program.source]
    if program.prepass_source:      # GLSL draws the cone pre-pass with a program of its own
        sources.append(program.prepass_source)
    for n, source in enumerate(sources):
        if n:
            print("// ==== the cone pre-pass's fragment shader, drawn before the program "
                  "above (its own line numbers) ====")
        if args.numbered:
            lines = source.splitlines()
            width = len(str(len(lines)))
            source = "".join(f"{i:>{width}}  {line}\n" for i, line in enumerate(lines, 1))
        print(source, end="")
    return 0


def cmd_compare(args) -> int:
    """``marchlab compare``: two backends' frames against the gates; exit 1 if one fails."""
    from .compare import (GATE_LEGEND, compare_frames, failures, gate_notes, gates_against,
                          reference_around, write_difference_images)
    refuse_empty_paths(args, "--save")
    check_outputs(folders=[args.save])
    scene = load_scene(args.scene, args.set)
    typed = {"a": (args.a, args.a_precision), "b": (args.b, args.b_precision)}
    args.a = args.a or reference_backend(scene)
    args.b = args.b or ("raster" if scene.meshes else "gpu")
    width, height = args.size
    with about_options(f"--size {width}x{height}"):
        check_render(scene, width, height, frames=2, allow_large=args.allow_large,
                     lift=COMMAND_LINE)
    b_precision = args.b_precision or BACKENDS[args.b].precisions[0]
    a_precision = args.a_precision or (
        b_precision if b_precision in BACKENDS[args.a].precisions else None)
    for side, backend, precision in (("a", args.a, a_precision), ("b", args.b, b_precision)):
        with about_options(given(args.scene, (f"--{side}", typed[side][0]),
                                 (f"--{side}-precision", typed[side][1]))):
            check_backend(scene, backend, precision)
    # Path labels tell the gates where either image may jump (marchlab.compare).
    frames = []
    with progress_bar(2 * width * height) as progress:
        for backend, precision in ((args.a, a_precision), (args.b, b_precision)):
            # One bar for both frames: the second one's pixels count on from the first's.
            offset = len(frames) * width * height
            frames.append(render(
                scene, width, height, backend=backend, precision=precision, path_labels=True,
                progress=progress and (lambda done, total: progress(offset + done, 2 * total)),
                allow_large=args.allow_large))
    a, b = frames
    # A hardware rasteriser samples off the pixel centres: the reference is drawn around them.
    subpixel = max(a.subpixel, b.subpixel)
    around = reference_around(scene, width, height, args.a, subpixel, a_precision)
    if around:
        print(f"the reference drawn {len(around)} more times around each pixel's centre "
              f"(sub-pixel precision {subpixel:.3g} px)")
    c = compare_frames(a, b, epsilon=scene.render.epsilon, around=around)
    gates = gates_against(a.precision, meshes=bool(scene.meshes))
    failed = failures(c, gates)
    print(f"{args.scene}: {args.b} {b.precision} against {args.a} {a.precision}, "
          f"{width}x{height}")
    rows = c.rows()
    notes = gate_notes(gates, c.pixels)
    name_width = max(len(name) for name, _ in rows)
    value_width = max(len(value) for _, value in rows)
    for name, value in rows:
        print(f"  {name:<{name_width}}  {value:<{value_width}}  {notes[name]}".rstrip())
    print(GATE_LEGEND)
    if args.save:
        for path in write_difference_images(a, b, gates, Path(args.save), around):
            print(f"wrote {path}")
    for line in failed:
        print(f"FAIL {line}")
    print("PASS" if not failed else f"FAIL ({len(failed)} gates)")
    return 1 if failed else 0


def load_scene(name_or_path, overrides=()):
    """`scene_model.scenefile.load_scene`, then its keyframes checked against the fields they
    animate (`scene_model.timeline.check_keyframes`), errors naming the file."""
    scene = read_scene(name_or_path, overrides)
    try:
        return check_keyframes(scene)
    except SceneError as err:
        raise err.in_file(str(name_or_path)) from None


def cmd_simulate(args) -> int:
    """``marchlab simulate``: step the scene's bodies, render each frame, write a GIF or MP4
    (`animate_scene`; the scene must have bodies)."""
    return animate_scene(args, need_bodies=True)


def cmd_animate(args) -> int:
    """``marchlab animate``: render the scene over time, its keyframes, orbit, kinematic
    objects and bodies (if any), into a GIF or MP4 (`animate_scene`)."""
    return animate_scene(args, need_bodies=False)


def animate_scene(args, need_bodies: bool) -> int:
    """Step the scene's bodies (none is fine unless ``need_bodies``), render each frame at its
    time (`scene_model.timeline.scene_at_time` and the bodies' poses), write a GIF or MP4.

    Every output and the budget (frames, physics steps, the frames' memory and rendering)
    are checked before the first step; the animation, the CSV and the saved state
    (``--save-state``) are written together. ``--load-state`` starts from a saved state, so
    the frames carry on in simulated time from where that run ended.
    """
    import physics
    from physics import PhysicsError
    from .animation import FORMATS, gif_bytes, mp4_bytes, mp4_problem
    from .simulation import build_world, frame_plan, physics_settings, simulate_scene
    refuse_empty_paths(args, "--output", "--csv", "--save-state", "--load-state")
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}.gif")
    kind = output.suffix.lower()
    if kind not in FORMATS:
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} "
                            "(use .gif or .mp4)")
    if kind == ".mp4" and mp4_problem():
        raise MarchlabError(f"{output}: {mp4_problem()}")
    table = Path(args.csv) if args.csv else None
    state = Path(args.save_state) if args.save_state else None
    check_outputs(files=[output, table, state])
    scene = load_scene(args.scene, args.set)
    if args.camera_path:
        from scene_model.camera_paths import camera_path
        try:
            scene = camera_path(scene, args.camera_path, args.seconds)
        except SceneError as err:
            raise MarchlabError(f"{args.scene}: --camera-path {args.camera_path}: "
                                f"{err}") from None
    if need_bodies and not scene.bodies:
        raise MarchlabError(f"{args.scene}: has no [[bodies]] to simulate (marchlab animate "
                            "renders a scene without them)")
    backend = args.backend or ("gpu" if backend_problem("gpu") is None else "numpy")
    if args.backend and backend_problem(backend):
        raise MarchlabError(f"the {backend} backend cannot run here: {backend_problem(backend)}")

    # The step is the scene's fixed dt; the frame rate only says how often to look.
    dt = physics_settings(scene).dt
    width, height = args.size
    with about_options(f"--seconds {args.seconds:g} --fps {args.fps:g} --size {width}x{height}"):
        plan = frame_plan(dt, args.fps, args.seconds)
        check_animation(scene, plan.frames, plan.steps, width, height,
                        allow_large=args.allow_large, lift=COMMAND_LINE)
    if not plan.exact:
        print(f"marchlab: note: 1/fps = {1 / args.fps:.6g} s is not a multiple of dt = "
              f"{dt:.6g} s; a frame every {plan.record_every} steps ({plan.frame_seconds:.6g} s "
              "of simulated time)", file=sys.stderr)
    start = time.perf_counter()
    try:
        world = build_world(scene)
        if args.load_state:
            try:
                physics.load_state(world, args.load_state)
            except PhysicsError as err:
                raise MarchlabError(f"--load-state {err}") from None
        with progress_bar(plan.steps, unit="step") as progress:
            trajectory = simulate_scene(scene, plan, allow_large=args.allow_large,
                                        progress=progress, world=world)
    except SceneError as err:
        raise err.in_file(args.scene) from None
    except PhysicsError as err:
        raise MarchlabError(f"{args.scene}: physics: {err}") from None

    images = render_frames(scene, trajectory.positions, width, height, backend,
                           allow_large=args.allow_large, times=trajectory.times,
                           orientations=trajectory.orientations, mark=args.mark_lights)
    payloads = {output: (gif_bytes(images, plan.frame_seconds) if kind == ".gif"
                         else mp4_bytes(images, 1 / plan.frame_seconds))}
    if table is not None:
        payloads[table] = trajectory_csv(trajectory)
    if state is not None:
        from physics.state import state_bytes
        payloads[state] = state_bytes(world)
    write_outputs(payloads)
    seconds = time.perf_counter() - start
    print(f"wrote {output} ({plan.frames} frames of {width}x{height} from t = "
          f"{trajectory.times[0]:.6g} to {trajectory.times[-1]:.6g} s, {plan.steps} steps of "
          f"dt = {dt:.6g} s, {backend}, {seconds:.2f} s)")
    if table is not None:
        print(f"wrote {table} ({len(trajectory.times)} records of "
              f"{trajectory.positions.shape[1]} bodies)")
    if state is not None:
        print(f"wrote {state} (the state at t = {world.time:.6g} s, step {world.steps}; "
              f"--load-state {state} carries on from there)")
    return 0


def cmd_truth(args) -> int:
    """``marchlab truth``: depth, normal and hit without sphere tracing, to an .npz file."""
    import numpy as np
    refuse_empty_paths(args, "--output")
    output = Path(args.output) if args.output else Path(f"{Path(args.scene).stem}-truth.npz")
    if output.suffix.lower() != ".npz":
        raise MarchlabError(f"{output}: unsupported output format {output.suffix!r} (use .npz)")
    check_outputs(files=[output])
    scene = load_scene(args.scene, args.set)
    width, height = args.size
    with about_options(f"--size {width}x{height}"):
        check_image(width, height, lift="ask for a smaller --size")
    if args.method == "embree":
        with about_options(f"--resolution {args.resolution}"):
            check_truth(scene, args.resolution, args.allow_large, COMMAND_LINE)
    from reference_cpu.truth import ground_truth
    start = time.perf_counter()
    try:
        with progress_bar(1, unit="step") as progress:
            truth = ground_truth(scene, width, height, method=args.method,
                                 resolution=args.resolution, progress=progress)
    except SceneError as err:
        raise err.in_file(args.scene) from None
    seconds = time.perf_counter() - start
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **truth.arrays())
    write_outputs({output: buffer.getvalue()})
    print(f"wrote {output} ({width}x{height}, {args.method}: {int(truth.hit.sum())} of "
          f"{width * height} pixels hit, error bound {truth.error_bound:.3g}, measured "
          f"|sdf| max {truth.measured_error:.3g}, p99 {truth.measured_error_p99:.3g}; "
          f"{seconds:.2f} s)")
    return 0


def cmd_bench_accuracy(args) -> int:
    """``marchlab bench accuracy``: the speed-against-error report and its plots.

    By default into out/ (never over the documentation's copy, which `make speed-vs-error`
    regenerates on purpose); the report and its plots are checked before the run, which
    takes minutes, and written together after it.
    """
    from .accuracy_report import plan_run, run
    refuse_empty_paths(args, "--output", "--images")
    output = Path(args.output)
    if output.suffix.lower() != ".md":
        raise MarchlabError(f"{output}: the report is Markdown (use a .md file)")
    images = Path(args.images) if args.images else output.parent / "images"
    check_outputs(files=[output], folders=[images])
    plan = plan_run(args.size, args.repeat, args.quick)
    with about_options(f"--size {args.size[0]}x{args.size[1]} --repeat {args.repeat}"):
        check(plan.ray_steps, MAX_BENCH_RAY_STEPS,
              f"the benchmark ({plan.configurations:,} configurations x {args.repeat + 1} "
              f"renders)", "ray steps at worst", args.allow_large, COMMAND_LINE)
    command = " ".join(["marchlab", "bench", "accuracy"] + sys.argv[3:]) if len(
        sys.argv) > 2 else "marchlab bench accuracy"
    try:
        with progress_bar(plan.configurations, unit="config") as progress:
            written = run(output, images, args.size, args.repeat, command, args.quick,
                          echo=lambda line: print(line, file=sys.stderr, flush=True),
                          progress=progress, allow_large=True, plan=plan)   # checked above
    except OSError as err:
        raise MarchlabError(f"{err.filename or output}: cannot write: {err.strerror}") from None
    for path in written:
        print(f"wrote {path}")
    return 0


def render_frames(scene, positions, width: int, height: int, backend: str,
                  allow_large: bool = False, times=None, orientations=None,
                  mark: bool = False) -> list:
    """One 8-bit RGB image (H, W, 3) per row of ``positions`` (T, N, 3), with a progress bar;
    ``times`` (T,) s place the kinematic objects (`scene_model.scene.scene_at`) and
    ``orientations`` (T, N, 4) turn the boxes and capsules; with ``mark``, the lights the
    camera sees are marked (`marchlab.light_marks`).

    Only numbers change from frame to frame, so the GPU backend compiles its program for the
    first frame and reuses it for the others.
    """
    from scene_model.timeline import scene_at_time
    from .light_marks import mark_lights
    from .simulation import drawn_poses
    images = []
    times = [None] * len(positions) if times is None else times
    with progress_bar(len(positions), unit="frame") as progress:
        for index, centres in enumerate(positions):
            rotations = None
            if orientations is not None:
                centres, rotations = drawn_poses(scene, centres, orientations[index])
            still = scene_at(scene, centres, times[index], rotations)
            if times[index] is not None:
                still = scene_at_time(still, times[index])
            frame = render(still, width, height,
                           backend=backend, allow_large=allow_large)
            image = frame.image("color")
            images.append(mark_lights(image, still, frame) if mark else image)
            if progress:
                progress(index + 1, len(positions))
    return images


def write_outputs(payloads: dict) -> None:
    """Write a command's files together (`scene_model.files.write_together`), making their
    folders; a failure is a `MarchlabError` naming the user's path."""
    make_folders(*payloads)
    try:
        write_together(payloads)
    except OSError as err:
        raise MarchlabError(f"{err.filename}: cannot write: {err.strerror}") from None


def trajectory_csv(trajectory) -> bytes:
    """The bytes `physics.Trajectory.to_csv` writes (so the file can be written atomically)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "trajectory.csv"
        trajectory.to_csv(path)
        return path.read_bytes()


def cmd_view(args) -> int:
    """``marchlab view``: a live window onto a scene (`marchlab.view`). With ``--frames N``
    it draws N frames and exits, writing ``--screenshot`` (the 3D view alone) at the end."""
    refuse_empty_paths(args, "--screenshot", "--script")
    if args.screenshot is not None and Path(args.screenshot).suffix.lower() != ".png":
        raise MarchlabError(f"--screenshot {args.screenshot}: a screenshot is a .png")
    if args.screenshot is not None and args.frames is None:
        raise MarchlabError("--screenshot is written when the window closes by itself: "
                            "give --frames N too")
    width, height = args.size
    with about_options(f"--size {width}x{height}"):
        # The view draws a frame of its window's size, as large as a render's.
        check_image(width, height, lift="ask for a smaller --size")
    check_outputs(files=[args.screenshot])
    from .view import Viewer
    from .view_script import read_script
    actions = read_script(args.script) if args.script else []
    viewer = Viewer(args.scene, args.size)
    from .view_window import Window, run, window_problem
    problem = window_problem()
    if problem:
        raise MarchlabError(problem)
    window = Window(viewer, frames=args.frames, screenshot=args.screenshot, actions=actions)
    run(window, args.size, title=f"marchlab view {args.scene}")
    if args.screenshot is not None:
        # A window is as large as the display lets it be: say so when that was not --size.
        shown = tuple(viewer.size)
        smaller = (f" ({shown[0]}x{shown[1]}: the window was that large, not --size "
                   f"{width}x{height})" if shown != (width, height) else "")
        print(f"wrote {args.screenshot}{smaller}")
    return 0
