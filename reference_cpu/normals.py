"""Surface normals as the normalised gradient of the SDF, by finite differences.

Quilez, "Normals for an SDF" (https://iquilezles.org/articles/normalsSDF/). The 1/(2h) factors
are dropped: normalising removes them. ``h`` is how far each sample lies from the point.
"""

from __future__ import annotations

import math

import numpy as np

from scene_model.geometry import dot

from .march import columns

# Both methods compute n = normalize(sum_k k f(p + h k)) over a stencil of unit offsets k.
# Central differences: +-h along each axis, so the sum is (f(p+hx) - f(p-hx), ...): 6 samples.
# Tetrahedron: the 4 corners of a regular tetrahedron, whose sum k k^T is proportional to the
# identity, so the sum is proportional to the gradient with only 4 samples.
STENCILS = {
    "central": np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]),
    "tetrahedron": np.array([[1, -1, -1], [-1, -1, 1], [-1, 1, -1], [1, 1, 1]]) / math.sqrt(3),
}


def estimate_normal(sdf, p, h, method="central"):
    """Unit normals (N, 3) of the SDF at points ``p`` (N, 3), by the named stencil.

    Where the estimated gradient vanishes (a point equidistant from several surfaces) the
    result is the zero vector; the caller decides what that means.
    """
    p = columns(p)
    gradient = np.zeros_like(p)
    for k in STENCILS[method].astype(p.dtype):
        gradient += sdf(p + h * k)[0][:, None] * k
    size = np.sqrt(dot(gradient, gradient))[:, None]
    return np.divide(gradient, size, out=np.zeros_like(gradient), where=size > 0)
