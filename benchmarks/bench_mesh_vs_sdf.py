"""Speed against error: the sphere tracer against the raster pipeline on the same shapes.

    python benchmarks/bench_mesh_vs_sdf.py [--size 640x480] [--repeat 3] [--plot PATH]

A sphere, a torus and a box, each drawn two ways under one camera and one point light, with
nothing else in the picture (a floor would add the same cost to both):

- **raster**: a triangle mesh of the shape (`scene_model.meshes`) drawn and lit by the GPU
  raster pipeline (`gpu_shader.raster_lit.RasterRenderer`, its buffers uploaded once), the
  colour read back;
- **sphere tracer**: the shape's SDF marched by the gpu backend (`gpu_shader.render.Renderer`,
  its program generated and compiled once), the colour plane read back.

Both read back one RGBA32F plane, so a frame costs the same transfer on both sides.

The **geometric error** of a mesh is the farthest any point of its triangles lies from the
true surface. It is measured, not assumed: `mesh_error` evaluates the exact SDF
(`reference_cpu.sdf`, float64) on a barycentric grid over every triangle and keeps the largest
|sdf|. The sphere tracer stops where the SDF is below its epsilon, so its geometric error is
epsilon; that is measured too (`hit_error`: |sdf| at the hit point o + t d of every pixel
the gpu backend hits). Each mesh is paired with a march at epsilon = the mesh's measured
error, so a row compares the two at equal error. The box's mesh is exact (flat faces: error 0
at any resolution), so the box is timed against the SDF box at several epsilons instead.

The best of ``--repeat`` frames after one warm-up frame, both methods in the same run; the
machine is shared, so compare the ratios of one run, not its times with another's.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import sys
import time
from collections.abc import Callable

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

from reference_cpu.sdf import sdf_box, sdf_sphere, sdf_torus  # noqa: E402
from scene_model import builder, meshes  # noqa: E402
from scene_model.camera import camera_rays  # noqa: E402
from scene_model.scene import (Camera, Material, PointLight, RenderSettings,  # noqa: E402
                               Scene, SolidBackground)

CAMERA = Camera(position=(2.2, 2.0, 3.4), look_at=(0.0, 0.0, 0.0), fov=40.0)
LIGHT = PointLight(position=(3.0, 5.0, 4.0))
MATERIAL = Material(color=(0.8, 0.3, 0.2))
AMBIENT = (0.2, 0.2, 0.2)

RADIUS = 1.0                    # the sphere
MAJOR, MINOR = 1.0, 0.35        # the torus: ring radius and tube radius
HALF = 0.75                     # the box's half side
BOX_EPSILONS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)


@dataclasses.dataclass(frozen=True)
class Shape:
    """One shape, as an SDF for the error measure, an SDF node for the sphere tracer and
    meshes of increasing resolution for the rasteriser (made when needed: the finest have a
    million triangles)."""
    name: str
    sdf: Callable[[np.ndarray], np.ndarray]
    node: object
    meshes: dict[str, Callable[[], meshes.TriangleMesh]]


SHAPES = (
    Shape("sphere", lambda p: sdf_sphere(p, RADIUS), builder.sphere(RADIUS),
          {**{f"UV sphere {n} x {n // 2}": (lambda n=n: meshes.uv_sphere(RADIUS, n, n // 2))
              for n in (16, 32, 64, 128, 256, 512, 1024)},
           **{f"cube sphere {s}": (lambda s=s: meshes.cube_sphere(RADIUS, s))
              for s in (4, 16, 64, 256)}}),
    Shape("torus", lambda p: sdf_torus(p, MAJOR, MINOR), builder.torus(MAJOR, MINOR),
          {f"torus {n} x {n // 2}": (lambda n=n: meshes.torus(MAJOR, MINOR, n, n // 2))
           for n in (16, 32, 64, 128, 256, 512, 1024)}),
    Shape("box", lambda p: sdf_box(p, np.full(3, HALF)), builder.box(HALF),
          {"cube": lambda: meshes.cube(2 * HALF)}),
)


# --- The error measures ------------------------------------------------------------------------

def barycentric_grid(subdivisions: int) -> np.ndarray:
    """Weights of the points of a triangle's grid of ``subdivisions`` cells a side.

    Returns
    -------
    (K, 3) ndarray
        (i, j, n - i - j) / n for every i, j >= 0 with i + j <= n: the corners, points along
        the edges and inside; K = (n + 1)(n + 2) / 2.
    """
    n = subdivisions
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    inside = i + j <= n
    i, j = i[inside], j[inside]
    return np.stack([i, j, n - i - j], axis=1) / n


def triangle_errors(corners: np.ndarray, sdf, subdivisions: int,
                    chunk: int = 1 << 15) -> np.ndarray:
    """Largest |sdf| over each triangle's barycentric grid.

    Parameters
    ----------
    corners : (T, 3, 3) ndarray
        The three corners of each triangle.
    sdf : callable
        ``sdf(p)`` for ``p : (N, 3)`` gives the exact signed distances ``(N,)``.
    subdivisions : int
        Cells along each side of a triangle's grid.

    Returns
    -------
    (T,) ndarray
        A lower bound of each triangle's distance from the surface, short of it by at most
        about the square of the grid's spacing over the surface's radius of curvature.
    """
    weights = barycentric_grid(subdivisions)
    errors = np.empty(len(corners))
    for start in range(0, len(corners), chunk):             # bounded memory on 1M triangles
        part = corners[start:start + chunk]
        points = np.einsum("kc,tcx->tkx", weights, part)    # (T, K, 3)
        d = np.abs(sdf(points.reshape(-1, 3))).reshape(len(part), -1)
        errors[start:start + chunk] = d.max(axis=1)
    return errors


def mesh_error(mesh: meshes.TriangleMesh, sdf, coarse: int = 4, fine: int = 32,
               refined: int = 256) -> float:
    """Geometric error of ``mesh``: the largest |sdf| over its triangles (world units).

    |sdf| is smooth over a triangle and largest inside it (a chord's sag), so a grid finds it
    to second order in its spacing. Every triangle is sampled on a ``coarse`` grid; the
    ``refined`` triangles that score worst are sampled again on a ``fine`` one, whose maximum
    is within about 0.1% of the true one (tests/test_bench_mesh_vs_sdf.py checks it against
    the UV sphere's closed form).
    """
    corners = mesh.positions[mesh.triangles]                    # (T, 3, 3), float64
    rough = triangle_errors(corners, sdf, coarse)
    worst = np.argsort(rough)[-refined:]
    return float(max(rough.max(), triangle_errors(corners[worst], sdf, fine).max()))


def uv_sphere_error(radius: float, segments: int, rings: int) -> float:
    """The closed form of a UV sphere's geometric error (n segments, m rings).

    A cell between two meridians and two parallels has its four corners on the sphere and is
    symmetric about its middle meridian, so it is a flat isosceles trapezoid. In that
    meridian's plane (distance from the axis, height) the midpoints of its two parallel edges
    are P_k = (r cos(a) cos(t_k), r sin(t_k)), a = pi / n: a chord across a parallel of
    radius r cos(t_k) sags by the factor cos(a), its height does not. The cell's plane holds
    the line P_1 P_2 and the direction across the meridian plane, so it passes as far from
    the centre as that line, |P_1 x P_2| / |P_2 - P_1|:

        r cos(a) cos(b) / sqrt(cos(t)^2 + cos(a)^2 sin(t)^2),   b = pi / (2 m),

    t the cell's middle latitude. That is least, and the error r minus it largest, in the
    cells nearest the equator, t = 0 for odd m (a row of cells straddles it) and t = b for
    even m, whose foot of the perpendicular lies inside the cell.
    """
    a, b = np.pi / segments, np.pi / (2 * rings)
    t = 0.0 if rings % 2 else b
    return radius * (1.0 - np.cos(a) * np.cos(b) / np.sqrt(
        np.cos(t) ** 2 + np.cos(a) ** 2 * np.sin(t) ** 2))


def hit_error(depth: np.ndarray, hit: np.ndarray, camera: Camera, sdf) -> float:
    """Geometric error of a frame: the largest |sdf| at the points o + t d that it hits.

    Parameters
    ----------
    depth : (H, W) ndarray
        Distance t along each pixel's unit ray (`scene_model.camera.camera_rays`).
    hit : (H, W) bool ndarray
    camera : Camera
    sdf : callable
        The exact SDF, evaluated in float64.
    """
    height, width = depth.shape
    origin, directions = camera_rays(camera, width, height)
    points = origin + depth[hit].astype(np.float64)[:, None] * directions[hit]
    return float(np.abs(sdf(points)).max())


# --- The timings -------------------------------------------------------------------------------

def best_seconds(run, repeat: int) -> float:
    """Shortest wall time of ``repeat`` calls of ``run`` after one untimed call: on a shared
    machine other work only ever adds time, so the least is the frame's own cost."""
    run()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def traced_scene(shape: Shape, epsilon: float) -> Scene:
    """The sphere tracer's scene: the shape alone, the benchmark's camera, light and
    material, no shadows or reflections, marched to ``epsilon``."""
    return Scene(camera=CAMERA, lights=(LIGHT,), materials={"default": MATERIAL},
                 objects=(shape.node,),
                 render=RenderSettings(epsilon=epsilon, shadows="none", reflection_depth=0,
                                       ambient=AMBIENT, background=SolidBackground()))


def raster_ms(mesh, width: int, height: int, repeat: int) -> float:
    """ms per lit raster frame of ``mesh``, the colour read back."""
    from gpu_shader.raster_lit import RasterRenderer
    renderer = RasterRenderer([mesh])
    colour = np.empty((height, width, 4), np.float32)

    def frame():                         # attachment 3 is the colour (draw_planes)
        fbo = renderer.draw_planes([MATERIAL], (LIGHT,), CAMERA, width, height,
                                   ambient=AMBIENT, background=SolidBackground())
        with renderer.ctx:
            fbo.read_into(colour, components=4, attachment=3, dtype="f4")
    try:
        return 1000 * best_seconds(frame, repeat)
    finally:
        renderer.release()


def traced(renderer, shape: Shape, epsilon: float, width: int, height: int,
           repeat: int) -> tuple[float, float]:
    """(ms per sphere-traced frame, the colour read back; that frame's measured error)."""
    scene = traced_scene(shape, epsilon)
    program = renderer.generate(scene, width, height)
    colour = np.empty((height, width, 4), np.float32)

    def frame():                         # attachment 0 is the colour and hit (planes.py)
        fbo = renderer.draw_planes(program, width, height)
        with renderer.ctx:
            fbo.read_into(colour, components=4, attachment=0, dtype="f4")
    ms = 1000 * best_seconds(frame, repeat)
    picture = renderer.render_program(scene, program, width, height)
    return ms, hit_error(picture.depth, picture.hit, CAMERA, shape.sdf)


def measure_shape(shape: Shape, renderer, width: int, height: int, repeat: int) -> list[dict]:
    """One row per mesh of ``shape``: its triangles, measured error and raster ms, and the
    sphere tracer at epsilon = that error (the box: one row per epsilon of BOX_EPSILONS)."""
    rows = []
    for name, make in shape.meshes.items():
        mesh = make()
        error = mesh_error(mesh, shape.sdf)
        row = {"mesh": name, "triangles": len(mesh.triangles), "mesh_error": error,
               "raster_ms": raster_ms(mesh, width, height, repeat)}
        epsilons = BOX_EPSILONS if error < 1e-9 else (error,)
        for epsilon in epsilons:
            ms, measured = traced(renderer, shape, epsilon, width, height, repeat)
            rows.append({**row, "epsilon": epsilon, "traced_error": measured, "traced_ms": ms})
            print(f"  {shape.name}: {name}, epsilon {epsilon:.2e}", file=sys.stderr, flush=True)
    return rows


def table(rows: list[dict]) -> str:
    """The markdown table of one shape's rows."""
    lines = [("| mesh | triangles | mesh error (measured) | raster ms | epsilon | "
              "sphere tracer error (measured) | sphere tracer ms |"),
             "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['mesh']} | {r['triangles']:,} | {r['mesh_error']:.2e} | "
                     f"{r['raster_ms']:.1f} | {r['epsilon']:.2e} | {r['traced_error']:.2e} | "
                     f"{r['traced_ms']:.1f} |")
    return "\n".join(lines)


def plot(results: dict[str, list[dict]], path: str, title: str) -> None:
    """Log-log: measured error on x, ms per frame on y, one line per method per shape."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colours = {"sphere": "tab:blue", "torus": "tab:orange", "box": "tab:green"}
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=100)
    for shape, rows in results.items():
        colour = colours[shape]
        traced_rows = sorted(rows, key=lambda r: r["traced_error"])
        ax.plot([r["traced_error"] for r in traced_rows], [r["traced_ms"] for r in traced_rows],
                "o--", color=colour, label=f"{shape}, sphere tracer")
        # A mesh's family is its name less the resolution: "UV sphere 16 x 8" -> "UV sphere".
        families = dict.fromkeys(re.sub(r"[\d x]+$", "", r["mesh"]) for r in rows)
        for family, marker in zip(families, "s^"):
            mine = [r for r in rows if re.sub(r"[\d x]+$", "", r["mesh"]) == family]
            if all(r["mesh_error"] < 1e-9 for r in mine):      # exact: no x on a log axis
                ax.axhline(mine[0]["raster_ms"], color=colour, linestyle="-", linewidth=1.2,
                           label=f"{shape}, raster ({mine[0]['mesh']}, error 0)")
                continue
            ax.plot([r["mesh_error"] for r in mine], [r["raster_ms"] for r in mine],
                    marker + "-", color=colour, label=f"{shape}, raster ({family} mesh)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.invert_xaxis()                    # more accurate to the right
    ax.set_xlabel("geometric error, measured (world units; accuracy grows to the right)")
    ax.set_ylabel("ms per frame")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main() -> None:
    from marchlab.cli import parse_size
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="640x480", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--plot", help="write the log-log plot of ms against error here (PNG)")
    args = parser.parse_args()
    width, height = args.size
    from gpu_shader.context import gl_context
    from gpu_shader.render import Renderer, device_name
    renderer = Renderer(gl_context())
    results = {shape.name: measure_shape(shape, renderer, width, height, args.repeat)
               for shape in SHAPES}
    print(f"Time per frame at {width}x{height}, ms (best of {args.repeat}), against the "
          "measured geometric error (world units; sphere radius 1, torus 1 and 0.35, box "
          "half side 0.75):")
    for name, rows in results.items():
        print(f"\n{name}:\n\n{table(rows)}")
    print(f"\ngpu: {device_name()}")
    if args.plot:
        plot(results, args.plot, f"{width}x{height}, {device_name()}")
        print(f"plot: {args.plot}")


if __name__ == "__main__":
    main()
