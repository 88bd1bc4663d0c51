"""The scenes the equivalence suite renders: every bundled scene and a feature matrix.

Each feature case starts from one small base scene (a checker floor, a sphere and a box,
one point light) and changes one thing: a primitive, an operator, a shading mode, a shadow
kind, a reflection depth, fog, a light type, the normal stencil, the background or a
texture. A
failure therefore names the feature that broke.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import tempfile
from pathlib import Path

import numpy as np

from marchlab import load_scene
from scene_model.builder import (Camera, Checker, DirectionalLight, Fog, Material, PointLight,
                                 RenderSettings, Scene, SkyBackground, SolidBackground, SpotLight,
                                 box, capped_cylinder, capsule, cone, disk, hex_prism, plane,
                                 pyramid, round_box, sphere, torus)
from scene_model.environment import equirect_directions, studio_radiance
from scene_model.files import write_atomically
from scene_model.scene import EquirectBackground, StudioBackground, Texture
from scene_model.scenefile import bundled_scene_names

SIZE = (64, 48)            # feature cases: small enough for CI, large enough to see edges
BUNDLED_SIZE = (96, 72)

MATERIALS = {
    "default": Material(color=(0.8, 0.75, 0.7), ks=0.4, shininess=24.0),
    "floor": Material(color=(0.8, 0.8, 0.8), ks=0.05,
                      checker=Checker(color_a=(0.85, 0.85, 0.8), color_b=(0.1, 0.1, 0.12))),
    "mirror": Material(color=(0.9, 0.9, 0.95), kd=0.1, ks=0.8, shininess=120.0, kr=0.8),
    "glass": Material(color=(1.0, 1.0, 1.0), ka=0.0, kd=0.0, ks=0.6, shininess=200.0,
                      transparency=1.0, ior=1.5, absorption=(0.6, 0.15, 0.05)),
    "dense_glass": Material(color=(1.0, 1.0, 1.0), ka=0.0, kd=0.05, ks=0.4, shininess=80.0,
                            transparency=0.9, ior=1.9),
}
# textures (docs/phong.md, "Textures"), of the built-in image: its texels change by at most
# 0.15 from one to the next, so a march that stops a little further on changes no colour
# by an 8-bit level
MATERIALS.update({
    "textured": Material(color=(0.8, 0.75, 0.7), ks=0.4, shininess=24.0,
                         texture=Texture(scale=1.5, sharpness=4.0)),
    "textured_uv": Material(ks=0.3, texture=Texture(mapping="uv", scale=1.5)),
    "textured_floor": Material(ks=0.05, texture=Texture(mapping="uv", scale=2.0,
                                                        tint=(0.9, 0.9, 0.8))),
})
# one material per shading model an object may choose (feature case "shading_per_object")
MATERIALS.update({f"model_{m}": Material(color=(0.8, 0.5, 0.3), ks=0.5, shading=m)
                  for m in ("blinn_phong", "toon", "stripes", "normals", "depth", "steps")})


def base_scene(objects=None, materials=None, **render) -> Scene:
    """A floor, the given objects (a sphere by default), one point light, hard shadows;
    ``materials`` in place of `MATERIALS`, where given."""
    shapes = objects if objects is not None else [sphere(0.8).at(0, 0.8, 0)]
    settings = dict(shadows="hard", max_distance=40.0,
                    background=SkyBackground(bottom=(0.7, 0.75, 0.8), top=(0.2, 0.35, 0.7)))
    settings.update(render)
    return Scene(
        description="equivalence feature case",
        camera=Camera(position=(2.5, 2.2, 4.5), look_at=(0, 0.6, 0), fov=50.0),
        render=RenderSettings(**settings),
        materials=MATERIALS if materials is None else materials,
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
        "morph": base_scene([sphere(0.8).morph(box(0.6), t=0.4).rotate(0, 30, 0).at(*at)]),
        "repeat_limited": base_scene([sphere(0.3).repeat((1.0, 0, 1.0), count=(1, 0, 1)).at(0, 0.3, 0)]),
        "repeat_infinite": base_scene([sphere(0.25).repeat((1.2, 0, 1.2)).at(0, 0.25, 0)]),
        # each shading mode
        "blinn_phong": base_scene(shading="blinn_phong"),
        "toon": base_scene(shading="toon", toon_bands=4),
        "stripes": base_scene(shading="stripes", toon_bands=5),
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
    # lights with their own ambient, diffuse and specular colours (two of them paired for
    # their hard shadow rays, one alone), in Phong and in toon
    own = [PointLight(position=(-3.0, 5.0, 3.0), intensity=1.2, linear=0.02,
                      ambient=(0.08, 0.04, 0.0), diffuse=(0.9, 0.7, 0.4), specular=(0.3, 0.5, 1.0)),
           dataclasses.replace(spot, specular=(1.0, 0.2, 0.2)),
           dataclasses.replace(directional, intensity=0.6, ambient=(0.0, 0.05, 0.1))]
    cases["lights_own_colors"] = with_lights(base_scene(), *own)
    cases["lights_own_colors_toon"] = with_lights(base_scene(shading="toon", shadows="soft"),
                                                  *own)
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
    # anti-aliasing (scene_model/sampling.py): each grid at n = 2 (an extra ray through the
    # centre), the rotated one at n = 3 (the centre is a sample) in an unlit mode, and samples
    # with the pre-pass's starts and mirrors
    cases["aa_regular_2"] = base_scene(samples=2)
    cases["aa_rotated_2"] = base_scene(samples=2, sample_pattern="rotated")
    cases["aa_rotated_3_normals"] = base_scene(shading="normals", samples=3,
                                               sample_pattern="rotated")
    cases["aa_prepass_mirrors"] = base_scene(mirrors, samples=2, sample_pattern="rotated",
                                             prepass="cone", reflection_depth=2)
    # glass (docs/glass.md): a tinted ball before a mirror, Schlick's Fresnel, a hollow ball
    # holding a denser one, the camera inside a glass block, and glass with everything else
    # that changes a march or a colour. A lens magnifies where a march stopped (up to
    # epsilon / cos i along a grazing ray), so glass asks for a finer epsilon.
    glass = [sphere(0.8, material="glass").at(0, 0.8, 0),
             box(0.5, material="mirror").rotate(0, 35, 0).at(-0.8, 0.5, -1.6)]
    fine = dict(epsilon=1e-4)
    cases["glass"] = base_scene(glass, reflection_depth=5, **fine)
    cases["glass_schlick"] = base_scene(glass, reflection_depth=5, fresnel="schlick", **fine)
    # (on a plain floor: through two lenses the checker shrinks to a few pixels a cell, and
    # nearly every pixel there lies next to a cell edge)
    nested = base_scene(
        [(sphere(0.85, material="glass") - sphere(0.65, material="glass")).at(0, 0.85, 0),
         sphere(0.45, material="dense_glass").at(0, 0.85, 0)], reflection_depth=6, **fine)
    plain_floor = Material(color=(0.75, 0.75, 0.7), ks=0.05)
    cases["glass_nested"] = dataclasses.replace(
        nested, materials=dict(nested.materials, floor=plain_floor))
    inside = base_scene([box(0.8, 0.6, 0.8, material="glass").at(2.5, 2.2, 4.5),
                         sphere(0.8).at(0, 0.8, 0)], reflection_depth=4, **fine)
    cases["glass_camera_inside"] = inside
    cases["glass_everything"] = base_scene(glass, reflection_depth=4, shadows="soft",
                                           fog=Fog(color=(0.7, 0.75, 0.8), density=0.05),
                                           prepass="cone", relaxation="auto",
                                           bounding_spheres=True, **fine)
    cases.update(environment_cases())
    cases.update(texture_cases())
    # a shading model per object (docs/phong.md, "One model per object"): lit models side by
    # side, the buffers shown as colours, seen directly and in a mirror
    gallery = [sphere(0.45, material="model_blinn_phong").at(-1.4, 0.45, 0.6),
               box(0.35, material="model_toon").rotate(0, 30, 0).at(-0.5, 0.35, 1.2),
               sphere(0.45, material="model_stripes").at(0.5, 0.45, 1.0),
               torus(0.35, 0.12, material="model_normals").rotate(70, 0, 0).at(1.4, 0.5, 0.4),
               sphere(0.4, material="model_depth").at(-0.9, 0.4, -0.6),
               box(0.3, material="model_steps").at(0.9, 0.3, -0.7),
               sphere(0.5, material="mirror").at(0.0, 0.5, -1.6)]
    cases["shading_per_object"] = base_scene(gallery, reflection_depth=1)
    return cases


def environment_cases() -> dict[str, Scene]:
    """Environment maps (scene_model/environment.py): the studio cube map seen around the
    objects, turned and brighter in mirrors, and a panorama of it, in files."""
    mirrors = [sphere(0.7, material="mirror").at(-0.6, 0.7, 0),
               box(0.5, material="mirror").rotate(0, 35, 0).at(0.9, 0.5, -0.3)]
    return {
        "background_cubemap": base_scene(background=StudioBackground(size=32)),
        "mirror_cubemap": base_scene(mirrors, reflection_depth=2, background=StudioBackground(
            intensity=1.3, rotation=40.0)),
        "mirror_equirect": base_scene(mirrors, reflection_depth=2, background=EquirectBackground(
            studio_panorama(), rotation=-25.0)),
    }


def texture_cases() -> dict[str, Scene]:
    """Surface textures (reference_cpu/texture.py): triplanar on a torus and a turned box;
    uv on a floor, a sphere and a box (three faces, and their seams, in view); and a sphere
    wearing an image file (the studio panorama) beside a mirror in the studio, so that the
    atlas holds an environment and a texture of another width."""
    on_floor = dict(MATERIALS, floor=MATERIALS["textured_floor"])
    globe = dict(on_floor, globe=Material(ks=0.3, texture=Texture(studio_panorama(),
                                                                   mapping="uv")))
    return {
        "texture_triplanar": base_scene([
            torus(0.6, 0.22, material="textured").rotate(60, 0, 0).at(-0.5, 0.8, 0),
            box(0.4, material="textured").rotate(20, 35, 0).at(0.9, 0.5, -0.4)]),
        "texture_uv_sphere_box_plane": base_scene(
            [sphere(0.6, material="textured_uv").at(-0.7, 0.6, 0.2),
             box(0.45, material="textured_uv").at(0.8, 0.45, -0.4)], on_floor),
        "texture_file_mirror_studio": base_scene(
            [sphere(0.7, material="globe").at(-0.6, 0.7, 0),
             box(0.5, material="mirror").rotate(0, 35, 0).at(0.9, 0.5, -0.3)], globe,
            reflection_depth=2, background=StudioBackground(size=32)),
    }


def studio_panorama(width: int = 128, height: int = 64) -> str:
    """The file of a panorama of the studio (a float32 .npy), written once into the
    system's temporary folder under a name holding a digest of its bytes."""
    directions = equirect_directions(width, height).reshape(-1, 3)
    pixels = studio_radiance(directions).reshape(height, width, 3).astype(np.float32)
    digest = hashlib.sha256(pixels.tobytes()).hexdigest()[:12]
    path = Path(tempfile.gettempdir()) / f"marchlab-studio-{width}x{height}-{digest}.npy"
    if not path.exists():
        buffer = io.BytesIO()
        np.save(buffer, pixels)
        write_atomically(path, buffer.getvalue())
    return str(path)


