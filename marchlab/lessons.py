"""Plumbing for the lesson notebooks: showing source, drawing fields, varying scenes, timing.

A lesson imports what it needs from here (``from marchlab.lessons import show_source``)
instead of defining it again in every notebook. Nothing here is the subject of a lesson: the
code a lesson explains is the toolkit's own, shown with `show_source`, and a function a lesson
builds up and explains stays in its notebook. matplotlib and IPython come with the
``lessons`` extra, so they are imported inside the functions that draw or display.
"""

from __future__ import annotations

import dataclasses
import inspect
import textwrap
import time

import numpy as np

from reference_cpu.scene_sdf import build_scene_sdf
from scene_model.frame import Frame
from scene_model.scene import Scene

from .render import fastest_backend, render

SAFE_STEPS = 4096      # max_steps of a converged picture: enough for every ray to finish
VISIBLE_LEVELS = 8     # an 8-bit colour further off than this is a visible artefact


# --- Code and distance fields --------------------------------------------------------------

def show_source(*functions) -> None:
    """Display the source of toolkit functions, highlighted, one block each.

    The lesson shows the real code (`inspect.getsource`, a method's moved to the left margin),
    so prose and code cannot drift apart.

    Parameters
    ----------
    *functions
        Functions, classes or methods of the toolkit.
    """
    from IPython.display import Code, display
    for function in functions:
        display(Code(textwrap.dedent(inspect.getsource(function)), language="python"))


def distance_field(*nodes):
    """The signed distance function of the union of builder nodes, without the object ids.

    Parameters
    ----------
    *nodes
        Shapes made with `scene_model.builder` (``sphere(1.0).at(0, 1, 0)``, ...).

    Returns
    -------
    callable
        ``f(p)`` for ``p : (N, 3)`` returns the ``(N,)`` distances.
    """
    sdf = build_scene_sdf(list(nodes))
    return lambda p: sdf(p)[0]


def slice_z0(f, xlim=(-2.0, 2.0), ylim=(-1.5, 1.5), n=241):
    """A distance function sampled on an n x n grid of the plane z = 0.

    Parameters
    ----------
    f : callable
        ``f(p)`` for ``p : (N, 3)`` returns ``(N,)`` distances (see `distance_field`).
    xlim, ylim : (2,) tuple of float
        The grid's extent along x and y.
    n : int
        Samples along each side.

    Returns
    -------
    x, y, d : (n, n) ndarray
        The grid's coordinates and f there; row i has y = y[i, 0].
    """
    x, y = np.meshgrid(np.linspace(*xlim, n), np.linspace(*ylim, n))
    p = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    return x, y, np.asarray(f(p)).reshape(x.shape)


def draw_field(ax, x, y, d, *, spacing=0.2, lines=True, title=None):
    """Draw a slice of a distance field: blue inside, red outside, the surface in black.

    Parameters
    ----------
    ax : matplotlib Axes
    x, y, d : (n, n) ndarray
        A slice, as `slice_z0` returns it.
    spacing : float
        Thin level lines at every multiple of ``spacing``, inside and outside.
    lines : bool
        Whether to draw the thin level lines (the surface d = 0 is always drawn).
    title : str, optional

    Returns
    -------
    matplotlib QuadContourSet
        The filled contours, for a colour bar.
    """
    from matplotlib.colors import TwoSlopeNorm
    norm = TwoSlopeNorm(0, min(d.min(), -1e-3), max(d.max(), 1e-3))
    filled = ax.contourf(x, y, d, levels=40, cmap="RdBu_r", norm=norm)
    if lines:
        levels = spacing * np.arange(np.ceil(d.min() / spacing), np.floor(d.max() / spacing) + 1)
        ax.contour(x, y, d, levels=levels[levels != 0], colors="k", linewidths=0.4, alpha=0.5)
    ax.contour(x, y, d, levels=[0], colors="k", linewidths=2)
    ax.set_aspect("equal")
    if title is not None:
        ax.set_title(title, fontsize=10)
    return filled


# --- Variations of a scene (scenes are frozen dataclasses) -----------------------------------

def with_settings(scene: Scene, **settings) -> Scene:
    """A copy of ``scene`` with some render settings changed, e.g. ``shadows="hard"``."""
    return dataclasses.replace(scene, render=dataclasses.replace(scene.render, **settings))


