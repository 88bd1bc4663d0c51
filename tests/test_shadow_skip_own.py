"""Hard shadow rays that leave out the convex object they start on (render.shadow_skip_own).

A convex solid lies behind the tangent plane at each of its surface points, so a ray that
leaves the surface on the outer side (n . l > 0, the only shadow rays cast) never meets it
again: leaving it out of the march changes no shadow, and spares the steps of creeping away
from the surface (reference_cpu/shadows.py). The tests check which objects count as convex,
which are left out, that no shadow changes where the skipped objects are convex (a sphere over
a floor, against the exact segment test, and the bundled classroom), that a non-convex
object keeps shadowing itself (a torus, a block with a hole), and that the steps do fall.
The backends' agreement with the reference under this default is the equivalence suite's.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import marchlab
import reference_cpu.shadows
from reference_cpu.culling import MAX_CULLED, object_bits, own_objects
from reference_cpu.scene_sdf import build_scene_sdf
from reference_cpu.shadows import own_object_mask
from scene_model.builder import (Camera, Material, PointLight, RenderSettings, Scene,
                                 SolidBackground, box, capsule, cone, disk, hex_prism,
                                 intersection, plane, pyramid, round_box, sphere, torus,
                                 union)
from scene_model.scene import rendered_scene
from scene_model.scenefile import load_scene
from scene_model.shapes import Morph, Repeat, SmoothUnion, is_convex, object_of_primitive

WIDTH, HEIGHT = 64, 48


def with_skip(scene, skip: bool):
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render,
                                                                 shadow_skip_own=skip))


class ShadowSteps:
    """Adds up the steps of every shadow march of the reference while in a `with` block."""

    def __init__(self):
        self.rays = self.steps = 0

    def __enter__(self):
        self.march = reference_cpu.shadows.march

        def counting(*args, **kwargs):
            t, steps, hit = self.march(*args, **kwargs)
            self.rays, self.steps = self.rays + len(steps), self.steps + int(steps.sum())
            return t, steps, hit
        reference_cpu.shadows.march = counting
        return self

    def __exit__(self, *exc):
        reference_cpu.shadows.march = self.march


def render_both(scene, **kwargs):
    """The reference's frames and shadow steps without and with the own object left out."""
    frames, counts = [], []
    for skip in (False, True):
        with ShadowSteps() as counter:
            frames.append(marchlab.render(with_skip(scene, skip), WIDTH, HEIGHT,
                                          path_labels=True, **kwargs))
        counts.append(counter)
    return frames, counts


# --- which objects are convex, and which are left out --------------------------------------

@pytest.mark.parametrize("node", [
    sphere(1.0), box(0.5), round_box(0.5, radius=0.1), plane(), capsule(), cone(), pyramid(),
    disk(), hex_prism(), sphere(1.0).at(1.0, 2.0, 3.0).rotate(10.0, 20.0, 30.0).scale(2.0),
    intersection(box(1.0), sphere(1.3)),
], ids=lambda node: node.kind)
def test_convex_primitives_moved_turned_scaled_or_intersected_are_convex(node):
    assert is_convex(node)


@pytest.mark.parametrize("node", [
    torus(), union(sphere(1.0), sphere(1.0).at(3.0, 0.0, 0.0)), box(1.0) - sphere(1.2),
    SmoothUnion(children=(sphere(1.0), box(0.5).at(1.0, 0.0, 0.0)), k=0.2),
    Morph(children=(sphere(1.0), box(0.5)), t=0.5), Repeat(child=sphere(0.2), period=(1, 0, 0)),
    intersection(box(1.0), torus()), torus().at(0.0, 1.0, 0.0),
], ids=["torus", "union", "subtraction", "smooth_union", "morph", "repeat",
        "intersection_with_a_torus", "moved_torus"])
def test_unions_subtractions_blends_repetitions_and_tori_are_not_convex(node):
    assert not is_convex(node)


def test_each_primitive_belongs_to_its_top_level_object():
    objects = (plane(), intersection(box(1.0), sphere(1.3)).at(0.0, 1.0, 0.0), torus(),
               union(sphere(0.5), sphere(0.5).at(1.0, 0.0, 0.0)))
    assert object_of_primitive(objects) == [0, 1, 1, 2, 3, 3]


def test_only_convex_objects_are_left_out_and_an_intersection_by_all_its_primitives():
    objects = (plane(), intersection(box(1.0), sphere(1.3)).at(0.0, 1.0, 0.0), torus(),
               union(sphere(0.5), sphere(0.5).at(1.0, 0.0, 0.0)))
    bits = object_bits(objects, 1e-3, culling=False, skip_own=True)
    assert [(index, centre) for index, centre, _ in bits] == [(0, None), (1, None)]
    assert own_objects(objects, bits).tolist() == [0, 1, 1, -1, -1, -1]


def test_with_culling_the_bounded_objects_keep_their_spheres_and_planes_come_after():
    objects = (plane(), sphere(1.0).at(0.0, 1.0, 0.0), torus().at(3.0, 0.0, 0.0))
    bits = object_bits(objects, 1e-3, culling=True, skip_own=True)
    assert [index for index, _, _ in bits] == [1, 2, 0]
    assert [centre is None for _, centre, _ in bits] == [False, False, True]
    assert own_objects(objects, bits).tolist() == [0, 1, -1]        # the torus is kept


def test_objects_past_the_shaders_bits_are_never_left_out():
    objects = tuple(sphere(0.1).at(float(i), 0.0, 0.0) for i in range(MAX_CULLED + 4))
    bits = object_bits(objects, 1e-3, culling=False, skip_own=True)
    own = own_objects(objects, bits)
    assert len(bits) == MAX_CULLED
    assert own.tolist() == list(range(MAX_CULLED)) + [-1] * 4


