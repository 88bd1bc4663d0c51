"""Scenes and pixel masks shared by the ground-truth tests (tests/truth/).

Importable from every test file of this folder: pytest puts a test file's folder on sys.path.
"""

from __future__ import annotations

import numpy as np

from scene_model.builder import Camera, RenderSettings, Scene, box, plane, sphere, torus

WIDTH, HEIGHT = 64, 48
EPSILON = 1e-3
CAMERA = Camera(position=(0.0, 2.2, 7.0), look_at=(0.0, 0.8, 0.0), fov=50.0)

# A sphere, a plane and a box turned about two axes: everything the analytic method takes.
SPHERE_PLANE_BOX = Scene(
    camera=CAMERA,
    render=RenderSettings(epsilon=EPSILON),
    objects=(plane(),
             sphere(0.8).at(-1.5, 0.8, 0.0),
             box(0.5).rotate(20, 35, 0).at(1.2, 0.6, 0.3),
             box(0.3, 0.2, 0.4).scale(1.5).at(0.0, 0.3, 1.5)),
)

# CSG, a smooth blend and a torus: only the embree method takes these.
CSG = Scene(
    camera=CAMERA,
    render=RenderSettings(epsilon=EPSILON),
    objects=(plane(),
             (box(0.75) - sphere(0.98)).at(-2.0, 0.8, 0.0),
             sphere(0.6).at(-0.35, 0, 0).smooth_union(sphere(0.45).at(0.45, 0.25, 0.1), k=0.45)
             .at(0.3, 0.75, 0.4),
             torus(0.65, 0.22).rotate(60, 0, 0).at(2.0, 0.8, 0.0)),
)


def _neighbours_differ(labels: np.ndarray) -> np.ndarray:
    """True where a pixel's 3x3 neighbourhood holds more than one value of ``labels``."""
    padded = np.pad(labels, 1, mode="edge")
    h, w = labels.shape
    windows = [padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)]
    return np.any([window != labels for window in windows], axis=0)


def near_silhouette(object_id: np.ndarray) -> np.ndarray:
    """Pixels within 1 px of a silhouette or of a boundary between objects.

    Rays there pass within a pixel's footprint of an edge, where a ray that clears a surface
    by less than epsilon counts as a hit for the sphere tracer and a mesh's edge may lie on
    either side of the true one. ``object_id`` is -1 on a miss, so hit edges are included.
    """
    return _neighbours_differ(object_id)


def cos_incidence(normal: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """|n . d| per pixel: (H, W, 3) with (H, W, 3) -> (H, W)."""
    return np.abs(np.sum(normal * directions, axis=-1))
