"""Writes pawn.obj and pawn.mtl, a chess pawn for the museum scenes: run it from anywhere with
``python scene_model/scenes/models/make_pawn.py``.

The pawn is a lathe, a surface of revolution: a profile curve (r(t), y(t)) in the half plane
r >= 0 turned around the y axis,

    p(phi, t) = (r cos phi, y, -r sin phi),    phi = 2 pi u,

as `scene_model.meshes` turns its round primitives (u = 0 at +x, turning towards -z). The
profile runs from the bottom of the base (r = 0) to the top of the head (r = 0 again); with
the outward normal of the profile (y', -r') / |(y', -r')|, dp/du x dp/dt points out of the
solid, so the quads (i, k), (i + 1, k), (i + 1, k + 1), (i, k + 1) of the grid are wound
outward. The texture coordinates are u and the profile's arc length from the bottom, as a
fraction of its whole length.

The profile is made of pieces: straight lines, circular arcs and the concave stem, each
with its exact normals. Where two pieces meet at an angle (the rim of the base, the collar)
the ring of positions is shared and the normals are not, so the edge looks sharp and the
surface stays closed. The base and the collar are the group ``body``, the head the group
``head``; the two share the ring where the head sits on the collar.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

SEGMENTS = 20                 # around the axis
DIGITS = 5                    # decimals written: 10 micrometres on a pawn 0.92 m tall
HEAD_RADIUS, NECK = 0.15, 0.10


def line(a, b, steps: int = 1) -> np.ndarray:
    """The straight piece from (r, y) = a to b: (steps + 1, 4) rows of r, y, n_r, n_y."""
    t = np.linspace(0.0, 1.0, steps + 1)[:, None]
    points = (1 - t) * np.asarray(a, float) + t * np.asarray(b, float)
    d = np.subtract(b, a)
    normal = np.array([d[1], -d[0]]) / math.hypot(*d)
    return np.hstack([points, np.tile(normal, (steps + 1, 1))])


def arc(centre, radius: float, start: float, end: float, steps: int) -> np.ndarray:
    """The circular piece from angle ``start`` to ``end`` (degrees, anticlockwise in the (r, y)
    plane, so that the normal points away from the centre)."""
    angle = np.radians(np.linspace(start, end, steps + 1))
    normal = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    return np.hstack([np.asarray(centre, float) + radius * normal, normal])


def stem(bottom, top, steps: int) -> np.ndarray:
    """The concave stem r(t) = r1 + (r0 - r1)(1 - t)^2, y(t) = y0 + t (y1 - y0), from
    bottom = (r0, y0) up to top = (r1, y1), where it is vertical."""
    (r0, y0), (r1, y1) = bottom, top
    t = np.linspace(0.0, 1.0, steps + 1)
    r = r1 + (r0 - r1) * (1 - t) ** 2
    dr, dy = -2 * (r0 - r1) * (1 - t), np.full_like(t, y1 - y0)
    length = np.hypot(dr, dy)
    return np.stack([r, y0 + t * (y1 - y0), dy / length, -dr / length], axis=1)


def profile() -> list[tuple[str, str, list[np.ndarray]]]:
    """The pawn's groups: (group, material, pieces), bottom to top; each piece (K, 4) rows
    of r, y (m) and the outward unit normal (n_r, n_y), each starting where the last ends."""
    # The head is a sphere cut where its radius is the neck's, on top of the collar (y 0.66).
    below = math.acos(NECK / HEAD_RADIUS)
    centre = 0.66 + HEAD_RADIUS * math.sin(below)
    body = [line((0.0, 0.0), (0.36, 0.0)),                  # underneath, facing down
            line((0.36, 0.0), (0.36, 0.06)),                # the base's rim
            arc((0.30, 0.06), 0.06, 0.0, 90.0, 3),          # its rounded top edge
            line((0.30, 0.12), (0.24, 0.12)),               # a flat step
            stem((0.24, 0.12), (0.10, 0.60), 5),
            line((0.10, 0.60), (0.17, 0.60)),               # under the collar
            arc((0.17, 0.63), 0.03, -90.0, 90.0, 4),        # its rounded rim
            line((0.17, 0.66), (NECK, 0.66))]               # on top of it
    head = [arc((0.0, centre), HEAD_RADIUS, -math.degrees(below), 90.0, 7)]
    return [("body", "boxwood", body), ("head", "ebony", head)]


def _arc_length(piece: np.ndarray) -> np.ndarray:
    """Length along a piece's polygon from its start to each of its points: (K,)."""
    return np.r_[0.0, np.cumsum(np.hypot(*np.diff(piece[:, :2], axis=0).T))]


def obj_text() -> str:
    """The OBJ file: each position, normal and texture coordinate written once."""
    tables = {"v": {}, "vn": {}, "vt": {}}

    def index(kind: str, values) -> int:
        # Rounded as written, and -0.0 made 0.0, so equal text is one entry.
        text = " ".join(f"{v:.{DIGITS}f}" for v in np.round(values, DIGITS) + 0.0)
        return tables[kind].setdefault(text, len(tables[kind]) + 1)

    groups = profile()
    lengths = [_arc_length(p) for _, _, pieces in groups for p in pieces]
    total, done = sum(a[-1] for a in lengths), 0.0
    phi = 2 * np.pi * (np.arange(SEGMENTS + 1) % SEGMENTS) / SEGMENTS   # the seam exactly
    c, s = np.cos(phi), np.sin(phi)
    faces = []
    for group, material, pieces in groups:
        faces += [f"g {group}", f"usemtl {material}"]
        for piece in pieces:
            r, y, nr, ny = piece.T
            on_axis = np.round(r, DIGITS) == 0            # cos 90 degrees is 6e-17, not 0
            along = _arc_length(piece)
            v, done = (done + along) / total, done + along[-1]
            corner = [[(index("v", (r[k] * c[i], y[k], -r[k] * s[i])),
                        index("vt", (i / SEGMENTS, v[k])),
                        index("vn", (nr[k] * c[i], ny[k], -nr[k] * s[i])))
                       for k in range(len(piece))] for i in range(SEGMENTS + 1)]
            for i in range(SEGMENTS):
                for k in range(len(piece) - 1):
                    quad = [corner[i][k], corner[i + 1][k], corner[i + 1][k + 1],
                            corner[i][k + 1]]
                    # On the axis a quad's two corners are one point: a triangle is left.
                    if on_axis[k]:
                        quad.pop(1)
                    elif on_axis[k + 1]:
                        quad.pop(2)
                    faces.append("f " + " ".join("/".join(map(str, q)) for q in quad))
    lines = [f"# A chess pawn, a lathe of {SEGMENTS} segments: written by make_pawn.py",
             "mtllib pawn.mtl"]
    for kind in ("v", "vt", "vn"):
        lines += [f"{kind} {text}" for text in tables[kind]]
    return "\n".join(lines + faces) + "\n"


MTL = """\
# The pawn's materials: written by make_pawn.py
newmtl boxwood
Kd 0.80 0.62 0.38
Ks 0.30 0.30 0.30
Ns 40

newmtl ebony
Kd 0.08 0.06 0.05
Ks 0.60 0.60 0.60
Ns 120
"""


if __name__ == "__main__":
    folder = Path(__file__).resolve().parent
    (folder / "pawn.obj").write_text(obj_text())
    (folder / "pawn.mtl").write_text(MTL)
    print(f"wrote {folder / 'pawn.obj'} and pawn.mtl")
