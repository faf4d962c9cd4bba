"""Load directions and rim DOF masks (internal ISO axes: x forward, y left, z up), defined once.

Rim coordinates are (x, y, z, rx, ry = spin about the axle, rz); a mask entry 1 means the DOF is
free (integrated under the forces), 0 that it is prescribed (locked unless a velocity is given).
"""

import numpy as np

DOWN = np.array([0.0, 0, -1, 0, 0, 0])  # a vertical load pushes the rim down, towards the road
LEFT = np.array([0.0, 1, 0, 0, 0, 0])  # +y (ISO): a lateral force to the left

RIM_LOCKED = np.zeros(6)
RIM_Z = np.array([0.0, 0, 1, 0, 0, 0])  # vertical load on the rim, everything else held
RIM_YZ = np.array([0.0, 1, 1, 0, 0, 0])  # vertical and lateral load
RIM_SPIN = np.array([0.0, 0, 0, 0, 1, 0])  # rim held except its spin about the axle
RIM_Z_SPIN = np.array([0.0, 0, 1, 0, 1, 0])  # rolling with the load on the rim, no drive torque


def lateral_sae(alpha, fx, fy_iso, xp=np):
    """Lateral force in road axes, SAE signs: F_y,SAE cos a - F_x sin a (N), F_y,SAE = -F_y,ISO."""
    return -fy_iso * xp.cos(alpha) - fx * xp.sin(alpha)
