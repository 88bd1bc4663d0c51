"""The OpenCL backend: the reference algorithm compiled, on a CPU OpenCL device (PoCL).

The kernel is generated from the same building blocks as the GLSL shader, in the OpenCL C
dialect (`gpu_shader.dialects`), in float32 or float64. Only what the scene uses is emitted;
the parameters are a buffer, so programs are cached by their text (the scene's structure).

Device selection has to work on real machines: an OpenCL platform can be installed and still
unable to build a kernel (the PoCL wheel from PyPI does not know some CPUs: "unknown target
CPU 'generic'"). So every platform/device is tried with a tiny kernel and the first that
builds and runs it is used; ``MARCHLAB_OPENCL_DEVICE`` picks one by platform:device index
("0:1"), by its position in the list of all devices ("1"), or by part of its name ("pocl").
The choice is made once per process.
"""

from __future__ import annotations

import os
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.frame import Frame
from scene_model.scene import Scene

from .dialects import PACKET_LANES
from .generate import generate
from .planes import frame_from_planes, row_bands

DEVICE_VARIABLE = "MARCHLAB_OPENCL_DEVICE"
INSTALL_HINT = ("install a working OpenCL CPU driver (Debian/Ubuntu: apt install "
                "pocl-opencl-icd; `make demo` does this)")
PROGRAM_CACHE_SIZE = 32
WORK_GROUP = (16, 4)           # pixels per work-group (columns, rows); see docs/performance.md
PACKET_WORK_GROUP = (1, 4)     # packets per work-group (columns, rows)

# The smallest kernel that proves a device can compile and run code.
PROBE = """
__kernel void probe(__global float* x)
{
    x[get_global_id(0)] = 2.0f * x[get_global_id(0)];
}
"""


@dataclass
class Device:
    """A working OpenCL device, its context and queue, and the programs built on it."""
    label: str                 # "platform: device"
    cl_device: object
    context: object
    queue: object
    fp64: bool
    programs: OrderedDict = field(default_factory=OrderedDict)


def check() -> None:
    """Raise MarchlabError, saying what is missing, if this backend cannot run here."""
    device()


def device_name() -> str:
    """The OpenCL platform and device the backend computes on."""
    return device().label


_chosen: Device | MarchlabError | None = None


def device() -> Device:
    """The device this process renders on, chosen on first use (a failure is kept too)."""
    global _chosen
    if _chosen is None:
        try:
            _chosen = choose_device(os.environ.get(DEVICE_VARIABLE, ""))
        except MarchlabError as err:
            _chosen = err
    if isinstance(_chosen, MarchlabError):
        raise _chosen
    return _chosen


def _import_pyopencl():
    try:
        import pyopencl
    except ImportError:
        raise MarchlabError("the opencl backend needs pyopencl: pip install 'marchlab[opencl]' "
                            "(or run `make demo`)") from None
    return pyopencl


def candidates(cl) -> list[tuple[str, str, object]]:
    """Every (index "p:d", "platform: device" label, device) this machine lists."""
    try:
        platforms = cl.get_platforms()
    except Exception:          # no ICD loader or no platform registered
        platforms = []
    found = []
    for p, platform in enumerate(platforms):
        try:
            devices = platform.get_devices()
        except Exception:
            devices = []
        for d, dev in enumerate(devices):
            found.append((f"{p}:{d}", f"{platform.name.strip()}: {dev.name.strip()}", dev))
    return found


