"""jtire: a JAX-native, differentiable ring-of-shells tire simulator and calibration toolkit.

Everything inside is SI (m, kg, s, N, Pa, rad) with z up; configs convert units once at the edge
(`jtire.config`). Importing the package does no numerical work; it only asks JAX for float64,
which the stiff shell model and its finite-difference gradient checks need.
"""

import os as _os

# equinox's runtime checks (inside diffrax) as NaN instead of a host callback: a program with a host
# callback cannot be stored in JAX's persistent compilation cache, and every failure they guard is
# caught in-band by jtire anyway (non-finite states are "unstable", with where and when).
_os.environ.setdefault("EQX_ON_ERROR", "nan")
# One BLAS thread unless the user set one: the static solves' host LAPACK calls are small, and threaded
# OpenBLAS spins against XLA's threads, making them far slower (docs/design-notes.md); and the
# rounding then does not depend on the core count (a cluster's workers give this process's numbers).
# It only takes effect when numpy is not imported yet (importing jtire first).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

import jax as _jax  # noqa: E402

_jax.config.update("jax_enable_x64", True)


def _host_devices():
    """One JAX CPU device per core (the batch runner shards cases over them); JTIRE_CPU_DEVICES
    overrides. Only takes effect before JAX starts its backends (importing jtire first)."""
    want = _os.environ.get("JTIRE_CPU_DEVICES")
    try:
        n = int(want) if want else len(_os.sched_getaffinity(0))
    except (ValueError, AttributeError):
        n = _os.cpu_count() or 1
    if "xla_force_host_platform_device_count" in _os.environ.get("XLA_FLAGS", ""):
        return
    try:
        _jax.config.update("jax_num_cpu_devices", max(1, n))
    except (RuntimeError, AttributeError):  # backends already started, or an older JAX
        pass


_host_devices()
