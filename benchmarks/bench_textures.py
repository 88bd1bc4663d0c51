"""What surface textures cost on every backend: time per frame of one scene with plain
colours, its textures as given, every texture triplanar, and every texture a larger image.

    python benchmarks/bench_textures.py [--scene textures] [--size 320x240] [--repeat 3]

A Markdown table for docs/performance.md: per backend, the median wall time per frame of
each variant and its ratio to plain colours, with the share of pixels whose camera ray hits
a textured object. The variants alternate within each round, so a busy moment of this
shared machine hits all of them:

- plain: each material's ``color``, its texture removed;
- as given: the scene's textures (the bundled `textures`: uv on the floor, the box and the
  globe, triplanar on a torus and a blob, all of the 32 x 32 built-in image);
- triplanar: every texture mapped by triplanar (three filtered look-ups a point);
- 512^2 image: the textures as given, of a 512 x 512 float32 image (written to a temporary
  folder) instead: the same arithmetic, more texels to hold and to copy.
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path

import numpy as np

import marchlab
from bench_environment import TIMED          # the same five backends and precisions
from bench_prepass import timing_rows         # the same alternating timing
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene
from scene_model.shapes import primitives
from scene_model.textures import uv_grid

def with_textures(scene, change):
    """``scene`` with each textured material's texture replaced by ``change(texture)``."""
    materials = {name: m if m.texture is None else dataclasses.replace(m, texture=change(m.texture))
                 for name, m in scene.materials.items()}
    return dataclasses.replace(scene, materials=materials)


def large_image(folder: Path, size: int = 512) -> str:
    """The built-in image, enlarged to size x size (nearest texel), as a .npy in ``folder``."""
    small = uv_grid()
    rows = np.arange(size) * small.shape[0] // size
    path = folder / "large.npy"
    np.save(path, small[rows][:, rows])
    return str(path)


def textured_share(scene, width, height) -> float:
    """The share of pixels whose camera ray hits a textured object (NumPy, float32)."""
    frame = marchlab.render(scene, width, height, backend="numpy", precision="float32")
    textured = np.array([scene.materials[p.material].texture is not None
                         for p in primitives(scene.objects)] + [False])
    return float(textured[frame.object_id].mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="textures")
    parser.add_argument("--size", default="320x240", type=parse_size)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--backends", default=",".join(TIMED))
    args = parser.parse_args()
    (width, height), scene = args.size, rendered_scene(load_scene(args.scene))
    labels = [b for b in args.backends.split(",") if backend_problem(b.split()[0]) is None]
    with tempfile.TemporaryDirectory() as folder:
        image = large_image(Path(folder))
        variants = {
            "plain": with_textures(scene, lambda t: None),
            "as given": scene,
            "triplanar": with_textures(scene, lambda t: dataclasses.replace(
                t, mapping="triplanar")),
            "512^2 image": with_textures(scene, lambda t: dataclasses.replace(t, image=image)),
        }
        print(f"Scene `{args.scene}` at {width}x{height}; ms per frame (median of "
              f"{args.repeat}; ratio to plain); {textured_share(scene, width, height):.0%} of "
              "the pixels show a texture:\n")
        print("| backend | " + " | ".join(variants) + " |\n|---|" + "---|" * len(variants))
        print("\n".join(timing_rows(list(variants.values()), width, height, TIMED, labels,
                                    args.repeat)))
    if "gpu" in labels:
        from gpu_shader.render import device_name
        print(f"\ngpu: {device_name()}")


if __name__ == "__main__":
    main()