# The steps shading mode colours by an integer that a rounding difference can change by one
# on any pixel (not only near edges): the 0.05% limit on such pixels needs more pixels.
SIZES = {"steps": (128, 96), "prepass_cone_tile_5": (128, 96)}

# The bundled glass scene sees a busy checker through balls of index 1.5, which magnify it:
# the band beside each checker edge where float32 rounding can flip a ray's label widens
# with them (docs/glass.md, "Equivalence"). On an NVIDIA H100 the gpu backend's frame of it
# with the pre-pass had 4 and 5 such pixels of 6,912, every one within 1 px of a label jump
# (llvmpipe: 2), against the 3.5 of 0.05%; its path labels may differ on 0.1% of pixels.
# The gate that no label differs away from a jump is the same for every case.
PATH_FRACTION = {"scene:glass": 0.001, "scene:glass+prepass": 0.001}


def all_cases() -> list[tuple[str, Scene, tuple[int, int]]]:
    """(name, scene, size) for every bundled scene and every feature case."""
    out = [(f"scene:{name}", load_scene(name), BUNDLED_SIZE)
           for name in bundled_scene_names(meshes=False)]
    # ... and each again with the cone pre-pass
    out += [(f"scene:{name}+prepass", load_scene(name, ["render.prepass=cone"]), BUNDLED_SIZE)
            for name in bundled_scene_names(meshes=False)]
    out += [(f"feature:{name}", scene, SIZES.get(name, SIZE))
            for name, scene in feature_cases().items()]
    return out