def with_materials(scene: Scene, **fields) -> Scene:
    """A copy of ``scene`` with some fields of every material changed.

    Each value is the new value (``kd=0, ks=0``) or a function of the material that returns
    it (``shininess=lambda m: 4 * m.shininess``).
    """
    def changed(material):
        return dataclasses.replace(material, **{
            name: value(material) if callable(value) else value for name, value in fields.items()})
    return dataclasses.replace(scene, materials={name: changed(m)
                                                 for name, m in scene.materials.items()})


# --- Pictures ------------------------------------------------------------------------------

def show_images(images: dict, panel_width=3.6):
    """Show pictures side by side, each under its title, without axes.

    Parameters
    ----------
    images : dict of str to (H, W, 3) or (H, W) ndarray
        Title and picture of each panel, left to right.
    panel_width : float
        Width of one panel, inches.
    """
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(images), figsize=(panel_width * len(images),
                                                      0.8 * panel_width), squeeze=False)
    for ax, (title, image) in zip(axes[0], images.items()):
        ax.imshow(image)
        ax.set_title(title, fontsize=10)
        ax.axis("off")
    fig.tight_layout()
    plt.show()


def show_renders(scenes: dict, width=160, height=120, backend=None) -> dict[str, Frame]:
    """Render scenes and show them side by side (`show_images`); return the frames.

    Parameters
    ----------
    scenes : dict of str to Scene
        Title and scene of each panel.
    width, height : int
        Pixels of each picture.
    backend : str, optional
        The backend to render with; the fastest that runs here by default
        (`marchlab.render.fastest_backend`).

    Returns
    -------
    dict of str to Frame
        The frame of each title.
    """
    backend = backend or fastest_backend()
    frames = {title: render(scene, width, height, backend=backend)
              for title, scene in scenes.items()}
    show_images({title: frame.image() for title, frame in frames.items()})
    return frames


# --- Measuring the cost and the artefacts of a setting -------------------------------------

def best_time(function, repeats=5):
    """Call ``function()`` ``repeats`` times: its last result and the fastest run, in seconds.

    The fastest of several runs is the one least disturbed by other work on the machine.
    """
    best, result = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return result, best


def timed_render(scene: Scene, width, height, repeats=5, backend="numpy") -> tuple[Frame, float]:
    """Render ``repeats`` times (`best_time`): the frame and the fastest run, in seconds.

    The NumPy reference is the default because its time follows the work done; a GPU's, at
    lesson sizes, is mostly a fixed overhead.
    """
    return best_time(lambda: render(scene, width, height, backend=backend), repeats)


def wrong_pixels(frame: Frame, converged: Frame, levels=VISIBLE_LEVELS) -> np.ndarray:
    """(H, W) bool: the pixels whose 8-bit colour is more than ``levels`` away from
    ``converged`` in some channel (visibly wrong)."""
    difference = np.abs(frame.image().astype(int) - converged.image().astype(int))
    return difference.max(axis=-1) > levels


def sweep(scene: Scene, knob: str, values, converged, width, height, repeats=5,
          **fixed) -> list[dict]:
    """Render ``scene`` at each value of one render setting and measure cost and artefacts.

    Parameters
    ----------
    scene : Scene
    knob : str
        The render setting swept, e.g. ``"epsilon"``.
    values : sequence
        Its values.
    converged : float or int
        Its safe extreme: the reference picture uses it, with at least `SAFE_STEPS` steps so
        that no ray runs out of them.
    width, height : int
    repeats : int
        Renders per value; the fastest is timed (`timed_render`).
    **fixed
        Other render settings, the same for every value.

    Returns
    -------
    list of dict
        Per value: ``value``, ``ms`` (best time), ``steps`` (mean steps per ray), ``wrong``
        ((H, W) bool, `wrong_pixels` against the converged picture) and the ``frame``.
    """
    safe = {**fixed, "max_steps": max(SAFE_STEPS, fixed.get("max_steps", 0)), knob: converged}
    reference, _ = timed_render(with_settings(scene, **safe), width, height, repeats=1)
    rows = []
    for value in values:
        frame, seconds = timed_render(with_settings(scene, **fixed, **{knob: value}), width,
                                      height, repeats)
        rows.append({"value": value, "ms": 1000 * seconds, "steps": frame.steps.mean(),
                     "wrong": wrong_pixels(frame, reference), "frame": frame})
    return rows
