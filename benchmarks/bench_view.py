"""Frames per second of the ``marchlab view`` window over a scripted orbit.

    xvfb-run -a -s "-screen 0 1920x1080x24" python benchmarks/bench_view.py \
        [--scenes classroom,primitives] [--size 640x480] [--frames 120]

The window (panels and all) orbits the scene by 4 pixels of left drag per frame for
``--frames`` frames, then stops. Per scene it runs twice, side by side in one process: with
the view's reduced resolution while moving (the default) and at full resolution throughout.
It reports the frames per second while orbiting (wall time per frame, the whole loop: input,
physics, render, display, panels, buffer swap) and how long after the last motion the view
shows full resolution again. Markdown, for docs/performance.md.
"""

from __future__ import annotations

import argparse
import statistics
import time

from marchlab.view import Viewer
from marchlab.view_window import Window, run


class Orbiting(Window):
    """A window that drags its view by ``step`` pixels a frame, then stops and waits for
    the full-resolution picture."""

    def __init__(self, viewer, frames: int, step: float = 4.0):
        super().__init__(viewer)
        self.orbit_frames, self.step = frames, step
        self.times: list[float] = []
        self.stopped_at = None
        self.settled_after = None
        self.previous = None

    def background(self):
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


def measure(scene: str, size, frames: int, refine: bool) -> tuple[float, float, str]:
    viewer = Viewer(scene, size)
    viewer.refine = refine
    window = Orbiting(viewer, frames)
    run(window, size, title="marchlab bench_view")
    fps = 1.0 / statistics.median(window.times)
    return fps, window.settled_after, window.drawer.ctx.info["GL_RENDERER"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="classroom,primitives")
    parser.add_argument("--size", default="640x480")
    parser.add_argument("--frames", type=int, default=120)
    args = parser.parse_args()
    size = tuple(int(s) for s in args.size.split("x"))
    print("| scene | view | fps orbiting, reduced resolution while moving | fps orbiting, "
          "full resolution | full resolution again after stopping |")
    print("|---|---|---:|---:|---:|")
    renderer = ""
    for scene in args.scenes.split(","):
        reduced, settle, renderer = measure(scene, size, args.frames, refine=True)
        full, _, _ = measure(scene, size, args.frames, refine=False)
        print(f"| {scene} | {size[0]}x{size[1]} | {reduced:.1f} | {full:.1f} | "
              f"{settle * 1e3:.0f} ms |")
    print(f"\n(OpenGL renderer: {renderer})")


if __name__ == "__main__":
    main()
