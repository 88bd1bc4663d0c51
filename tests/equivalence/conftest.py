"""Fixtures of the equivalence suite, in the style of mitsuba3's conftest.py.

``backend`` runs a test body once for every candidate backend marchlab knows (every backend
but the NumPy reference). A backend this machine cannot run is skipped with the reason the
backend itself gives (say, no OpenGL context), never passed silently; where
``MARCHLAB_REQUIRE_BACKENDS`` names it (``make test``), its tests fail instead
(tests/required_backends.py).

References are rendered once per (scene, size, precision) and shared by every test and
backend that needs them. At the end of the run a table of PSNR and SSIM per case is printed:
they are trends to watch, not gates.
"""

from __future__ import annotations

import numpy as np
import pytest

from marchlab import render
from marchlab.render import BACKENDS, MESH_BACKENDS
from required_backends import need_backend
from scene_model.scenefile import scene_to_toml

# The sphere tracers checked against the NumPy reference; the mesh backends have their own
# cases (test_raster_equivalence.py).
CANDIDATES = [name for name in BACKENDS if name != "numpy" and name not in MESH_BACKENDS]

TRENDS: list[tuple[str, str, str, float, float]] = []   # case, backend, reference, psnr, ssim


@pytest.fixture(params=CANDIDATES)
def backend(request) -> str:
    """The name of a backend that can run here; skipped (or failed, if required) if not."""
    need_backend(request.param)
    return request.param


_REFERENCES: dict[tuple, object] = {}


def reference_frame(scene, width: int, height: int, precision: str):
    """The NumPy reference frame of ``scene``, rendered once per run (keyed by its TOML)."""
    key = (scene_to_toml(scene), width, height, precision)
    if key not in _REFERENCES:
        _REFERENCES[key] = render(scene, width, height, backend="numpy", precision=precision,
                                  path_labels=True)
    return _REFERENCES[key]


def pytest_terminal_summary(terminalreporter):
    if not TRENDS:
        return
    write = terminalreporter.write_line
    terminalreporter.section("equivalence trends (PSNR dB, SSIM; not gated)")
    width = max(len(case) for case, *_ in TRENDS)
    for case, backend, reference, psnr, ssim in sorted(TRENDS):
        write(f"{case:<{width}}  {backend:>6} vs numpy {reference}  "
              f"PSNR {psnr:7.2f}  SSIM {ssim:.5f}")


def contact_steps(events) -> list:
    """(step, kind, body, other) of each physics event, in order: what two runs of one world
    (the CPU and the GPU step) must agree on."""
    return [(int(e["step"]), str(e["kind"]), int(e["body"]), int(e["other"])) for e in events]


def position_difference(gpu, cpu) -> float:
    """The largest |x_gpu - x_cpu| (m) over two trajectories recorded at the same steps."""
    np.testing.assert_array_equal(gpu.steps, cpu.steps)
    return float(np.abs(gpu.positions.astype(np.float64) - cpu.positions).max())


SHAPE_PROGRAM = """#version 430
layout(local_size_x = 64) in;
#define real float
{shapes}
layout(std430, binding = 1) buffer Points {{ vec4 points[]; }};
layout(std430, binding = 2) buffer Results {{ vec4 results[]; }};
uniform int u_count;
void main() {{
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
    vec3 p = points[i].xyz;
{outputs}
}}
"""


def evaluate_shape_code(source, parameters, points, outputs):
    """Run the physics step's generated shape code (``source``, with its parameter block
    ``parameters``) at ``points`` (N, 3) on the GPU: each of ``outputs``, GLSL vec4
    expressions of p such as ``"vec4(shape_normal(0, p), 0.0)"``, per point. (N, K, 4)."""
    from gpu_shader.context import gl_context
    count = len(outputs)
    lines = "\n".join(f"    results[{count} * i + {k}] = {expression};"
                       for k, expression in enumerate(outputs))
    ctx = gl_context()
    with ctx:
        program = ctx.compute_shader(SHAPE_PROGRAM.format(shapes=source, outputs=lines))
        padded = np.zeros((len(points), 4), np.float32)
        padded[:, :3] = points
        buffers = [ctx.buffer(padded.tobytes()), ctx.buffer(reserve=16 * count * len(points)),
                   ctx.buffer(np.asarray(parameters, np.float32).tobytes())]
        buffers[0].bind_to_storage_buffer(1)
        buffers[1].bind_to_storage_buffer(2)
        buffers[2].bind_to_uniform_block(0)
        program["u_count"].value = len(points)
        program.run((len(points) + 63) // 64)
        results = np.frombuffer(buffers[1].read(), np.float32).reshape(-1, count, 4)
        for buffer in buffers + [program]:
            buffer.release()
    return results
