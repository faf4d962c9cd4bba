"""jtire: a JAX-native, differentiable ring-of-shells tire simulator and calibration toolkit.

Everything inside is SI (m, kg, s, N, Pa, rad) with z up; configs convert units once at the edge
(`jtire.config`). Importing the package does no numerical work; it only asks JAX for float64,
which the stiff shell model and its finite-difference gradient checks need.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)
