"""Ground truth for the reference: depth, normal and hit images without sphere tracing.

`ground_truth` gives them by exact ray intersections (analytic.py) or by Embree ray casts
(embree.py) of the scene meshed by marching cubes (mesh.py); parts.py splits a scene into
the pieces both methods trace. ground_truth.py says how far each method may be off.
"""

from .ground_truth import METHODS, Truth, ground_truth, surface_distances

__all__ = ["METHODS", "Truth", "ground_truth", "surface_distances"]