def choose_device(wanted: str = "") -> Device:
    """The first device that builds and runs `PROBE` (only those matching ``wanted``)."""
    cl = _import_pyopencl()
    found = candidates(cl)
    if not found:
        raise MarchlabError(f"no OpenCL platform found; {INSTALL_HINT}")
    if wanted:
        if wanted.isdigit():     # a position in the list of every device
            matching = found[int(wanted):int(wanted) + 1]
        else:
            matching = [c for c in found if wanted == c[0] or wanted.lower() in c[1].lower()]
        if not matching:
            listed = "; ".join(f"{index} {label}" for index, label, _ in found)
            raise MarchlabError(f"{DEVICE_VARIABLE}={wanted!r} matches no OpenCL device "
                                f"(there are: {listed})")
        found = matching
    tried = []
    for _, label, dev in found:
        problem = _probe(cl, dev)
        if problem is None:
            context = cl.Context([dev])
            return Device(label, dev, context, cl.CommandQueue(context),
                          fp64="cl_khr_fp64" in dev.extensions)
        tried.append(f"{label} ({problem})")
    raise MarchlabError(f"no OpenCL device could build a kernel; tried {'; '.join(tried)}. "
                        + INSTALL_HINT[0].upper() + INSTALL_HINT[1:])


def _probe(cl, dev) -> str | None:
    """None if ``dev`` builds and runs `PROBE` correctly, else why not (one line)."""
    try:
        context = cl.Context([dev])
        queue = cl.CommandQueue(context)
        program = cl.Program(context, PROBE).build()
        values = np.arange(4, dtype=np.float32)
        buffer = cl.Buffer(context, cl.mem_flags.READ_WRITE | cl.mem_flags.COPY_HOST_PTR,
                           hostbuf=values)
        program.probe(queue, (4,), None, buffer)
        out = np.empty_like(values)
        cl.enqueue_copy(queue, out, buffer)
        queue.finish()
    except Exception as err:   # a driver's failure can be any of pyopencl's errors
        return _first_line(err)
    if not np.array_equal(out, 2 * values):
        return "the test kernel computed wrong values"
    return None


def _first_line(err: Exception) -> str:
    """The most telling line of a driver error (build logs run to many lines)."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    for line in lines:
        if "error" in line.lower() and "clBuildProgram failed" not in line:
            return line[:200]
    return (lines[0] if lines else type(err).__name__)[:200]


def render(scene: Scene, width: int, height: int, precision: str = "float32",
           progress: Callable[[int, int], None] | None = None,
           packets: bool = True, path_labels: bool = False) -> Frame:
    """Render ``scene`` with the OpenCL kernel (see `marchlab.render`).

    ``packets`` (the default) runs the packet program, LANES pixels of a row per work-item
    computed as vectors (`gpu_shader.packets`), which is several times faster on a
    CPU; False runs the one-ray program, the line-by-line twin of the GLSL shader. Both give
    the same frame (tests/opencl/test_packet_program.py).
    """
    dev = device()
    if precision == "float64" and not dev.fp64:
        raise MarchlabError(f"the OpenCL device {dev.label} has no float64 (cl_khr_fp64); "
                            "use --precision float32")
    cl = _import_pyopencl()
    program = generate(scene, width, height, precision=precision, path_labels=path_labels,
                       dialect="opencl-packets" if packets else "opencl")
    dtype = np.dtype(np.float32 if precision == "float32" else np.float64)
    kernels = _kernels(cl, dev, program.source, precision)
    kernel = kernels["render"]

    flags = cl.mem_flags
    parameters = cl.Buffer(dev.context, flags.READ_ONLY | flags.COPY_HOST_PTR,
                           hostbuf=parameter_buffer(program, dtype))
    # colour and hit in float32 (the Frame's), normal and depth in the precision, counts in
    # int32 (glsl/main.cl)
    planes = [np.empty((height, width, 4), t) for t in (np.float32, dtype, np.int32)]
    outputs = [cl.Buffer(dev.context, flags.WRITE_ONLY, plane.nbytes) for plane in planes]
    local = PACKET_WORK_GROUP if packets else WORK_GROUP
    if program.prepass_tile:
        # The cone pre-pass first: one work-item per tile (per LANES tiles of a row in the
        # packet program), into the buffer of tile starts that the frame's kernel reads.
        tile_columns, tile_rows = program.tiles(width, height)
        starts = cl.Buffer(dev.context, flags.READ_WRITE,
                           tile_columns * tile_rows * dtype.itemsize)
        prepass = kernels["cone_prepass"]
        prepass.set_args(parameters, starts)
        items = -(-tile_columns // PACKET_LANES) if packets else tile_columns
        cl.enqueue_nd_range_kernel(dev.queue, prepass, (_round_up(items, local[0]),
                                                        _round_up(tile_rows, local[1])), local)
        outputs.append(starts)
    kernel.set_args(parameters, *outputs)
    columns = -(-width // PACKET_LANES) if packets else width     # work-items per row
    for start, stop in row_bands(height, progress):
        rows = stop - start
        global_size = (_round_up(columns, local[0]), _round_up(rows, local[1]))
        cl.enqueue_nd_range_kernel(dev.queue, kernel, global_size, local,
                                   global_work_offset=(0, start))
        if progress is not None:
            dev.queue.finish()
            progress(stop * width, height * width)
    for plane, buffer in zip(planes, outputs):
        cl.enqueue_copy(dev.queue, plane, buffer)
    dev.queue.finish()
    frame = frame_from_planes(planes, scene, "opencl", precision)
    if not path_labels:
        frame.path = None
    return frame


def parameter_buffer(program, dtype) -> np.ndarray:
    """(N, 4) ``dtype``: what the kernel's P holds: the parameter block, then the texture
    atlas's texels, a row each (glsl/texture.glsl). In the one buffer, what already passes
    P on to every function and the packet program's gather() serve the texels too."""
    rows = [np.asarray(program.parameters, dtype)]
    if program.texels is not None:
        rows.append(program.texels.reshape(-1, 4).astype(dtype))
    return np.ascontiguousarray(np.concatenate(rows))


