"""Shading: the colour of a surface point under the lights, and the other shading modes.

The lit models take the light arriving at each point (``incoming``: one ``(L, radiance)`` pair
per light, radiance already multiplied by attenuation and shadow) and return linear RGB.

Phong (Phong 1975)::

    I = ka albedo i_a + sum_m radiance_m (kd max(N.L_m, 0) albedo + ks max(R_m.V, 0)^alpha)

with R_m = reflect(-L_m, N) and V the unit vector toward the eye. Blinn-Phong replaces R.V by
N.H with H = normalize(L + V) (Blinn 1977). Specular light is not tinted by the albedo (the
highlight has the light's colour, as in Phong 1975: a plastic, not a metal), and it is zero
where N.L <= 0 so that a light behind a surface cannot make a highlight on it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from scene_model.colormaps import heat
from scene_model.environment import ENVIRONMENT_KINDS
from scene_model.geometry import dot, normalize

from .environment import background_environment



@dataclass
class Surface:
    """What shading needs at N surface points (all arrays have N rows)."""
    position: np.ndarray    # (N, 3)
    normal: np.ndarray      # (N, 3) unit
    view: np.ndarray        # (N, 3) unit, from the point toward the eye
    albedo: np.ndarray      # (N, 3)
    ka: np.ndarray          # (N,)
    kd: np.ndarray          # (N,)
    ks: np.ndarray          # (N,)
    shininess: np.ndarray   # (N,)
    object_id: np.ndarray | None = None   # (N,) int, where known

    def select(self, rows) -> "Surface":
        """The points picked by ``rows`` (a mask or indices)."""
        values = (getattr(self, f.name) for f in dataclasses.fields(self))
        return Surface(*(None if v is None else v[rows] for v in values))


def reflect(d, n):
    """Mirror direction of ``d`` about the normal ``n``: d - 2 (d.n) n (Whitted 1980).

    Split d into its part along n, (d.n) n, and the rest; the mirror keeps the rest and flips
    the part along n.
    """
    return d - 2 * dot(d, n)[:, None] * n


def diffuse(n, l):
    """Lambert's cosine term max(N.L, 0)."""
    return np.maximum(dot(n, l), 0)


def specular_phong(n, l, v, shininess):
    """max(R.V, 0)^alpha with R = reflect(-L, N); zero where the light is behind the surface."""
    r = reflect(-l, n)
    return np.where(dot(n, l) > 0, np.maximum(dot(r, v), 0) ** shininess, 0)


def specular_blinn_phong(n, l, v, shininess):
    """max(N.H, 0)^alpha with the half vector H = normalize(L + V) (Blinn 1977)."""
    h = normalize(l + v)
    return np.where(dot(n, l) > 0, np.maximum(dot(n, h), 0) ** shininess, 0)


def shade_phong(s: Surface, incoming, ambient):
    """The Phong model summed over the lights, plus ambient."""
    return _lit(s, incoming, ambient, lambda x: x, specular_phong)


def shade_blinn_phong(s: Surface, incoming, ambient):
    """Phong with the Blinn half-vector highlight."""
    return _lit(s, incoming, ambient, lambda x: x, specular_blinn_phong)


def shade_toon(s: Surface, incoming, ambient, bands):
    """Phong with the diffuse and specular terms quantised into ``bands`` levels.

    Toon (cel) shading: Lake et al. 2000 look the diffuse term up in a texture of a few flat
    tones; here both terms go through `toon_band`.
    """
    return _lit(s, incoming, ambient, lambda x: toon_band(x, bands), specular_phong)


def shade_stripes(s: Surface, incoming, ambient, stripes):
    """Phong with the diffuse and specular terms drawn as ``stripes`` stripes
    (`stripes_band`): contour lines of the light, a sawtooth of its strength."""
    return _lit(s, incoming, ambient, lambda x: stripes_band(x, stripes), specular_phong)


