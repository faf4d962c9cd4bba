"""The experiment interface: a traced `simulate` and a host `reduce`, configured from a table.

An `Experiment` is an equinox Module built from its validated config table (`from_table`): settings
that fix the program's structure (counts, sample numbers, options) are static fields, every other
setting an array leaf, so changing a duration or a force never recompiles. Then:

- `cases(condition)`: the traced cases one condition expands into (one by default; E10: one per slip
  angle), as host dicts with the case's `aux` values;
- `simulate(model, params, case) -> outputs`: pure and traced (phases from `program.run_plan`), so
  the batch runner vmaps it over cases and parameter sets, shards it over devices, and autodiff
  differentiates it;
- `reduce(tire, condition, outputs) -> ExperimentResult`: host (numpy/scipy) from the outputs of the
  condition's cases to the quantities of result.json, with every validity check;
- `traced(model, params, condition_cases, outputs) -> dict`: the quantities calibration and
  sensitivities need, reduced in JAX (checked against `reduce` by the tests).

The registry (`jtire.experiments`) imports the experiment modules; experiments never import it.
"""

import abc
from typing import ClassVar

import equinox as eqx
import numpy as np

from .phases import Case, Protocol


METHODS = ("static", "steady", "transient")


def _method(exp) -> str:
    """exp's `method` field: every experiment declares one, and no default is assumed (a static
    experiment taken for a transient was vmapped and given an explicit step it never used: E14 was)."""
    m = getattr(exp, "method", None)
    if m not in METHODS:
        raise TypeError(f"{type(exp).__name__}: method {m!r}: an experiment declares a `method` field, one of "
                        f"{', '.join(METHODS)}")
    return m


class Experiment(eqx.Module):
    """Base class of every virtual experiment (the module docstring describes the interface).

    Class attributes: `name` (the registry and config key), `study_id` (e.g. "E02"), `description`,
    `schema` (the config table's Fields), `needs_load` (a condition must give a load),
    `per_pressure` (the load does not enter: one condition per pressure), `aux_names` (the case's
    own variables), `traced_names` (what `traced` returns), `quantity_names` (what `reduce` writes).
    Instances are built by `from_table`; `proto` holds the solver protocol (settling damping,
    kinetic-energy tolerance, ramps and time limits; SI).
    """

    name: ClassVar[str]
    study_id: ClassVar[str]
    description: ClassVar[str]
    schema: ClassVar[dict]  # the experiment's config table: key -> schema.Field
    needs_load: ClassVar[bool] = True
    per_pressure: ClassVar[bool] = False  # the load does not enter (E05, E07, E08)
    aux_names: ClassVar[tuple] = ()  # names of the case's aux values (case dict keys)
    traced_names: ClassVar[tuple] = ()  # quantities `traced` returns
    quantity_names: ClassVar[tuple] = ()  # quantities `reduce` writes into result.json (see `produces`)

    proto: Protocol

    @property
    def shardable(self) -> bool:
        """Whether a batch of this experiment may be split over several devices. Static and steady
        solves may not: their Newton loops end after a different number of iterations on each device, and the
        partitioned program then deadlocks on CPU host devices (docs/design-notes.md); `batch.run` runs
        them case by case, unbatched, on one device (a vmapped Newton loop runs both branches of its
        conditionals). A transient started from a static state (method "static" with a release) holds
        a Newton solve too."""
        return self.time_stepped and _method(self) not in ("static", "steady")

    @property
    def time_stepped(self) -> bool:
        """Whether the experiment integrates in time (needs the explicit step of each case)."""
        return _method(self) not in ("static", "steady")

    @classmethod
    @abc.abstractmethod
    def from_table(cls, table: dict, proto: Protocol, tire_spec) -> "Experiment":
        """Build from the validated table (SI values); cross-field checks raise ConfigError here,
        before anything is simulated."""

    @classmethod
    def produces(cls, table: dict) -> tuple:
        """The quantity names `reduce` writes with this validated table (SI): `quantity_names`, unless
        an option of the table adds or removes some. Calibration targets are checked against it before
        anything runs; the tests check it against what `reduce` wrote."""
        return cls.quantity_names

    def cases(self, condition: dict) -> list:
        """Host case dicts ({"load_N", "pressure_Pa", *aux_names}) for one condition."""
        return [dict(condition)]

    def aux(self, case: dict) -> np.ndarray:
        """The case's own variables (the values of `aux_names` in a host case dict, e.g. the slip angle
        in rad) as a float array of shape (len(aux_names),): the `aux` of the traced `Case`."""
        return np.array([case[k] for k in self.aux_names], float)

    @abc.abstractmethod
    def simulate(self, model, params, case: Case):
        """Traced: every phase of the experiment. Returns a pytree of arrays of fixed shapes."""

    @abc.abstractmethod
    def reduce(self, tire, condition: dict, outputs: list):
        """Host: outputs (numpy pytrees, one per case of `cases(condition)`) -> ExperimentResult."""

    def traced(self, model, params, condition_cases: list, outputs: list) -> dict:
        """Traced quantities from the outputs of one condition's cases (jnp scalars)."""
        raise NotImplementedError(f"{self.name}: no traced reduction")
