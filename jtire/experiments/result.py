"""ExperimentResult: what every experiment returns and what `jtire run --out` writes."""

import dataclasses
from pathlib import Path

import numpy as np

from ..io import atomic_write_csv, atomic_write_json
from ..results import RESULT, SIGNALS


@dataclasses.dataclass
class ExperimentResult:
    """experiment: name; condition: SI inputs; quantities: the reduced numbers (SI names);
    signals: equal-length recorded series (written as CSV); checks: settling and validity;
    info: solver facts (step, steps, wall times)."""

    experiment: str
    condition: dict
    quantities: dict
    signals: dict = dataclasses.field(default_factory=dict)
    checks: dict = dataclasses.field(default_factory=dict)
    info: dict = dataclasses.field(default_factory=dict)

    def to_json_dict(self) -> dict:
        return {"experiment": self.experiment, "condition": self.condition, "quantities": self.quantities,
                "checks": self.checks, "info": self.info}

    def write(self, out_dir) -> list:
        """signals.csv, then result.json, each atomically: result.json marks the case done (a resume
        skips a folder that has it), so it goes last and a kill between the two redoes the case."""
        out = Path(out_dir)
        written = []
        if self.signals:
            n = {len(np.atleast_1d(v)) for v in self.signals.values()}
            if len(n) != 1:
                raise ValueError(f"signals of unequal length: { {k: len(v) for k, v in self.signals.items()} }")
            written.append(atomic_write_csv(out / SIGNALS, None, {k: np.asarray(v) for k, v in self.signals.items()}))
        written.append(atomic_write_json(out / RESULT, self.to_json_dict()))
        return written
