"""Shadow maps' artefacts measured against the exact shadows, as a table.

    python benchmarks/bench_shadow_maps.py [--size 256 1024 4096] [--bias 0 0.001 0.05 0.2]
                                           [--slope 0 1.5] [--image 96x72] [--pcf 1]

On the tests' "cube and cone on a floor" (tests/mesh_scenes.py), for a point and a
directional light, every map size x bias x slope bias, against the NumPy shadow volumes
(`reference_cpu.shadow_volumes`, the exact hard shadows):

- **wrong**: the fraction of drawn pixels whose visibility differs from the exact one;
- **acne**: the fraction of exactly lit pixels the map shadows;
- **missed**: the fraction of exactly shadowed pixels the map lights;
- **far**: how many wrong pixels lie more than a pixel from an exact edge or silhouette.

Then peter-panning beside a thin wall (tests/test_shadow_map.py's scene): how wide, in
image pixels (mean per column), the lit gap between the wall's foot and its shadow is, for
each bias. And the milliseconds a shadow map takes (draw and look-up) at each size.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))

from marchlab.compare import boundary, dilate  # noqa: E402
from mesh_scenes import CAMERA, SCENES  # noqa: E402
from reference_cpu.rasterise import rasterise  # noqa: E402
from reference_cpu.shadow_map import shadow_map_visibility  # noqa: E402
from reference_cpu.shadow_volumes import shadow_volume_visibility  # noqa: E402
from scene_model.meshes import cube, plane, transformed  # noqa: E402
from scene_model.scene import Camera, DirectionalLight, PointLight  # noqa: E402

LIGHTS = {"point": PointLight(position=(-1.0, 3.0, -2.5)),
          "directional": DirectionalLight(direction=(0.5, -1.0, 0.9))}


def artefact_table(sizes, biases, slopes, width, height, pcf) -> None:
    meshes = SCENES["cube and cone on a floor"]
    raster = rasterise(meshes, CAMERA, width, height)
    print(f"{'light':<12}{'size':>6}{'bias m':>9}{'slope':>7}{'wrong':>9}{'acne':>9}"
          f"{'missed':>9}{'far':>6}{'ms':>8}")
    for name, light in LIGHTS.items():
        exact = shadow_volume_visibility(meshes, raster, CAMERA, light)
        lit, dark = raster.hit & (exact == 1), raster.hit & (exact == 0)
        near = dilate(boundary(exact) | boundary(raster.object_id), 1)
        for size in sizes:
            for bias in biases:
                for slope in slopes:
                    start = time.perf_counter()
                    v = shadow_map_visibility(meshes, raster, CAMERA, light, size, bias, slope,
                                              pcf)
                    ms = 1e3 * (time.perf_counter() - start)
                    wrong = raster.hit & (np.abs(v - exact) >= 0.5)
                    print(f"{name:<12}{size:>6}{bias:>9.4f}{slope:>7.1f}"
                          f"{wrong.sum() / raster.hit.sum():>9.4f}"
                          f"{(lit & (v < 0.5)).sum() / lit.sum():>9.4f}"
                          f"{(dark & (v >= 0.5)).sum() / dark.sum():>9.4f}"
                          f"{(wrong & ~near).sum():>6}{ms:>8.0f}")


def peter_panning(biases, width, height, size) -> None:
    wall = transformed(cube(1.0), np.array([[0.04, 0, 0, 0], [0, 1, 0, 0.5],
                                            [0, 0, 1.2, 0], [0, 0, 0, 1.0]]))
    meshes = [wall, plane(6.0, 6.0, 4)]
    light = DirectionalLight(direction=(1.0, -1.0, 0.0))
    camera = Camera(position=(1.8, 1.4, 1.8), look_at=(0.5, 0.0, 0.0), fov=50.0)
    raster = rasterise(meshes, camera, width, height)
    shadow = (shadow_volume_visibility(meshes, raster, camera, light) == 0) & (
        raster.object_id == 1)
    print(f"\npeter-panning beside a 4 cm wall, {size} map: gap in image pixels (mean per column)")
    for bias in biases:
        missed = shadow & (shadow_map_visibility(meshes, raster, camera, light, size, bias) == 1)
        columns = len(np.unique(np.nonzero(missed)[1]))
        print(f"  bias {bias:6.3f} m: {missed.sum():5d} pixels, "
              f"{missed.sum() / max(columns, 1):5.1f} wide")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, nargs="+", default=[256, 1024, 4096],
                        help="shadow map sides in texels")
    parser.add_argument("--bias", type=float, nargs="+", default=[0.0, 0.001, 0.05, 0.2],
                        help="constant biases (m)")
    parser.add_argument("--slope", type=float, nargs="+", default=[0.0, 1.5],
                        help="slope biases (texels)")
    parser.add_argument("--image", default="96x72", help="picture size WxH")
    parser.add_argument("--pcf", type=int, default=1, help="PCF kernel side (odd)")
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.image.lower().split("x"))
    artefact_table(args.size, args.bias, args.slope, width, height, args.pcf)
    peter_panning([0.0, 0.2, 0.4, 0.6, 0.8], width, height, 1024)


if __name__ == "__main__":
    main()