def test_without_the_setting_no_object_gets_a_bit():
    assert object_bits((plane(), sphere(1.0)), 1e-3, culling=False, skip_own=False) == []


# --- no shadow changes where the object left out is convex ---------------------------------

BALL = np.array([0.0, 2.0, 0.0])
LIGHT = np.array([0.0, 6.0, 0.0])
OFFSET = 0.01

OVER_THE_FLOOR = Scene(
    camera=Camera(position=(0.0, 3.0, 8.0), look_at=(0.0, 0.0, 0.0), fov=50.0),
    render=RenderSettings(epsilon=1e-6, max_steps=512, max_distance=100.0, shadows="hard",
                          surface_offset=OFFSET, background=SolidBackground((0.0, 0.0, 0.0))),
    materials={"floor": Material(color=(0.8, 0.8, 0.8)), "ball": Material(color=(0.9, 0.1, 0.1))},
    lights=(PointLight(position=tuple(LIGHT), intensity=1.0),),
    objects=(plane(material="floor"), sphere(1.0, material="ball").at(*BALL)),
)


def test_a_floor_point_is_shadowed_exactly_where_the_segment_to_the_light_meets_the_ball():
    """Against the closed form: the segment from the (offset) floor point to the light passes
    within 1 m of the ball's centre. Points within 1 mm of the shadow's edge are not judged."""
    x = np.linspace(-3.0, 3.0, 61)
    p = np.stack(np.meshgrid(x, [0.0], x, indexing="ij"), axis=-1).reshape(-1, 3)
    origins = p + OFFSET * np.array([0.0, 1.0, 0.0])
    offset = LIGHT - origins
    distance = np.linalg.norm(offset, axis=1)
    to_light = offset / distance[:, None]
    along = np.clip(np.einsum("ij,ij->i", BALL - origins, to_light), 0, distance)
    clearance = np.linalg.norm(origins + along[:, None] * to_light - BALL, axis=1) - 1.0
    own = own_object_mask(np.zeros(len(p), dtype=np.intp), 2)   # every ray leaves the floor
    sdf = build_scene_sdf(OVER_THE_FLOOR.objects)
    visible = reference_cpu.shadows.hard_shadow(sdf, origins, to_light, distance, 512, 1e-6,
                                                100.0, objects=own)
    judged = np.abs(clearance) > 1e-3
    assert (judged & (clearance < 0)).sum() > 20 and (judged & (clearance > 0)).sum() > 1000
    np.testing.assert_array_equal(visible[judged], (clearance[judged] > 0).astype(float))


def test_leaving_out_the_floor_and_the_ball_changes_no_pixel_and_saves_steps():
    frames, counts = render_both(OVER_THE_FLOOR)
    np.testing.assert_array_equal(frames[0].color, frames[1].color)
    np.testing.assert_array_equal(frames[0].path, frames[1].path)
    assert counts[0].rays == counts[1].rays > 1000
    assert counts[1].steps < counts[0].steps / 2


def test_the_classroom_blocks_the_same_shadow_rays_in_a_third_of_the_steps():
    """The bundled classroom (a floor, three balls, two lights, a mirror bounce): every
    pixel's colour and path label (which lights a hard shadow blocked) are unchanged, and
    the shadow rays take at most two thirds of the steps (0.30 of them at 320x240)."""
    scene = rendered_scene(load_scene("classroom"))
    frames, counts = render_both(scene, precision="float32")
    np.testing.assert_array_equal(frames[0].color, frames[1].color)
    np.testing.assert_array_equal(frames[0].path, frames[1].path)
    assert counts[0].rays == counts[1].rays
    assert counts[1].steps <= 2 / 3 * counts[0].steps


# --- a non-convex object keeps shadowing itself ---------------------------------------------

def self_shadowing(obj) -> Scene:
    """``obj`` alone on a floor, lit from low on one side, so that it shadows part of
    itself; seen from the other side."""
    return Scene(
        camera=Camera(position=(-1.0, 2.5, 4.0), look_at=(0.0, 0.3, 0.0), fov=45.0),
        render=RenderSettings(shadows="hard", max_steps=512,
                              background=SolidBackground((0.0, 0.0, 0.0))),
        lights=(PointLight(position=(5.0, 1.5, 0.5), intensity=1.0),),
        objects=(plane(), obj))


@pytest.mark.parametrize("obj", [
    torus(1.0, 0.3).rotate(0.0, 0.0, 20.0).at(0.0, 0.6, 0.0),
    (box(0.8, 0.5, 0.8) - box(0.4, 0.6, 0.4).at(0.0, 0.3, 0.0)).at(0.0, 0.5, 0.0),
], ids=["torus", "block_with_a_hole"])
def test_a_non_convex_object_still_shadows_itself(obj):
    """Rays from the object itself are blocked by it (the tube's far side, the hole's wall),
    and as many with the setting as without: the object is not left out."""
    scene = self_shadowing(obj)
    frames, counts = render_both(scene)
    on_object = frames[0].object_id >= 1
    np.testing.assert_array_equal(frames[0].path, frames[1].path)
    np.testing.assert_array_equal(frames[0].color, frames[1].color)
    # The object does shadow itself: some of its own pixels are darker than with no shadows.
    unshadowed = marchlab.render(dataclasses.replace(
        scene, render=dataclasses.replace(scene.render, shadows="none")), WIDTH, HEIGHT)
    darker = on_object & np.any(frames[1].color < unshadowed.color - 0.05, axis=-1)
    assert darker.sum() >= 5
