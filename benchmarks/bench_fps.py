"""Frames per second of the gpu backend as a live view draws them: no read-back.

    python benchmarks/bench_fps.py [--scenes classroom,primitives] [--size 1920x1080]
                                   [--frames 200] [--prepass none,cone]
                                   [--stages fragment,compute]

For each bundled scene (or those named), each shader stage the gpu backend can draw with
(`gpu_shader.render.STAGES`) and each pre-pass setting, side by side in one run:

- **fps**: frames drawn back to back for ``--frames`` frames, then one ``finish``: the wall
  time a view drawing as fast as it can would see. A frame is the cone pre-pass (when on),
  the scene's draw into the three planes, and the display pass
  (`gpu_shader.display.Display.draw`) into an RGBA8 picture of the same size, which is what
  `marchlab view` shows (without ImGui's panels and the buffer swap); the CPU's part,
  writing the parameter block, overlaps the GPU's as it does in a window;
- **read-back ms**: the median wall time of a whole render at the same size (draw and
  read-back of every plane into a `Frame`, as `marchlab.render` does), for scale.

The device is printed: on llvmpipe this measures the CPU; on an NVIDIA GPU it gives the
real-GPU figures of docs/performance.md (issue: classroom at 1920x1080, 500 fps or more).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time

from marchlab.cli import parse_size
from scene_model.scene import rendered_scene
from scene_model.scenefile import bundled_scene_names, load_scene
from scene_model.sampling import pixel_max_steps


def with_prepass(scene, prepass: str):
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, prepass=prepass))


class Drawer:
    """Draws a scene's planes and its picture on the process's GL context, as the view does,
    with the shader ``stage`` given."""

    def __init__(self, stage: str):
        from gpu_shader.context import gl_context
        from gpu_shader.display import Display
        from gpu_shader.render import Renderer
        self.ctx = gl_context()
        self.renderer = Renderer(self.ctx, stage)
        self.display = Display(self.ctx)

    def frame(self, program, scene, width, height, picture):
        target = self.renderer.draw_planes(program, width, height)
        with self.ctx:
            picture.use()
        self.display.draw(target, "color", gamma=scene.render.gamma,
                          max_steps=pixel_max_steps(scene.render.max_steps,
                                                    scene.render.samples),
                          viewport=(0, 0, width, height))

    def measure(self, scene, width, height, frames):
        """Frames per second of ``scene``, drawn back to back."""
        program = self.renderer.generate(scene, width, height)
        picture = self.display._offscreen(width, height)
        for _ in range(3):                                  # compile, warm the caches
            self.frame(program, scene, width, height, picture)
        with self.ctx:
            self.ctx.finish()
        start = time.perf_counter()
        for _ in range(frames):
            self.frame(program, scene, width, height, picture)
        with self.ctx:
            self.ctx.finish()
        seconds = time.perf_counter() - start
        return frames / seconds


    def readback_ms(self, scene, width, height, repeat=5) -> float:
        """Median ms of a whole render of ``scene`` (draw and read-back into a Frame)."""
        self.renderer.render(scene, width, height)
        times = []
        for _ in range(repeat):
            start = time.perf_counter()
            self.renderer.render(scene, width, height)
            times.append(time.perf_counter() - start)
        return 1000 * statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default=",".join(bundled_scene_names(meshes=False)))
    parser.add_argument("--size", default="1920x1080", type=parse_size)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--prepass", default="none,cone")
    parser.add_argument("--repeat", type=int, default=5, help="frames timed with read-back")
    parser.add_argument("--stages", default="fragment,compute")
    args = parser.parse_args()
    width, height = args.size
    drawers = {stage: Drawer(stage) for stage in args.stages.split(",")}
    settings = args.prepass.split(",")
    ctx = next(iter(drawers.values())).ctx
    print(f"{width}x{height}, {ctx.info['GL_RENDERER']}, OpenGL {ctx.version_code}\n")
    print("| scene | stage | prepass | fps, drawn back to back | ms with read-back |")
    print("|---|---|---|---:|---:|")
    for name in args.scenes.split(","):
        scene = rendered_scene(load_scene(name))
        for stage, drawer in drawers.items():
            for prepass in settings:
                variant = with_prepass(scene, prepass)
                fps = drawer.measure(variant, width, height, args.frames)
                back = drawer.readback_ms(variant, width, height, args.repeat)
                print(f"| {name} | {stage} | {prepass} | {fps:.0f} | {back:.1f} |", flush=True)


if __name__ == "__main__":
    main()
