"""Inflation pressure as p dV/dX of the closed cavity volume.

The cavity is bounded by the tire's mid-surface (bead to bead) and closed across the rim by the
quads between the two bead rings. The force p * dV/dX is exact for a follower load on the current
surface, balanced by construction (the rim, which carries the beads and the closure, takes the
reaction), and needs no hand-derived normals. Each quad is split into four triangles about its
centroid so that the volume, and the pressure forces, keep the mesh's mirror symmetry.
The pressure acts on the mid-surface (the inner liner lies ~t/2 inside it; the difference in
loaded area is under 3 % and is absorbed by calibration).
"""

from .geometry_ops import cross, dot


def _quad_volume(a, b, c, d):
    m = (a + b + c + d) * 0.25
    tri = lambda p, q: dot(p, cross(q, m))  # noqa: E731  6 x signed tetra volume
    return (tri(a, b) + tri(b, c) + tri(c, d) + tri(d, a)) / 6.0


def cavity_volume(X, sign):
    """Enclosed volume (m^3) of the tire + rim closure. X: V of (T, S+2); sign fixes orientation."""
    real = X[:, 1:-1]
    nxt = real.roll(-1, 0)
    v_tire = _quad_volume(real[:, :-1], real[:, 1:], nxt[:, 1:], nxt[:, :-1]).sum()
    bl, br = real[:, 0], real[:, -1]
    v_close = _quad_volume(br, bl, bl.roll(-1, 0), br.roll(-1, 0)).sum()
    return sign * (v_tire + v_close)
