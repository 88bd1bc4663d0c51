"""Shadow rays toward two lights marched in one loop (``glsl/shadow_pair.glsl``).

The one-ray programs (the GLSL shader, the one-ray OpenCL kernel) march the hard shadow rays
of a lit point two lights at a time, because llvmpipe then overlaps the two chains of
arithmetic. That is an optimisation, not a change of algorithm: with pairing on or off,
every buffer of every frame must be the same to the bit. The scenes: the classroom (two
lights, one pair), ``lights`` (three: a pair and one alone) and ``grazing_lights``, built
so that mixing up the two rays of a pair shows.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import gpu_shader.generate as generator
from marchlab import load_scene, render
from scene_model.builder import Checker, Material, PointLight, Scene, plane, sphere

WIDTH, HEIGHT = 64, 48
BUFFERS = ("color", "depth", "normal", "steps", "object_id", "hit", "path")


def grazing_lights() -> Scene:
    """Five lights: two low over the floor, far away (long shadow marches, some out of
    steps); one close above the floor with a sphere floating just beyond it, paired with one
    farther off (a ray that marched past its own light would find that sphere, one that
    stopped at its partner's distance would miss the spheres between); one under the floor
    (points facing away need no shadow ray), marched alone."""
    scene = Scene(
        objects=(plane(material="floor"), sphere(0.7).at(-1.0, 0.7, 0.0),
                 sphere(0.5).at(1.2, 0.5, -1.0), sphere(0.3).at(0.2, 0.3, 1.2),
                 sphere(0.4).at(0.0, 2.2, 0.2)),
        materials={"floor": Material(checker=Checker()), "default": Material()},
        lights=(PointLight(position=(-30.0, 0.6, -5.0)), PointLight(position=(25.0, 0.4, 10.0)),
                PointLight(position=(0.0, 1.2, 0.2)), PointLight(position=(2.5, 3.0, 2.0)),
                PointLight(position=(0.0, -3.0, 0.0))))
    settings = dataclasses.replace(scene.render, shadows="hard", max_steps=64)
    return dataclasses.replace(scene, render=settings)


def culled(scene: Scene) -> Scene:
    """``scene`` with bounding-sphere culling: each ray of a pair has its own object set."""
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render,
                                                                 bounding_spheres=True))


SCENES = {"classroom": lambda: load_scene("classroom"), "lights": lambda: load_scene("lights"),
          "grazing-lights": grazing_lights,
          "grazing-lights-culled": lambda: culled(grazing_lights())}


def render_one_ray(backend: str, scene, precision: str):
    """The one-ray program of ``backend`` (the opencl backend's default is the packet one)."""
    if backend == "opencl":
        from gpu_shader import opencl
        return opencl.render(scene, WIDTH, HEIGHT, precision, packets=False, path_labels=True)
    return render(scene, WIDTH, HEIGHT, backend=backend, precision=precision, path_labels=True)


@pytest.mark.parametrize("name", list(SCENES))
def test_shadow_rays_in_pairs_give_the_frame_of_one_ray_per_light_to_the_bit(
        backend, name, monkeypatch):
    scene = SCENES[name]()
    assert "hard_shadow_pair(" in generator.generate(scene, WIDTH, HEIGHT).source
    unlit = dataclasses.replace(scene, render=dataclasses.replace(scene.render, shadows="none"))
    for precision in ("float32",) if backend == "gpu" else ("float32", "float64"):
        monkeypatch.setattr(generator, "PAIR_SHADOW_RAYS", True)
        paired = render_one_ray(backend, scene, precision)
        monkeypatch.setattr(generator, "PAIR_SHADOW_RAYS", False)
        alone = render_one_ray(backend, scene, precision)
        assert "hard_shadow_pair(" not in generator.generate(scene, WIDTH, HEIGHT).source
        # the scene has shadows to get right: pixels darker than without them
        darker = (paired.color.sum(-1) < render_one_ray(backend, unlit, precision)
                  .color.sum(-1) - 1e-3)
        assert darker.sum() > 0.02 * darker.size, (name, precision)
        for buffer in BUFFERS:
            assert np.array_equal(getattr(paired, buffer), getattr(alone, buffer),
                                  equal_nan=True), (name, precision, buffer)