def _kernels(cl, dev: Device, source: str, precision: str) -> dict:
    """The kernels of ``source`` by name (``render``, and ``cone_prepass`` with the pre-pass),
    built once per text and precision."""
    key = (source, precision)
    if key in dev.programs:
        dev.programs.move_to_end(key)
        return dev.programs[key]
    try:
        # A build that succeeds may still log remarks (PoCL's "AVX vector argument ... changes
        # the ABI", hundreds of lines); pyopencl raises them as a CompilerWarning. They say
        # nothing a user can act on, so they are dropped: a failed build still says why.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", cl.CompilerWarning)
            built = cl.Program(dev.context, source).build(
                options=build_options(cl, dev, precision))
    except Exception as err:
        raise MarchlabError(f"the generated OpenCL kernel failed to build on {dev.label}: "
                            f"{_first_line(err)} (`marchlab shader SCENE --dialect opencl "
                            f"--numbered` prints it)") from None
    kernels = {k.function_name: k for k in built.all_kernels()}
    dev.programs[key] = kernels
    if len(dev.programs) > PROGRAM_CACHE_SIZE:
        dev.programs.popitem(last=False)
    return kernels


def build_options(cl, dev: Device, precision: str) -> list[str]:
    """Compiler options: exact IEEE arithmetic, never -cl-fast-relaxed-math.

    In float32, unsuffixed literals (``0.5``) are single precision, as in GLSL, and divisions
    and square roots are correctly rounded where the device can (OpenCL allows them 2.5-3
    ulp otherwise; NumPy rounds them correctly).

    ``-w`` (OpenCL 1.2, section 5.8.4.4) silences the compiler's warnings: PoCL's clang would
    otherwise print "186 warnings generated." straight to the terminal for remarks about its
    own vector ABI, which no user can act on. Errors are still reported.
    """
    options = ["-w"]
    if precision == "float32":
        options.append("-cl-single-precision-constant")
        rounded = cl.device_fp_config.CORRECTLY_ROUNDED_DIVIDE_SQRT
        if dev.cl_device.single_fp_config & rounded:
            options.append("-cl-fp32-correctly-rounded-divide-sqrt")
    return options


def _round_up(n: int, multiple: int) -> int:
    return -(-n // multiple) * multiple
