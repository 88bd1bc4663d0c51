"""The scenes the equivalence suite renders: every bundled scene and a feature matrix.

Each feature case starts from one small base scene (a checker floor, a sphere and a box,
one point light) and changes one thing: a primitive, an operator, a shading mode, a shadow
kind, a reflection depth, fog, a light type, the normal stencil or the background. A
failure therefore names the feature that broke.
"""

from __future__ import annotations

import dataclasses

from marchlab import load_scene
from scene_model.builder import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                                 RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight,
                                 box, capped_cylinder, capsule, cone, disk, hex_prism, plane,
                                 pyramid, round_box, sphere, torus)
from scene_model.scenefile import bundled_scene_names

SIZE = (64, 48)            # feature cases: small enough for CI, large enough to see edges
BUNDLED_SIZE = (96, 72)

MATERIALS = {
    "default": Material(color=(0.8, 0.75, 0.7), ks=0.4, shininess=24.0),
    "floor": Material(color=(0.8, 0.8, 0.8), ks=0.05,
                      checker=Checker(color_a=(0.85, 0.85, 0.8), color_b=(0.1, 0.1, 0.12))),
    "mirror": Material(color=(0.9, 0.9, 0.95), kd=0.1, ks=0.8, shininess=120.0, kr=0.8),
}


def base_scene(objects=None, **render) -> Scene:
    """A floor, the given objects (a sphere by default), one point light, hard shadows."""
    shapes = objects if objects is not None else [sphere(0.8).at(0, 0.8, 0)]
    settings = dict(shadows="hard", max_distance=40.0,
                    background=SkyBackground(bottom=(0.7, 0.75, 0.8), top=(0.2, 0.35, 0.7)))
    settings.update(render)
    return Scene(
        description="equivalence feature case",
        camera=Camera(position=(2.5, 2.2, 4.5), look_at=(0, 0.6, 0), fov=50.0),
        render=RenderSettings(**settings),
        materials=MATERIALS,
        lights=(PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02),),
        objects=tuple([plane(material="floor")] + list(shapes)),
    )


def with_lights(scene: Scene, *lights) -> Scene:
    return dataclasses.replace(scene, lights=tuple(lights))


