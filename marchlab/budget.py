"""Budgets: how much work a job may start before someone has to ask for more.

Every long job estimates its work before it starts, at worst, from numbers a user chose, and
is refused beyond a limit here with one line that says how to lift it (``--allow-large`` on
the command line, ``allow_large=True`` from Python). A limit is not a promise of speed: it
catches the typing slip (``--fps 1e9``, ``--seconds 1e9``, ``--size 10000x10000``) before it
becomes an hour of computing or a machine out of memory.

========================  ==============================================  ===================
the work                  estimated as                                    limit
========================  ==============================================  ===================
an image's memory         width x height pixels                           `MAX_PIXELS`
                                                                          (scene_model.camera)
rendering                 pixels x max_steps x rays per pixel, summed     `MAX_RAY_STEPS`
                          over the frames of the job (`ray_steps`)
an animation's length     seconds x fps frames                            `MAX_FRAMES`
an animation's memory     frames x pixels x `ANIMATION_BYTES_PER_PIXEL`   `MAX_ANIMATION_BYTES`
physics                   steps (seconds / dt) x bodies                   `MAX_BODY_STEPS`
a benchmark               its renders' ray steps, as for rendering        `MAX_BENCH_RAY_STEPS`
the Embree ground truth   resolution^3 marching-cubes cells per part      `MAX_MESH_CELLS`
========================  ==============================================  ===================

"Ray steps" count SDF evaluations as if every ray used all ``max_steps``: the NumPy reference
makes about 2.5e7 a second on one core, so `MAX_RAY_STEPS` is about half an hour of it at
worst; a typical frame needs a tenth of its worst case or less (most rays stop within 30
steps), and the GPU is a hundred times faster.
"""

from __future__ import annotations

from scene_model.camera import MAX_IMAGE_BYTES, image_size_problem
from scene_model.errors import MarchlabError
from scene_model.sampling import rays_per_pixel as primary_rays
from scene_model.scene import Scene

MAX_RAY_STEPS = 50_000_000_000          # classroom at 640x480 is 4.7e8, at 3840x2160 1.3e10
MAX_FRAMES = 10_000                     # 5.5 minutes at 30 frames per second
ANIMATION_BYTES_PER_PIXEL = 8           # the 8-bit frames kept until encoded, and the encoder's
MAX_ANIMATION_BYTES = MAX_IMAGE_BYTES   # copies of them
MAX_BODY_STEPS = 5_000_000              # bounce (6 bodies) for 58 minutes at dt = 1/240 s
MAX_BENCH_RAY_STEPS = 1_000_000_000_000  # `marchlab bench accuracy` at its defaults: 4.7e10
MAX_MESH_CELLS = 2_000_000_000          # 15 parts at --resolution 512, about 3 minutes here

PYTHON = "pass allow_large=True to go ahead"
COMMAND_LINE = "add --allow-large to go ahead"


class BudgetError(MarchlabError):
    """A job whose estimated work is beyond its limit (a user error: one line, exit 2)."""


def rays_per_pixel(scene: Scene) -> int:
    """The most rays one pixel marches: each of its primary rays (one, or with anti-aliasing
    `scene_model.sampling.rays_per_pixel`) and their mirror bounces, and from each of those
    a shadow ray toward every light when the scene has shadows."""
    settings = scene.render
    shadow_rays = len(scene.lights) if settings.shadows != "none" else 0
    return (primary_rays(settings.samples) * (1 + settings.reflection_depth)
            * (1 + shadow_rays))


def ray_steps(scene: Scene, width: int, height: int, frames: int = 1) -> int:
    """The SDF evaluations of ``frames`` renders of ``scene`` at ``width`` x ``height`` if
    every ray used all its ``max_steps``: the worst case."""
    return frames * width * height * scene.render.max_steps * rays_per_pixel(scene)


