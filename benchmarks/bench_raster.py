"""The three rasterisers of triangle meshes side by side, and the sphere tracer against
rasterisation at equal geometric error.

    python benchmarks/bench_raster.py [--size 640x480] [--repeat 3]

1. Time per frame of the mesh scene of the tests (a cube, a cone and a subdivided floor) and
   of finer spheres, at ``--size``: the NumPy rasteriser (`reference_cpu.rasterise`), the
   GPU raster pipeline (`gpu_shader.raster`, draw and read-back of its planes) and Embree's
   ray casts through every pixel centre (`reference_cpu.truth.embree`).
2. A sphere of radius 1 as a UV sphere of n segments (its largest distance from the true
   sphere, where a triangle's centre lies, about r (1 - cos(pi / n))) against the SDF sphere
   marched to the same epsilon: the gpu backend's sphere tracer and the raster pipeline,
   each frame's surface error: how far from the exact sphere the point it shows lies,
   | |o + t d| - 1 |, largest over the pixels it hits.

3. The lit raster pipeline (`gpu_shader.raster_lit.RasterRenderer`: meshes uploaded once, a
   shader generated for the scene, the skybox drawn last): ms per frame of the cube, cone
   and floor with a uv texture, a triplanar one and a checkerboard under a point, a
   directional and a coloured spot light, against each background kind; the draw alone
   (until glFinish returns), with the colour read back (what a viewer shows), and with
   every plane read back into a colour and a `Raster`; and NumPy's rasteriser and
   `shade_raster` for the same frame. ``--lit-only`` runs this part alone.

4. The ``museum`` scene (shadows of three lights, a mirror, a glass pane, a skybox) through
   the three mesh backends: numpy-raster and embree (`marchlab.render`), and the raster
   backend both as `marchlab.render` makes a frame (a new `MeshRenderer`, programs already
   compiled), with its renderer kept (`MeshRenderer.frame`: draw, read-back, path labels)
   and as a live view draws it (`MeshRenderer.draw`: buffers, shadow volumes and textures
   kept on the GPU, nothing read back, until glFinish returns). ``--museum-only`` runs this
   part alone.

5. ``--passes``: where a museum frame's time goes in the live view, pass by pass: each of
   `MeshRenderer`'s passes timed from a glFinish before it to one after it (llvmpipe runs
   a pass's fragments when it is flushed, so the glFinish charges each pass its own work),
   the rest being Python, uniforms and state. ``--passes`` runs this part alone.

6. ``--live``: the live view alone (`MeshRenderer.draw`) after 20 warm-up frames, 60 frames
   each finished with glFinish, then 60 back to back, at 640x480 and 1920x1080: a GPU whose
   clocks idle low (an H100's at 345 MHz) needs the warm-up to be measured at speed.

Medians of ``--repeat`` frames after one warm-up; machines are shared and noisy, so compare
the ratios of one run.
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

from marchlab.cli import parse_size  # noqa: E402
from mesh_scenes import CAMERA, SCENES  # noqa: E402
from reference_cpu.rasterise import rasterise  # noqa: E402
from scene_model.camera import camera_rays  # noqa: E402
from scene_model.meshes import uv_sphere  # noqa: E402


def median_seconds(run, repeat):
    run()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def embree_cast(meshes, width, height):
    from reference_cpu.truth.embree import cast
    from reference_cpu.truth.mesh import Mesh
    truth = [Mesh(m.positions, m.triangles.astype(np.int32), 0.0, None, "exact") for m in meshes]
    origin, directions = camera_rays(CAMERA, width, height)
    return cast(truth, origin, directions.reshape(-1, 3))


def surface_error(depth, hit, width, height) -> float:
    """Largest distance from the unit sphere of the points a frame shows: | |o + t d| - 1 |."""
    origin, d = camera_rays(CAMERA, width, height)
    points = origin + depth[hit][:, None] * d[hit]
    return float(np.abs(np.linalg.norm(points, axis=1) - 1.0).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--lit-only", action="store_true", help="time the lit pipeline only")
    parser.add_argument("--museum-only", action="store_true",
                        help="time the museum through the three mesh backends only")
    parser.add_argument("--live", action="store_true",
                        help="time the museum's live view after a warm-up only")
    parser.add_argument("--passes", action="store_true",
                        help="time the museum's live view pass by pass only")
    args = parser.parse_args()
    width, height = args.size
    from gpu_shader.raster import rasterise as gpu_rasterise
    from gpu_shader.render import device_name
    if args.live:
        museum_live()
        return
    if args.passes:
        museum_passes(width, height, args.repeat)
        print(f"\ngpu: {device_name()}")
        return
    if args.museum_only:
        museum_frames(width, height, args.repeat)
        print(f"\ngpu: {device_name()}")
        return
    if args.lit_only:
        lit_frames(width, height, args.repeat)
        print(f"\ngpu: {device_name()}")
        return

    scenes = {"cube, cone and floor": SCENES["cube and cone on a floor"]}
    for n in (32, 128):
        scenes[f"UV sphere, {n} x {n // 2}"] = [uv_sphere(1.0, n, n // 2)]
    print(f"Time per frame at {width}x{height}, ms (median of {args.repeat}):\n")
    print("| scene | triangles | NumPy rasteriser | GPU raster pipeline | Embree ray casts |")
    print("|---|---:|---:|---:|---:|")
    for name, meshes in scenes.items():
        cells = [median_seconds(lambda: rasterise(meshes, CAMERA, width, height), args.repeat),
                 median_seconds(lambda: gpu_rasterise(meshes, CAMERA, width, height),
                                args.repeat),
                 median_seconds(lambda: embree_cast(meshes, width, height), args.repeat)]
        triangles = sum(len(m.triangles) for m in meshes)
        print(f"| {name} | {triangles:,} | " + " | ".join(f"{1000 * c:.1f}" for c in cells)
              + " |", flush=True)

    import dataclasses
    import marchlab
    from scene_model.builder import sphere
    from scene_model.scene import RenderSettings, Scene
    print("\nA unit sphere at equal geometric error: the raster pipeline's UV sphere of n "
          "segments against the gpu backend's sphere tracer at epsilon = its error; each "
          "frame's surface error (the farthest its points lie from the sphere), ms per "
          "frame:\n")
    print("| n | geometric error | raster: ms, surface error | sphere tracer: ms, surface "
          "error |")
    print("|---:|---:|---:|---:|")
    base = Scene(camera=CAMERA, render=RenderSettings(shadows="none", reflection_depth=0),
                 objects=(sphere(1.0),))
    for n in (16, 64, 256, 1024):
        error = 1 - math.cos(math.pi / n)
        mesh = [uv_sphere(1.0, n, n // 2)]
        raster_ms = median_seconds(lambda: gpu_rasterise(mesh, CAMERA, width, height),
                                   args.repeat)
        raster = gpu_rasterise(mesh, CAMERA, width, height)
        scene = dataclasses.replace(base, render=dataclasses.replace(
            base.render, epsilon=max(error, 1e-6)))
        traced_ms = median_seconds(lambda: marchlab.render(scene, width, height, backend="gpu"),
                                   args.repeat)
        frame = marchlab.render(scene, width, height, backend="gpu")
        raster_error = surface_error(raster.depth, raster.hit, width, height)
        traced_error = surface_error(frame.depth, frame.hit, width, height)
        print(f"| {n} | {error:.2e} | {1000 * raster_ms:.1f}, {raster_error:.2e} | "
              f"{1000 * traced_ms:.1f}, {traced_error:.2e} |", flush=True)
    lit_frames(width, height, args.repeat)
    museum_frames(width, height, args.repeat)
    print(f"\ngpu: {device_name()}")


def museum_frames(width, height, repeat):
    """Part 4: the museum through the three mesh backends, ms per frame and frames per second."""
    import marchlab
    from gpu_shader.raster_render import MeshRenderer
    from marchlab import load_scene
    scene = load_scene("museum")
    renderer = MeshRenderer(scene)
    rows = {
        "numpy-raster (marchlab.render)": (lambda: marchlab.render(
            scene, width, height, backend="numpy-raster"), max(1, repeat // 3)),
        "embree (marchlab.render)": (lambda: marchlab.render(
            scene, width, height, backend="embree"), repeat),
        "raster (marchlab.render: new renderer, read-back)": (lambda: marchlab.render(
            scene, width, height, backend="raster"), repeat),
        "raster, renderer kept: draw, read-back, path labels": (lambda: renderer.frame(
            scene, width, height), repeat),
        "raster, live view: draw only": (lambda: renderer.draw(scene, width, height), repeat),
    }
    print(f"\nThe museum at {width}x{height}: shadows of three lights, a mirror, a glass "
          "pane, a skybox:\n")
    print("| backend | ms per frame | frames per second |")
    print("|---|---:|---:|")
    for name, (run, times) in rows.items():
        seconds = median_seconds(run, times)
        print(f"| {name} | {1000 * seconds:.1f} | {1 / seconds:.1f} |", flush=True)
    renderer.release()


def museum_live(warm_up=20, frames=60):
    """Part 6: the museum's live view at 640x480 and 1920x1080 after ``warm_up`` frames:
    the median of ``frames`` frames each to glFinish, and ``frames`` drawn back to back."""
    from gpu_shader.raster_render import MeshRenderer
    from marchlab import load_scene
    scene = load_scene("museum")
    renderer = MeshRenderer(scene)

    def finish():
        with renderer.ctx:
            renderer.ctx.finish()

    print("\n| museum live view | each frame to glFinish, median ms (min-max) | back to back, "
          "ms a frame |\n|---|---:|---:|")
    for width, height in [(640, 480), (1920, 1080)]:
        for _ in range(warm_up):
            renderer.draw(scene, width, height)
        finish()
        times = []
        for _ in range(frames):
            start = time.perf_counter()
            renderer.draw(scene, width, height)
            finish()
            times.append(time.perf_counter() - start)
        start = time.perf_counter()
        for _ in range(frames):
            renderer.draw(scene, width, height)
        finish()
        print(f"| {width}x{height} | {1000 * statistics.median(times):.2f} "
              f"({1000 * min(times):.2f}-{1000 * max(times):.2f}) | "
              f"{1000 * (time.perf_counter() - start) / frames:.2f} |")
    renderer.release()


def museum_passes(width, height, repeat):
    """Part 5: the museum's live view (`MeshRenderer.draw`), ms per pass, median of ``repeat``
    frames after one warm-up."""
    from gpu_shader.raster_render import MeshRenderer
    from marchlab import load_scene
    scene = load_scene("museum")
    renderer = MeshRenderer(scene)
    ctx = renderer.ctx
    frame: dict = {}

    def timed(owner, method, name, current=False):
        """Wrap ``owner.method`` to add its time, glFinish to glFinish, to frame[name]
        (``current``: it is called inside a ``with ctx`` block already)."""
        run = getattr(owner, method)

        def finish():
            if current:
                ctx.finish()
            else:
                with ctx:
                    ctx.finish()

        def wrapped(*args, **kwargs):
            finish()
            start = time.perf_counter()
            out = run(*args, **kwargs)
            finish()
            label = name(args, kwargs) if callable(name) else name
            frame[label] = frame.get(label, 0.0) + time.perf_counter() - start
            return out
        setattr(owner, method, wrapped)

    passes = {"opaque": "lit opaque pass (with the skybox)", "mirror": "mirrored pass",
              "layer a": "peeling passes", "layer b": "peeling passes"}
    timed(renderer.volumes, "draw", "shadow volumes (depth, 3 lights)", current=True)
    timed(renderer.lit, "draw_pass", lambda a, k: passes[k.get("target", "opaque")
                                                         .replace("frame", "opaque")])
    timed(renderer, "_composite", lambda a, k: ("mirror compositing" if a[0] == 0
                                                 else "peeled layers compositing"))
    frames = []
    for _ in range(repeat + 1):
        frame.clear()
        start = time.perf_counter()
        renderer.draw(scene, width, height)
        frame["whole frame"] = time.perf_counter() - start
        frames.append(dict(frame))
    frames = frames[1:]
    names = [n for n in frames[0] if n != "whole frame"]
    print(f"\nThe museum's live view at {width}x{height}, ms per pass (median of {repeat}):\n")
    print("| pass | ms |")
    print("|---|---:|")
    for name in names:
        print(f"| {name} | {1000 * statistics.median(f.get(name, 0.0) for f in frames):.1f} |")
    rest = [f["whole frame"] - sum(f.get(n, 0.0) for n in names) for f in frames]
    print(f"| the rest (Python, clears, uniforms) | {1000 * statistics.median(rest):.1f} |")
    print(f"| whole frame | {1000 * statistics.median(f['whole frame'] for f in frames):.1f} |")
    renderer.release()


def lit_frames(width, height, repeat):
    """Part 3: the lit raster pipeline's frame times, one row per background kind."""
    from gpu_shader.raster_lit import RasterRenderer
    from reference_cpu.raster_shading import shade_raster
    from scene_model.scene import (Checker, DirectionalLight, Material, PointLight,
                                   SkyBackground, SolidBackground, SpotLight,
                                   StudioBackground, Texture)
    meshes = SCENES["cube and cone on a floor"]
    materials = [Material(color=(0.8, 0.3, 0.2), ks=0.5, texture=Texture(mapping="uv")),
                 Material(texture=Texture(scale=0.7)), Material(checker=Checker(scale=0.5))]
    lights = (PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),
              DirectionalLight(direction=(1.0, -1.0, -0.5), intensity=0.5),
              SpotLight(position=(2.0, 3.0, 2.0), direction=(-1.0, -1.5, -1.0),
                        intensity=0.8, diffuse=(1.0, 0.9, 0.7), specular=(0.5, 0.5, 1.0)))
    backgrounds = {"solid (a clear)": SolidBackground(color=(0.1, 0.1, 0.1)),
                   "sky gradient": SkyBackground(), "studio cube map": StudioBackground()}
    renderer = RasterRenderer(meshes)
    ctx = renderer.ctx
    colour = np.empty((height, width, 4), np.float32)

    def drawn(settings):
        fbo = renderer.draw_planes(materials, lights, CAMERA, width, height, **settings)
        with ctx:                # glFinish on our context: the frame is done, not queued
            ctx.finish()
        return fbo

    def shown(settings):         # attachment 3 is the colour (RasterRenderer.draw_planes)
        fbo = renderer.draw_planes(materials, lights, CAMERA, width, height, **settings)
        with ctx:
            fbo.read_into(colour, components=4, attachment=3, dtype="f4")

    print(f"\nThe lit raster pipeline at {width}x{height}: the cube (uv texture), cone "
          "(triplanar texture) and checkered floor under three lights, ms per frame:\n")
    print("| background | draw | draw, colour read back | draw, colour and Raster read "
          "back | NumPy rasterise + shade_raster |")
    print("|---|---:|---:|---:|---:|")
    for name, background in backgrounds.items():
        settings = {"ambient": (0.1, 0.1, 0.1), "background": background}
        cells = [median_seconds(lambda: drawn(settings), repeat),
                 median_seconds(lambda: shown(settings), repeat),
                 median_seconds(lambda: renderer.draw(materials, lights, CAMERA, width,
                                                      height, **settings), repeat)]
        cells.append(median_seconds(lambda: shade_raster(
            rasterise(meshes, CAMERA, width, height), CAMERA, materials, lights,
            background=background, ambient=(0.1, 0.1, 0.1)), max(1, repeat // 3)))
        print(f"| {name} | " + " | ".join(f"{1000 * c:.1f}" for c in cells) + " |", flush=True)
    renderer.release()


if __name__ == "__main__":
    main()
