"""What one shading model per object, lights with their own colours and the morph node cost,
each against the same scene without it, on every backend, side by side in one run.

    python benchmarks/bench_models.py [--size 320x240] [--repeat 5]

Markdown tables for docs/performance.md: per backend, the median ms per frame of each variant
and its ratio to the first (`bench_prepass.timing_rows`, the variants alternating):

1. the bundled `gallery`: every object drawn by Phong (its materials' `shading` removed, and
   the crate's texture), as given (six models chosen per object, `shade_surface`), and as
   given with its key light's own colours folded into one colour;
2. the bundled `morph`: its three morphs (t = 0, 0.5, 1) replaced by the child they show at
   their t (a sphere, the t = 0.5 one by its union with the box), and as given.
"""

from __future__ import annotations

import argparse
import dataclasses

import marchlab
from bench_environment import TIMED          # the same five backends and precisions
from bench_prepass import timing_rows         # the same alternating timing
from marchlab.cli import parse_size
from marchlab.render import backend_problem
from scene_model.scene import rendered_scene
from scene_model.shapes import Morph, Translate, Union


def gallery_variants() -> dict:
    scene = rendered_scene(marchlab.load_scene("gallery"))
    phong = {k: dataclasses.replace(m, shading=None, texture=None)
             for k, m in scene.materials.items()}
    plain = [dataclasses.replace(light, ambient=None, diffuse=None, specular=None)
             for light in scene.lights]
    return {"all Phong": dataclasses.replace(scene, materials=phong),
            "a model per object": scene,
            "one-colour lights": dataclasses.replace(scene, lights=tuple(plain))}


def without_morphs(node):
    """The tree with each morph replaced by what it shows at its ends (t 0 or 1: that child;
    between: the union of both, a bound of the same surface's cost)."""
    if isinstance(node, Morph):
        a, b = node.children
        return a if node.t == 0 else b if node.t == 1 else Union((a, b))
    if isinstance(node, Translate):
        return dataclasses.replace(node, child=without_morphs(node.child))
    return node


def morph_variants() -> dict:
    scene = rendered_scene(marchlab.load_scene("morph"))
    plain = tuple(without_morphs(node) for node in scene.objects)
    return {"children instead": dataclasses.replace(scene, objects=plain), "morphs": scene}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="320x240", type=parse_size)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    width, height = args.size
    labels = [label for label in TIMED if backend_problem(label.split()[0]) is None]
    for title, variants in (("gallery", gallery_variants()), ("morph", morph_variants())):
        print(f"\n{title}, {width}x{height}, ms per frame (median of {args.repeat}; ratio to "
              "the first):\n")
        print("| backend | " + " | ".join(variants) + " |\n|---|" + "---|" * len(variants))
        print("\n".join(timing_rows(list(variants.values()), width, height, TIMED, labels,
                                    args.repeat)))


if __name__ == "__main__":
    main()