def check(amount: int, limit: int, what: str, unit: str, allow_large: bool = False,
          lift: str = PYTHON) -> None:
    """Raise `BudgetError` if ``amount`` (of ``unit``) is over ``limit``, unless
    ``allow_large``.

    ``what`` names the job, e.g. ``"rendering 640x480 pixels x 256 steps x 6 rays"``;
    ``lift`` says how to go ahead anyway (`PYTHON` or `COMMAND_LINE`).
    """
    if amount > limit and not allow_large:
        raise BudgetError(f"{what}: {count(amount)} {unit} is more than the limit of "
                          f"{count(limit)}; {lift}")


def check_image(width: int, height: int, allow_large: bool = False, lift: str = PYTHON) -> None:
    """The image-memory limit of `scene_model.camera.check_image_size`, worded for ``lift``."""
    problem = image_size_problem(width, height)
    if problem and not allow_large:
        raise BudgetError(f"{problem}; {lift}")


def check_render(scene: Scene, width: int, height: int, frames: int = 1,
                 allow_large: bool = False, lift: str = PYTHON) -> None:
    """Refuse ``frames`` renders of ``scene`` beyond the image or the ray-step budget."""
    check_image(width, height, allow_large, lift)
    what = (f"rendering {width}x{height} pixels x {scene.render.max_steps:,} steps x "
            f"{rays_per_pixel(scene)} rays" + (f" x {count(frames)} frames" if frames != 1 else ""))
    check(ray_steps(scene, width, height, frames), MAX_RAY_STEPS, what, "ray steps at worst",
          allow_large, lift)


def check_animation(scene: Scene, frames: int, steps: int, width: int, height: int,
                    allow_large: bool = False, lift: str = PYTHON) -> None:
    """Refuse an animation of ``frames`` frames of ``width`` x ``height`` from ``steps``
    physics steps of the scene's bodies beyond any of its budgets: frames, physics, the
    frames' memory and their rendering."""
    check(frames, MAX_FRAMES, "the animation", "frames", allow_large, lift)
    check_physics(steps, len(scene.bodies), allow_large, lift)
    check(frames * width * height * ANIMATION_BYTES_PER_PIXEL, MAX_ANIMATION_BYTES,
          f"keeping {count(frames)} frames of {width}x{height} until they are encoded",
          "bytes", allow_large, lift)
    check_render(scene, width, height, frames, allow_large, lift)


def check_physics(steps: int, bodies: int, allow_large: bool = False, lift: str = PYTHON) -> None:
    """Refuse ``steps`` physics steps of ``bodies`` bodies beyond `MAX_BODY_STEPS`."""
    check(steps * max(bodies, 1), MAX_BODY_STEPS,
          f"stepping {bodies:,} bodies {count(steps)} times", "body steps", allow_large, lift)


def count(n: int | float) -> str:
    """A count for a message: ``12,345`` when short, ``6.14e+10`` when long (even for an
    integer too large for a float)."""
    if n < 10_000_000:
        return f"{n:,}"
    digits = str(int(n))
    return f"{digits[0]}.{digits[1:3]}e+{len(digits) - 1:02d}"


def check_truth(scene: Scene, resolution: int, allow_large: bool = False,
                lift: str = PYTHON) -> None:
    """Refuse an Embree ground truth of ``scene`` whose meshing is beyond `MAX_MESH_CELLS`:
    every part but a plane counted as marched at ``resolution`` cells a side (at worst:
    spheres and boxes are tessellated more cheaply)."""
    from reference_cpu.truth.parts import scene_parts
    from scene_model.scene import rendered_scene
    from scene_model.shapes import Plane
    meshed = sum(not isinstance(part.leaf, Plane)
                 for part in scene_parts(rendered_scene(scene).objects))
    check(meshed * resolution ** 3, MAX_MESH_CELLS,
          f"meshing {meshed} parts at {resolution} cells a side", "marching-cubes cells at worst",
          allow_large, lift)
