"""Unit factors to SI. Used only by `jtire.config` (units are converted once, at the edge)."""

G0 = 9.81  # m/s^2: the study converts kg of load to newtons with 9.81
PSI = 6894.757293168  # Pa
LBF = 4.4482216152605  # N
MPH = 0.44704  # m/s
KMH = 1.0 / 3.6  # m/s
MM = 1e-3
INCH = 0.0254  # m
MPA = 1e6
KN = 1e3
MS = 1e-3  # millisecond
DEG = 3.141592653589793 / 180.0
