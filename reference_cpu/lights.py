"""Where each light comes from, and how strongly, at a set of surface points.

Point and spot lights fade with distance as 1 / (K_c + K_l d + K_q d^2); a spot light also fades
from its inner to its outer cone, clamp((cos theta - cos outer) / (cos inner - cos outer), 0, 1)
(LearnOpenGL, "Light casters"). A directional light is the same everywhere.
"""

from __future__ import annotations

import math

import numpy as np

from scene_model.geometry import dot
from scene_model.scene import DirectionalLight, PointLight, SpotLight

from .sdf import length


def light_at(light, p):
    """The light arriving at points ``p`` (N, 3) from one light, before shadowing.

    Returns
    -------
    to_light : (N, 3) ndarray
        Unit vectors from each point toward the light (L in the Phong formula).
    distance : (N,) ndarray
        Distance to the light; inf for a directional light.
    radiance : (N, 3) ndarray
        colour * intensity * attenuation (* spot cone factor).
    """
    dtype = p.dtype
    color = np.asarray(light.color, dtype=np.float64) * light.intensity
    if isinstance(light, DirectionalLight):
        direction = np.asarray(light.direction, dtype=np.float64)
        to_light = np.broadcast_to((-direction / np.linalg.norm(direction)).astype(dtype), p.shape)
        return to_light, np.full(len(p), np.inf, dtype=dtype), np.broadcast_to(color.astype(dtype), p.shape)

    offset = np.asarray(light.position, dtype=dtype) - p
    distance = length(offset)
    to_light = offset / distance[:, None]
    factor = attenuation(distance, light.constant, light.linear, light.quadratic)
    if isinstance(light, SpotLight):
        axis = np.asarray(light.direction, dtype=np.float64)
        axis = (axis / np.linalg.norm(axis)).astype(dtype)
        factor = factor * spot_cone(-dot(to_light, axis), light.inner_angle, light.outer_angle)
    elif not isinstance(light, PointLight):
        raise TypeError(f"unknown light type {type(light).__name__}")
    return to_light, distance, factor[:, None] * color.astype(dtype)


def attenuation(distance, constant, linear, quadratic):
    """1 / (K_c + K_l d + K_q d^2) for distances ``distance`` (N,)."""
    return 1 / (constant + distance * (linear + distance * quadratic))


def spot_cone(cos_theta, inner_degrees, outer_degrees):
    """1 inside the inner cone, 0 outside the outer one, linear in cos(theta) between."""
    cos_inner = math.cos(math.radians(inner_degrees))
    cos_outer = math.cos(math.radians(outer_degrees))
    return np.clip((cos_theta - cos_outer) / (cos_inner - cos_outer), 0, 1)