def _lit(s, incoming, ambient, shape, specular):
    """The sum over ``incoming``, one tuple per light: ``(L, radiance)``, or ``(L, radiance,
    specular, ambient)``: a light with its own ambient, diffuse and specular colours
    (`scene_model.scene.Light`) gives the specular radiance and the ambient light it sends
    (radiance is then the diffuse one); None in either place means as a plain light."""
    color = s.ka[:, None] * s.albedo * ambient
    for to_light, radiance, *own in incoming:
        d = shape(diffuse(s.normal, to_light))
        sp = shape(specular(s.normal, to_light, s.view, s.shininess))
        light_specular, light_ambient = own or (None, None)
        if light_specular is None:
            color = color + radiance * (s.kd[:, None] * d[:, None] * s.albedo
                                        + (s.ks * sp)[:, None])
        else:
            color = (color + radiance * (s.kd[:, None] * d[:, None] * s.albedo)
                     + light_specular * (s.ks * sp)[:, None])
        if light_ambient is not None:
            color = color + s.ka[:, None] * s.albedo * light_ambient
    return color


def toon_band(x, bands):
    """Quantise x in [0, 1] to ``bands`` levels 0, 1/(bands-1), ..., 1.

    Each step is a narrow smoothstep (a tenth of a band wide) rather than a jump, so the
    result is continuous: a rounding difference in x changes the colour by a rounding
    difference, not by a whole band.
    """
    q = x * bands
    level = np.floor(q)
    step = smoothstep(0.9, 1.0, q - level)
    return np.minimum((level + step) / (bands - 1), 1)


def stripes_band(x, stripes):
    """A sawtooth of x in [0, 1] with ``stripes`` teeth: u = frac(stripes x), rising from 0
    to 1 across each stripe (the "ramp" of Blinn-Phong stripes shaders).

    Each tooth falls back to 0 over its last tenth by a smoothstep, as `toon_band` steps, so
    the colour stays continuous and the stripes' edges are no discontinuity.
    """
    q = x * stripes
    u = q - np.floor(q)
    return u * (1 - smoothstep(0.9, 1.0, u))


def smoothstep(edge0, edge1, x):
    """GLSL's smoothstep: 0 below edge0, 1 above edge1, 3u^2 - 2u^3 between."""
    u = np.clip((x - edge0) / (edge1 - edge0), 0, 1)
    return u * u * (3 - 2 * u)


def shade_normals(normal):
    """|N| as a colour, a common debugging view of normals: x red, y green, z blue."""
    return np.abs(normal)


def shade_depth(t, max_distance):
    """Grey 1 - t / max_distance: white at the eye, black at max_distance (a depth image)."""
    grey = np.clip(1 - t / max_distance, 0, 1)
    return np.repeat(grey[:, None], 3, axis=1)


def shade_steps(steps, max_steps):
    """The heat map of how many SDF evaluations a ray took, out of max_steps."""
    return heat(steps / max_steps)


def checker_parity(p, scale):
    """0 where floor(x/s) + floor(z/s) is even, 1 where it is odd (N,)."""
    return (np.floor(p[:, 0] / scale) + np.floor(p[:, 2] / scale)) % 2


def checker(p, color_a, color_b, scale):
    """Checkerboard in the xz-plane: color_a where floor(x/s) + floor(z/s) is even."""
    return np.where(checker_parity(p, scale)[:, None] == 0, color_a, color_b)


def apply_fog(color, t, fog_color, density):
    """Exponential fog: mix toward the fog colour by 1 - exp(-density t) (Quilez, "Fog")."""
    amount = 1 - np.exp(-density * t)
    return color + (fog_color - color) * amount[:, None]


def background(direction, bg):
    """What a ray that hits nothing sees: a solid colour, a sky gradient by the ray's y, or
    an environment map (`reference_cpu.environment`).

    The sky blends ``bottom`` to ``top`` by a = (d.y + 1) / 2, as in "Ray Tracing in One
    Weekend" (Shirley), so straight down is ``bottom`` and straight up is ``top``.
    """
    dtype = direction.dtype
    if bg.kind in ENVIRONMENT_KINDS:
        return background_environment(direction, bg)
    if bg.kind == "solid":
        return np.broadcast_to(np.asarray(bg.color, dtype=dtype), direction.shape)
    a = (direction[:, 1:2] + 1) / 2
    bottom, top = np.asarray(bg.bottom, dtype=dtype), np.asarray(bg.top, dtype=dtype)
    return bottom + (top - bottom) * a
