"""Frames per second of the ``marchlab view`` window over a scripted orbit, and how long a
structural edit holds a frame.

    xvfb-run -a -s "-screen 0 1920x1080x24" python benchmarks/bench_view.py \
        [--scenes classroom,primitives] [--size 640x480] [--frames 120] [--edits 4]

Orbit: the window (panels and all) orbits the scene by 4 pixels of left drag per frame for
``--frames`` frames, then stops. Per scene it runs twice, side by side in one process: with
the view's reduced resolution while moving (the default, adapting its scale to 30 fps) and at
full resolution throughout. It reports the frames per second while orbiting (median wall time
per frame of the whole loop: input, physics, render, display, panels, buffer swap), the
moving scale the view settled on, and how long after the last motion the view shows full
resolution again.

Edits: while orbiting, the window adds an object ``--edits`` times (each a new program), with
the background compiler and without it (compiling in the frame). It reports the longest frame
from each edit until the edited scene is on screen, and how long that took. Each run uses a
fresh, empty Mesa shader cache (``MESA_SHADER_CACHE_DIR`` in a temporary folder, set before
any context exists), so no edit finds its program compiled by an earlier run.

Markdown, for docs/performance.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

from marchlab.view import Viewer
from marchlab.view_window import Window, run


class Orbiting(Window):
    """A window that stays still for ``still`` frames (as a view does before a person
    drags: those frames tell the view its frame's fixed part), drags its view by ``step``
    pixels a frame for ``frames`` frames, then stops and waits for the full-resolution
    picture."""

    def __init__(self, viewer, frames: int, step: float = 4.0, still: int = 30):
        super().__init__(viewer)
        self.orbit_frames, self.step, self.still = frames, step, still
        self.times: list[float] = []
        self.stopped_at = None
        self.settled_after = None
        self.previous = None

    def background(self):
        if self.still > 0:
            self.still -= 1
            return super().background()
        now = time.perf_counter()
        if self.previous is not None and len(self.times) < self.orbit_frames:
            self.times.append(now - self.previous)
        self.previous = now
        if self.drawer is not None and len(self.times) < self.orbit_frames:
            self.viewer.drag("left", self.step, 0.0)
        elif self.drawer is not None and self.stopped_at is None:
            self.stopped_at = now
        super().background()
        if self.stopped_at is not None and self.drawer.drawn is not None \
                and self.drawer.drawn[1] == self.viewer.size and self.settled_after is None:
            self.settled_after = time.perf_counter() - self.stopped_at
            from imgui_bundle import hello_imgui
            hello_imgui.get_runner_params().app_shall_exit = True


def measure(scene: str, size, frames: int, refine: bool) -> tuple[float, float, float, str]:
    viewer = Viewer(scene, size)
    viewer.refine = refine
    window = Orbiting(viewer, frames)
    run(window, size, title="marchlab bench_view")
    fps = 1.0 / statistics.median(window.times[frames // 2:])     # once the scale settled
    return fps, viewer.moving_scale, window.settled_after, window.drawer.ctx.info["GL_RENDERER"]


KINDS = ("torus", "capsule", "box", "cone", "capped_cylinder", "round_box")


class Editing(Window):
    """A window that orbits and, every ``every`` frames, adds an object; it notes the
    longest frame and the time from each edit until the edited scene is drawn."""

    def __init__(self, viewer, edits: int, every: int = 40):
        super().__init__(viewer)
        self.edits, self.every = edits, every
        self.count = 0
        self.edited_at = None
        self.worst = 0.0
        self.results: list[tuple[float, float]] = []     # (longest frame, until drawn)

    def background(self):
        if self.drawer is None:
            return super().background()
        start = time.perf_counter()
        self.count += 1
        if self.count % self.every == 0 and self.edited_at is None:
            self.viewer.add_object(KINDS[len(self.results) % len(KINDS)])
            self.edited_at = start
            self.worst = 0.0
        self.viewer.drag("left", 3.0, 0.0)
        super().background()
        if self.edited_at is not None:
            self.worst = max(self.worst, time.perf_counter() - start)
            if not self.drawer.compiling:
                self.results.append((self.worst, time.perf_counter() - self.edited_at))
                self.edited_at = None
                if len(self.results) == self.edits:
                    from imgui_bundle import hello_imgui
                    hello_imgui.get_runner_params().app_shall_exit = True


def measure_edits(scene: str, size, edits: int, background: bool):
    import marchlab.view_window as view_window
    made = view_window.background_compiler
    if not background:
        view_window.background_compiler = lambda: None
    try:
        window = Editing(Viewer(scene, size), edits)
        run(window, size, title="marchlab bench_view")
    finally:
        view_window.background_compiler = made
    return window.results


def _edits_in_a_process(scene: str, size: str, edits: int, mode: str):
    """`measure_edits` in a child process with an empty shader cache of its own."""
    with tempfile.TemporaryDirectory(prefix="marchlab-bench-cache-") as cache:
        result = subprocess.run(
            [sys.executable, __file__, "--scenes", scene, "--size", size, "--edits",
             str(edits), "--edits-only", mode],
            env={**os.environ, "MESA_SHADER_CACHE_DIR": cache}, capture_output=True,
            text=True, check=True)
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="classroom,primitives")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--edits", type=int, default=4)
    parser.add_argument("--edits-only", choices=("background", "frame"),
                        help=argparse.SUPPRESS)          # one edit run, as a child process
    args = parser.parse_args()
    size = tuple(int(s) for s in args.size.split("x"))
    if args.edits_only:
        results = measure_edits(args.scenes, size, args.edits, args.edits_only == "background")
        print(json.dumps(results))
        return
    print("| scene | view | fps orbiting, reduced resolution while moving (scale it settled "
          "on) | fps orbiting, full resolution | full resolution again after stopping |")
    print("|---|---|---:|---:|---:|")
    renderer = ""
    for scene in args.scenes.split(","):
        reduced, scale, settle, renderer = measure(scene, size, args.frames, refine=True)
        full, _, _, _ = measure(scene, size, args.frames, refine=False)
        print(f"| {scene} | {size[0]}x{size[1]} | {reduced:.1f} ({scale:.2f}) | {full:.1f} | "
              f"{settle * 1e3:.0f} ms |")
    if args.edits:
        print("\n| scene | compile | longest frame after an edit, ms (each edit) | "
              "edit on screen after, s (each edit) |")
        print("|---|---|---|---|")
        for scene in args.scenes.split(","):
            for mode in ("background", "frame"):
                results = _edits_in_a_process(scene, args.size, args.edits, mode)
                print(f"| {scene} | {'background' if mode == 'background' else 'in the frame'} | "
                      + ", ".join(f"{w * 1e3:.0f}" for w, _ in results) + " | "
                      + ", ".join(f"{d:.2f}" for _, d in results) + " |")
    print(f"\n(OpenGL renderer: {renderer})")


if __name__ == "__main__":
    main()
