"""The GPU physics step's reads through buffer textures (gpu_shader/buffer_texture.py,
TEXEL_READS in glsl/physics_step.glsl) give the very steps of its storage-buffer reads.

The texel reads are an optimisation only (three times as fast per word on llvmpipe): the
same words of the same buffers reach the same arithmetic. So a pile stepped each way must be
equal to the bit, events included, on any GPU, and a buffer texture must hand a shader every
32-bit pattern unchanged, the floats that are not plain numbers (subnormals, -0, NaN with a
payload) included.
"""

from __future__ import annotations

import numpy as np
import pytest

import physics
from marchlab.colliders import primitive_coefficients, shape_objects
from marchlab.simulation import build_world
from scene_model.builder import Body, Material, PhysicsSettings, Scene, box, plane
from sphere_piles import box_pile


@pytest.fixture(autouse=True)
def _needs_buffer_textures(gpu):
    from gpu_shader import buffer_texture
    from gpu_shader.context import gl_context
    if not buffer_texture.available(gl_context()):
        pytest.skip("buffer textures cannot be made on this context")


def stepper(world, **options):
    from gpu_shader.physics import GpuStepper            # needs moderngl
    return GpuStepper(world, **options)


def _state(world):
    return {"position": world.position, "velocity": world.velocity,
            "spin": world.angular_velocity, "orientation": world.orientation,
            "active": world.active}


def _assert_same_steps(runs):
    (state_a, events_a), (state_b, events_b) = runs
    for name in state_a:
        np.testing.assert_array_equal(state_a[name], state_b[name], err_msg=name)
    assert len(events_a) > 0
    np.testing.assert_array_equal(events_a, events_b)


def test_texel_reads_step_a_pile_bit_for_bit_as_storage_buffer_reads():
    runs = []
    for texel_reads in (True, False):
        world = box_pile(300, height=0.5)        # dense: it piles up within 40 steps
        step = stepper(world, texel_reads=texel_reads)
        assert step.texel_reads is texel_reads
        step(40)
        runs.append((_state(world), world.events))
        step.release()
    _assert_same_steps(runs)


def test_texel_reads_step_balls_among_shapes_bit_for_bit_as_storage_buffer_reads():
    # shapes bring the contacts' slots, landing faces and the continuous test's reads
    cavity = box(1, 0.5, 1) - box(0.5, 0.5, 0.5).at(0, 0.5, 0)
    balls = [Body(position=(0.1 * k - 0.3, 1.0 + 0.15 * k, 0.05 * k), radius=0.06,
                  velocity=(0.4, 0, -0.3), restitution=0.4) for k in range(8)]
    scene = Scene(materials={"default": Material()},
                  objects=(plane(), cavity, box(0.3, 0.2, 0.3).at(1.2, 0.2, 0)),
                  physics=PhysicsSettings(solver="simultaneous", dt=1 / 120),
                  bodies=(*balls, Body(position=(1.2, 0.8, 0.02), radius=0.08, restitution=0.2)))
    runs = []
    for texel_reads in (True, False):
        world = build_world(scene, np.float32)
        nodes = shape_objects(scene)
        step = stepper(world, shape_nodes=nodes, texel_reads=texel_reads,
                       shape_surfaces=[primitive_coefficients(node, scene, scene.physics)
                                       for node in nodes])
        step(120)
        runs.append((_state(world), world.events))
        step.release()
    _assert_same_steps(runs)


def test_buffer_texture_hands_a_shader_every_32_bit_pattern_unchanged():
    special = np.array([0x00000000, 0x80000000, 0x00000001, 0x007FFFFF, 0x80000001,
                        0x7F800000, 0xFF800000, 0x7FC00000, 0x7F800001, 0x7FA5A5A5,
                        0xFFFFFFFF, 0x3F800000, 0x12345678, 0x7FFFFFFF, 0xDEADBEEF,
                        0x00800000], np.uint32)
    rng = np.random.default_rng(7)
    words = np.concatenate([special, rng.integers(0, 2 ** 32, 48, dtype=np.uint32)])
    from gpu_shader import buffer_texture
    from gpu_shader.context import gl_context
    ctx = gl_context()
    with ctx:
        source = ctx.buffer(words.tobytes())
        as_ints, as_floats = (ctx.buffer(reserve=words.nbytes) for _ in range(2))
        program = ctx.compute_shader("""#version 430
            layout(local_size_x = 1) in;
            layout(binding = 16) uniform isamplerBuffer texels;
            layout(std430, binding = 0) buffer Ints { ivec4 ints[]; };
            layout(std430, binding = 1) buffer Floats { vec4 floats[]; };
            void main() {
                int k = int(gl_GlobalInvocationID.x);
                ints[k] = texelFetch(texels, k);
                floats[k] = intBitsToFloat(texelFetch(texels, k));  // as the step reads floats
            }""")
        texture = buffer_texture.BufferTexture(source)
        texture.use(16)
        as_ints.bind_to_storage_buffer(0)
        as_floats.bind_to_storage_buffer(1)
        program.run(len(words) // 4)
        ctx.finish()
        ints = np.frombuffer(as_ints.read(), np.uint32)
        floats = np.frombuffer(as_floats.read(), np.uint32)
        for gl_object in (texture, program, source, as_ints, as_floats):
            gl_object.release()
    np.testing.assert_array_equal(ints, words)
    np.testing.assert_array_equal(floats, words)


def test_stepper_reads_storage_buffers_where_buffer_textures_cannot_be_made(monkeypatch):
    from gpu_shader import buffer_texture
    monkeypatch.setattr(buffer_texture, "available", lambda ctx: False)
    step = stepper(box_pile(20))
    assert step.texel_reads is False and step.texels == {}
    step(2)
    step.release()
    with pytest.raises(physics.PhysicsError, match="texel_reads: this context cannot") as error:
        stepper(box_pile(20), texel_reads=True)
    assert "\n" not in str(error.value)
