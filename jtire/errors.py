"""Exceptions that the CLI reports as one line (no traceback)."""


class JtireError(Exception):
    """Base class of every error that is the user's to fix or that a run reports in-band."""


class ConfigError(JtireError, ValueError):
    """A config field is missing, unknown, of the wrong type, or out of its allowed range.

    The message names the field and the allowed range, e.g.
    ``condition.pressure_psi = -3: must be in [10, 250] psi``.
    """


class SimulationError(JtireError, RuntimeError):
    """A simulation went unstable or failed to settle; the message says where and when."""


class UnderResolved(SimulationError):
    """A result failed a discretization check of its own (the steady flow's energy balance): the ring has
    too few segments for it. `batch.run` reruns such a case on a ring with more segments."""

    def __init__(self, message, n_theta: int):
        self.n_theta = int(n_theta)
        super().__init__(message)


class ClusterError(JtireError, RuntimeError):
    """The cluster named by --cluster cannot be used (unreachable, another jtire build, a case that killed
    its workers); the message says which and what to do."""


class CasesFailed(SimulationError):
    """A long job finished its other cases and wrote its outputs, but some cases failed (each named in the
    message; a rerun retries them)."""

    def __init__(self, failures):
        self.failures = list(failures)
        super().__init__(f"{len(self.failures)} cases failed (rerun to retry them): " + "; ".join(self.failures))
