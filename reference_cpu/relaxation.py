"""Over-relaxed sphere tracing: longer steps, and a way back when one went too far.

Plain sphere tracing steps exactly d_i = |sdf(o + t_i d)|, the radius of a sphere that holds no
surface. Along a surface seen at a grazing angle the radii shrink slowly and the ray crawls.
Keinert et al. ("Enhanced Sphere Tracing", STAG 2014) step omega d_i with 1 < omega < 2
instead, and check every step afterwards: the step from t_i to t_i+1 is safe when the empty
spheres around the two points overlap, d_i + d_i+1 >= t_i+1 - t_i, because together they cover
the segment between them. When they do not, a surface may lie in the gap: the march goes back
to the plain step t_i + d_i, which is always safe. The test misses one case: a step that lands
inside the solid exactly along the surface normal, where the spheres just touch (d_i + d_i+1
equals the step). So a relaxed step that changed the sign of the distance is taken back too.

Bán & Valasek ("Automatic Step Size Relaxation in Sphere Tracing", Eurographics 2023 short
paper) choose omega per step from the field itself. If the distance changes along the ray
with slope m (d(t + s) ~ d(t) + m s, with -1 <= m <= 0 for an exact SDF approached from
outside), the longest step whose next sphere still touches the current one solves
d + (d + m s) = s: s = 2 d / (1 - m), i.e. omega = 2 / (1 - m). Head-on (m = -1) that is a
plain step; parallel to a wall (m = 0) it doubles it. m is a moving average of the slopes
measured between consecutive points, restarted at -1 after a step back.

The rules every backend follows (relaxed march: ``glsl/relaxed.glsl``):

- state per ray: t, the previous point t_prev with its radius r_prev, the last step s (all 0
  at the start), omega (OMEGA for "fixed", 1 for "auto") and, for "auto", the slope m = -1;
- each step evaluates f = sdf(o + t d) and r = |f|. If r_prev + r < s, or if the last step
  was relaxed (s > r_prev) and f and f_prev (the distance at t_prev) differ in sign, the step
  may have skipped a surface: t = t_prev + r_prev, s = r_prev, omega = 1 (for "fixed" from
  then on, as Keinert et al. do; for "auto" m = -1), and this point decides nothing;
- otherwise the point is checked as in plain sphere tracing (hit if r < epsilon, miss if
  t + r > limit); for "auto", where s > 0, m += (( r - r_prev) / s - m) SLOPE_WEIGHT and
  omega = 2 / (1 - clamp(m, -1, 0)); then t_prev = t, r_prev = r, f_prev = f, s = omega r,
  t += s.

A relaxed ray stops only where a plain one may: within epsilon of a surface, with no
surface skipped before it (the overlap test), so the hit mask and the depth agree with plain
sphere tracing to within epsilon. Each evaluation counts as a step, those taken back too.
"""

from __future__ import annotations

import numpy as np

SLOPE_WEIGHT = 0.3        # weight of the newest slope in the moving average ("auto")
MODES = ("none", "fixed", "auto")


class Relaxation:
    """The per-ray state of a relaxed march over N rays (see the module's rules)."""

    def __init__(self, mode: str, omega: float, n: int, dtype: np.dtype):
        if mode not in ("fixed", "auto"):
            raise ValueError(f"relaxation must be one of {MODES} (got {mode!r})")
        self.mode, f = mode, dtype.type
        self.t_prev = np.zeros(n, dtype)
        self.r_prev = np.zeros(n, dtype)
        self.inside_prev = np.zeros(n, bool)              # f_prev < 0
        self.length = np.zeros(n, dtype)                  # s, the last step
        self.omega = np.full(n, f(omega) if mode == "fixed" else f(1), dtype)
        self.slope = np.full(n, f(-1), dtype)

    def step(self, t, f):
        """The next t of every ray, and whether the point at ``t`` may decide (hit or miss).

        Parameters
        ----------
        t, f : (N,) ndarray
            Current position along each ray and the (signed) sdf there.

        Returns
        -------
        t_next : (N,) ndarray
        valid : (N,) bool ndarray
            False where the last step was taken back.
        """
        r, inside = np.abs(f), f < 0
        crossed = (self.length > self.r_prev) & (inside != self.inside_prev)
        valid = ~((self.r_prev + r < self.length) | crossed)
        if self.mode == "auto":
            measured = valid & (self.length > 0)
            slope = np.divide(r - self.r_prev, self.length, where=measured,
                              out=np.zeros_like(r))
            self.slope = np.where(measured, self.slope + (slope - self.slope) * SLOPE_WEIGHT,
                                  self.slope)
            self.slope = np.where(valid, self.slope, -1)
            self.omega = 2 / (1 - np.clip(self.slope, -1, 0))
        else:
            self.omega = np.where(valid, self.omega, 1)
        self.length = np.where(valid, self.omega * r, self.r_prev)
        t_next = np.where(valid, t + self.length, self.t_prev + self.r_prev)
        self.t_prev = np.where(valid, t, self.t_prev)
        self.r_prev = np.where(valid, r, self.r_prev)
        self.inside_prev = np.where(valid, inside, self.inside_prev)
        return t_next, valid

    def keep(self, rows):
        """Drop the rays not in ``rows`` (N,) bool, as the march compacts its working set."""
        for name in ("t_prev", "r_prev", "inside_prev", "length", "omega", "slope"):
            setattr(self, name, getattr(self, name)[rows])