def feature_cases() -> dict[str, Scene]:
    at = (0, 0.8, 0)
    cases = {
        # each primitive (and each transform along the way)
        "sphere": base_scene(),
        "box": base_scene([box(0.6, 0.5, 0.4).rotate(0, 30, 0).at(*at)]),
        "round_box": base_scene([round_box(0.7, 0.5, 0.5, radius=0.15).rotate(10, 20, 30).at(*at)]),
        "torus": base_scene([torus(0.7, 0.22).rotate(60, 0, 0).at(*at)]),
        "capped_cylinder": base_scene([capped_cylinder(0.5, 0.7).rotate(0, 0, 20).at(0, 0.9, 0)]),
        "capsule": base_scene([capsule((-0.6, 0.3, 0), (0.6, 1.1, 0.2), 0.3)]),
        "cone": base_scene([cone(0.7, 1.4)]),
        "pyramid": base_scene([pyramid(1.4, 1.3).rotate(0, 25, 0)]),
        "disk": base_scene([disk(0.85, 0.16).rotate(55, 0, 20).at(0, 0.9, 0)]),
        "hex_prism": base_scene([hex_prism(0.55, 0.7).rotate(0, 35, 0).at(0, 0.55, 0)]),
        "scale": base_scene([box(0.5).scale(1.6).at(*at)]),
        # each operator
        "union": base_scene([sphere(0.6).at(-0.4, 0.7, 0) | box(0.5).at(0.5, 0.6, 0)]),
        "intersection": base_scene([(sphere(0.8) & box(0.6)).at(*at)]),
        "subtraction": base_scene([(box(0.65) - sphere(0.85)).rotate(0, 25, 0).at(*at)]),
        "smooth_union": base_scene([sphere(0.55).at(-0.35, 0.7, 0).smooth_union(
            sphere(0.55).at(0.35, 0.8, 0), k=0.3)]),
        "smooth_intersection": base_scene([sphere(0.8).smooth_intersection(box(0.6), k=0.2).at(*at)]),
        "smooth_subtraction": base_scene([box(0.65).smooth_subtraction(sphere(0.8), k=0.15).at(*at)]),
        "repeat_limited": base_scene([sphere(0.3).repeat((1.0, 0, 1.0), count=(1, 0, 1)).at(0, 0.3, 0)]),
        "repeat_infinite": base_scene([sphere(0.25).repeat((1.2, 0, 1.2)).at(0, 0.25, 0)]),
        # each shading mode
        "blinn_phong": base_scene(shading="blinn_phong"),
        "toon": base_scene(shading="toon", toon_bands=4),
        "normals": base_scene(shading="normals"),
        "depth": base_scene(shading="depth"),
        "steps": base_scene(shading="steps"),
        # shadows, normals, background, fog
        "shadows_none": base_scene(shadows="none"),
        "shadows_soft": base_scene(shadows="soft", penumbra_k=8.0),
        "normals_tetrahedron": base_scene(normal_method="tetrahedron"),
        "background_solid": base_scene(background=SolidBackground(color=(0.3, 0.3, 0.35))),
        "fog": base_scene(fog=Fog(color=(0.7, 0.75, 0.8), density=0.08)),
        # ambient light only: the shading sum over the lights is empty
        "no_lights": with_lights(base_scene()),
    }
    # reflections, depth 0 to 3, between a mirror sphere and a mirror box
    mirrors = [sphere(0.7, material="mirror").at(-0.6, 0.7, 0),
               box(0.5, material="mirror").rotate(0, 35, 0).at(0.9, 0.5, -0.3)]
    for depth in range(4):
        cases[f"reflections_{depth}"] = base_scene(mirrors, reflection_depth=depth)
    # light types, one at a time and all together
    directional = DirectionalLight(direction=(-0.4, -1.0, -0.3), color=(1.0, 0.95, 0.9))
    spot = SpotLight(position=(1.5, 4.0, 1.5), direction=(-0.3, -1.0, -0.3), intensity=1.5,
                     inner_angle=15.0, outer_angle=25.0)
    point = PointLight(position=(3.0, 3.0, 2.0), color=(0.5, 0.6, 1.0), quadratic=0.05)
    cases["light_directional"] = with_lights(base_scene(), directional)
    cases["light_spot"] = with_lights(base_scene(), spot)
    cases["lights_all_soft"] = with_lights(base_scene(shadows="soft"), directional, spot, point)
    # faster marching (docs/sphere-tracing.md, "Longer steps"): relaxed steps, bounding-sphere
    # culling, and both together with mirrors, whose rays start next to a surface
    several = [sphere(0.6).at(-0.9, 0.6, 0), torus(0.45, 0.15).rotate(70, 0, 0).at(0.7, 0.6, 0.4),
               box(0.35).rotate(0, 30, 0).at(0.2, 0.35, -1.0)]
    cases["relaxation_fixed"] = base_scene(relaxation="fixed", omega=1.5)
    cases["relaxation_auto"] = base_scene(several, relaxation="auto")
    cases["bounding_spheres"] = base_scene(several, bounding_spheres=True)
    cases["relaxed_culled_mirrors"] = base_scene(mirrors, relaxation="auto", bounding_spheres=True,
                                                 reflection_depth=2)
    # the cone pre-pass (docs/sphere-tracing.md, "Starting later"): alone, with tiles that do
    # not divide the image, and with everything else that changes a march
    cases["prepass_cone"] = base_scene(several, prepass="cone")
    cases["prepass_cone_tile_5"] = base_scene(several, prepass="cone", prepass_tile=5,
                                              shading="steps")
    cases["prepass_relaxed_culled_mirrors"] = base_scene(
        mirrors, prepass="cone", relaxation="auto", bounding_spheres=True, reflection_depth=2,
        shadows="soft")
    return cases


# The steps shading mode colours by an integer that a rounding difference can change by one
# on any pixel (not only near edges): the 0.05% limit on such pixels needs more pixels.
SIZES = {"steps": (128, 96), "prepass_cone_tile_5": (128, 96)}


def all_cases() -> list[tuple[str, Scene, tuple[int, int]]]:
    """(name, scene, size) for every bundled scene and every feature case."""
    out = [(f"scene:{name}", load_scene(name), BUNDLED_SIZE) for name in bundled_scene_names()]
    # ... and each again with the cone pre-pass
    out += [(f"scene:{name}+prepass", load_scene(name, ["render.prepass=cone"]), BUNDLED_SIZE)
            for name in bundled_scene_names()]
    out += [(f"feature:{name}", scene, SIZES.get(name, SIZE))
            for name, scene in feature_cases().items()]
    return out
