"""Every backend samples an environment map as the NumPy reference does, checked where the
answer is known exactly: one colour, the face a tie picks, and a linear ramp.

The images come as .npy files in tmp_path (tests/test_environment_files.py checks reading
them). The equivalence suite (cases.py: background_cubemap, mirror_cubemap, mirror_equirect
and the bundled scene `environment`) holds the backends to the reference on the studio too.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import render
from required_backends import need_backend
from scene_model.builder import Camera, RenderSettings, Scene
from scene_model.camera import camera_rays
from scene_model.scene import CubeMapBackground, EquirectBackground

# A colour per cube face, +x, -x, +y, -y, +z, -z.
FACE_COLOURS = np.float32([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1]])


@pytest.fixture(params=["numpy", "gpu", "opencl"])
def any_backend(request) -> str:
    if request.param != "numpy":
        need_backend(request.param)
    return request.param


def cube_map(folder, colours) -> CubeMapBackground:
    paths = []
    for k, colour in enumerate(colours):
        paths.append(str(folder / f"face{k}.npy"))
        np.save(paths[-1], np.full((4, 4, 3), colour, np.float32))
    return CubeMapBackground(tuple(paths))


def empty_scene(background, look_at=(0.0, 0.0, -1.0), fov=60.0) -> Scene:
    """Nothing but the background, seen from the origin."""
    return Scene(camera=Camera(position=(0.0, 0.0, 0.0), look_at=look_at, fov=fov),
                 render=RenderSettings(background=background), objects=())


def test_an_environment_of_one_colour_is_that_colour_on_every_miss_to_the_bit(any_backend,
                                                                            tmp_path):
    colour = np.float32([0.2, 0.45, 0.7])
    scene = empty_scene(cube_map(tmp_path, [colour] * 6), look_at=(0.3, 0.8, -0.5), fov=150.0)
    frame = render(scene, 32, 24, backend=any_backend, precision="float32")
    assert not frame.hit.any()
    assert (frame.color == colour).all()


@pytest.mark.parametrize("look_at, face", [
    ((1, 1, 0), 0), ((-1, 1, 0), 1), ((1, 0, 1), 0), ((0, 1, 1), 2), ((0, -1, -1), 3),
    ((0, 1, -1), 2), ((1, 1, 1), 0), ((-1, -1, -1), 1)])
def test_a_ray_between_two_faces_sees_x_before_y_before_z_on_every_backend(any_backend, tmp_path,
                                                                          look_at, face):
    """The centre pixel of an odd-sized image looks exactly along the camera's forward
    direction, whose components tie here: each backend must pick the documented face."""
    scene = empty_scene(cube_map(tmp_path, FACE_COLOURS), look_at=look_at)
    frame = render(scene, 5, 3, backend=any_backend, precision="float32")
    np.testing.assert_array_equal(frame.color[1, 2], FACE_COLOURS[face])


def test_a_panorama_of_a_linear_ramp_shows_the_ramp_on_every_backend(any_backend, tmp_path):
    """Texel (j, i) = (i / W, j / H, 1/2): bilinear filtering gives ((u W - 1/2) / W,
    (v H - 1/2) / H, 1/2) between the texel centres, with u, v of the ray's direction
    (reference_cpu.environment.equirect_uv) computed here in float64. The float32 rays,
    atan2 and texels of a backend leave 1e-5 at most."""
    height, width = 32, 64
    j, i = np.indices((height, width))
    np.save(tmp_path / "ramp.npy",
            np.stack([i / width, j / height, np.full(i.shape, 0.5)], axis=-1).astype(np.float32))
    scene = empty_scene(EquirectBackground(str(tmp_path / "ramp.npy")), fov=80.0)
    frame = render(scene, 40, 30, backend=any_backend, precision="float32")
    _, d = camera_rays(scene.camera, 40, 30, np.float64)
    u = np.arctan2(d[..., 0], -d[..., 2]) / (2 * np.pi) + 0.5
    v = np.arccos(d[..., 1]) / np.pi
    expected = np.stack([(u * width - 0.5) / width, (v * height - 0.5) / height,
                         np.full(u.shape, 0.5)], axis=-1)
    np.testing.assert_allclose(frame.color, expected, rtol=0, atol=1e-5)
