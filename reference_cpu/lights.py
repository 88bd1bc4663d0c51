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
        colour * intensity * attenuation (* spot cone factor): the light's diffuse colour
        (`scene_model.scene.Light.term_colors`), its colour unless it gives one.
    """
    dtype = p.dtype
    color = np.asarray(light.color, dtype=np.float64) * light.intensity
    if light.separate_colors():
        color = np.asarray(light.term_colors()[1], dtype=np.float64)
    to_light, distance, factor, _ = light_geometry(light, p)
    if factor is None:                                   # a directional light
        return to_light, distance, np.broadcast_to(color.astype(dtype), p.shape)
    return to_light, distance, factor[:, None] * color.astype(dtype)


def light_geometry(light, p):
    """Where one light is from points ``p`` (N, 3), and how much of it reaches them.

    Returns
    -------
    to_light : (N, 3) ndarray
    distance : (N,) ndarray
        As `light_at`.
    factor : (N,) ndarray or None
        Attenuation times the spot cone (None for a directional light: 1 everywhere).
    fade : (N,) ndarray or None
        The attenuation alone, which a light's ambient term takes (None: 1 everywhere).
    """
    dtype = p.dtype
    if isinstance(light, DirectionalLight):
        direction = np.asarray(light.direction, dtype=np.float64)
        to_light = np.broadcast_to((-direction / np.linalg.norm(direction)).astype(dtype), p.shape)
        return to_light, np.full(len(p), np.inf, dtype=dtype), None, None

    offset = np.asarray(light.position, dtype=dtype) - p
    distance = length(offset)
    to_light = offset / distance[:, None]
    fade = attenuation(distance, light.constant, light.linear, light.quadratic)
    factor = fade
    if isinstance(light, SpotLight):
        axis = np.asarray(light.direction, dtype=np.float64)
        axis = (axis / np.linalg.norm(axis)).astype(dtype)
        factor = fade * spot_cone(-dot(to_light, axis), light.inner_angle, light.outer_angle)
    elif not isinstance(light, PointLight):
        raise TypeError(f"unknown light type {type(light).__name__}")
    return to_light, distance, factor, fade


def light_terms(light, p):
    """A light with its own colours (`scene_model.scene.Light.term_colors`) at points ``p``
    (N, 3), before shadowing: ``to_light``, ``distance``, the falloff (N, 3) that scales the
    diffuse and specular colours (``factor`` of `light_geometry` in every channel), and the
    ambient light (N, 3), its colour times the attenuation alone."""
    dtype = p.dtype
    to_light, distance, factor, fade = light_geometry(light, p)
    ambient = np.asarray(light.term_colors()[0], dtype=np.float64).astype(dtype)
    if factor is None:
        ones = np.ones(p.shape, dtype)
        return to_light, distance, ones, np.broadcast_to(ambient, p.shape)
    return to_light, distance, factor[:, None] * np.ones(3, dtype), fade[:, None] * ambient


def unshadowed(light, p):
    """Everything of one light at points ``p`` (N, 3) that shading takes, before shadowing.

    Returns
    -------
    to_light : (N, 3) ndarray
    distance : (N,) ndarray
        As `light_at`.
    radiance : (N, 3) ndarray
        What the diffuse term takes.
    specular, ambient : (N, 3) ndarrays or None
        For a light with its own colours (`scene_model.scene.Light.term_colors`), the
        radiance its specular term takes and the ambient light it sends; None for a plain
        light (its radiance does both, `reference_cpu.shading`).
    reach : (N, 3) ndarray
        Zero where the light sends nothing (outside a spot's cone): no shadow ray is needed.
    """
    if not light.separate_colors():
        to_light, distance, radiance = light_at(light, p)
        return to_light, distance, radiance, None, None, radiance
    to_light, distance, falloff, ambient = light_terms(light, p)
    _, diffuse_color, specular_color = (np.asarray(c, np.float64).astype(p.dtype)
                                        for c in light.term_colors())
    return (to_light, distance, falloff * diffuse_color, falloff * specular_color, ambient,
            falloff)


def attenuation(distance, constant, linear, quadratic):
    """1 / (K_c + K_l d + K_q d^2) for distances ``distance`` (N,)."""
    return 1 / (constant + distance * (linear + distance * quadratic))


def spot_cone(cos_theta, inner_degrees, outer_degrees):
    """1 inside the inner cone, 0 outside the outer one, linear in cos(theta) between."""
    cos_inner = math.cos(math.radians(inner_degrees))
    cos_outer = math.cos(math.radians(outer_degrees))
    return np.clip((cos_theta - cos_outer) / (cos_inner - cos_outer), 0, 1)
