"""The packet program renders the frames the one-ray program renders.

The opencl backend runs the packet program: LANES pixels of a row per work-item, as
vectors, its functions derived from the one-ray program's (gpu_shader/vectorise.py). The
one-ray program is the line-by-line twin of the GLSL shader, already held to the NumPy
reference by the equivalence suite. Lane by lane the packet program does the same
operations in the same order, so on every equivalence case (each bundled scene and each
feature) both must agree:

- to the bit in the hit mask, step counts, object ids, path labels, depths and normals: the
  march, the SDF and the normal are exact IEEE arithmetic and square roots;
- within COLOR_DIFFERENCE in colour. Fog calls exp, and PoCL's vector exp rounds
  differently from its scalar one by up to one ulp (tests/opencl/test_packet_shading.py; its
  vector pow is not used: glsl/packet.cl, `power`). The fog colour then moves by a few ulps
  of the working precision, which after the float32 rounding of Frame.color is at most one
  float32 ulp of a value below 2: 2**-23. Measured over all cases: 5.96e-8 in float32 (fog,
  classroom, repetition), 0 in float64.

Widths that are not a multiple of LANES check that the last packet of a row, part of which
lies outside the image, writes its pixels and nothing else.
"""

from __future__ import annotations

import numpy as np
import pytest

from gpu_shader.dialects import PACKET_LANES
from gpu_shader import opencl
from tests.equivalence.cases import all_cases

CASES = all_cases()
COLOR_DIFFERENCE = 2.0 ** -23


def assert_same_frame(packets, one_ray, label: str):
    for name in ("hit", "steps", "object_id", "path", "depth", "normal"):
        np.testing.assert_array_equal(getattr(packets, name), getattr(one_ray, name),
                                      err_msg=f"{label}: {name}")
    difference = np.abs(packets.color.astype(np.float64) - one_ray.color)
    assert not np.isnan(packets.color).any(), f"{label}: NaN in the colour"
    assert difference.max() <= COLOR_DIFFERENCE, (
        f"{label}: colour differs by {difference.max():.3g} at "
        f"{np.argwhere(difference == difference.max())[0].tolist()} (bound {COLOR_DIFFERENCE:.3g})")


@pytest.mark.parametrize("precision", ["float32", "float64"])
@pytest.mark.parametrize("name, scene, size", CASES, ids=[c[0] for c in CASES])
def test_packet_program_renders_the_one_ray_frame(opencl_device, name, scene, size,
                                                  precision):
    if precision == "float64" and not opencl_device.fp64:
        pytest.skip(f"{opencl_device.label} has no float64")
    width, height = size
    packets = opencl.render(scene, width, height, precision, path_labels=True)
    one_ray = opencl.render(scene, width, height, precision, packets=False, path_labels=True)
    # (a feature case shows some background, but not from inside a glass block)
    assert (packets.hit.any() and not packets.hit.all() or name.startswith("scene:")
            or name.endswith("camera_inside"))
    assert packets.path is not None
    assert_same_frame(packets, one_ray, f"{name} {precision}")


@pytest.mark.parametrize("width", [PACKET_LANES - 3, 2 * PACKET_LANES + 5, 1])
def test_packets_cut_by_the_right_edge_write_exactly_the_image(opencl_device, width):
    name, scene, _ = CASES[0]
    packets = opencl.render(scene, width, 9, "float32", path_labels=True)
    one_ray = opencl.render(scene, width, 9, "float32", packets=False, path_labels=True)
    assert packets.color.shape == (9, width, 3)
    assert_same_frame(packets, one_ray, f"{name} at {width}x9")
