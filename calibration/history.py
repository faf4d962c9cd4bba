"""One evaluation-history format for every optimizer, with resume by replay.

A history file is JSON lines (jtire.io.append_jsonl), one record per black-box call, written and
fsynced as soon as the call returns:

    {"method": "arsm", "seed": 3, "call": 0, "x": [...], "f": 1.25, "wall_s": 0.8, ...extras}

x is in physical units; f is null when the call failed (SimulationError) or was not finite.

Resume: an `Evaluator` opened on an existing file replays its records in order instead of
calling the black box, checking that each x the optimizer asks for is the recorded one. The
optimizers are deterministic given their seed and the values they see, so after the replayed
calls a killed run continues exactly where it stopped: no completed call is lost or repeated.
"""

import dataclasses
import math
import time
from pathlib import Path

import numpy as np

from ..errors import ConfigError, SimulationError
from ..io import append_jsonl, read_jsonl

__all__ = ["BudgetExhausted", "Evaluator", "OptimizeResult", "load_history", "best_so_far"]

# A replayed x must match the requested one to this many unit-box widths (round-off only).
_REPLAY_TOL = 1e-9


class BudgetExhausted(Exception):
    """Raised by an Evaluator asked for a call beyond its budget (control flow, not an error)."""


@dataclasses.dataclass(frozen=True)
class OptimizeResult:
    """What every optimizer returns.

    x_best: (d,) best point, physical units; f_best: its value; n_calls: calls used;
    history: the records (dicts) in call order; stop_reason: "budget", "region", "agreement",
    "target" or the method's own; method, seed: as run.
    """

    x_best: np.ndarray
    f_best: float
    n_calls: int
    history: list
    stop_reason: str
    method: str
    seed: int


def _f_of(record) -> float:
    f = record.get("f")
    return float("nan") if f is None else float(f)


def load_history(path) -> list:
    """All complete records of a history file (a torn last line is dropped)."""
    return read_jsonl(path)


def best_so_far(history) -> np.ndarray:
    """Running minimum of f over the records, shape (n,); failed calls count as +inf."""
    f = np.array([_f_of(r) for r in history], dtype=float)
    return np.minimum.accumulate(np.where(np.isfinite(f), f, np.inf)) if f.size else f


class Evaluator:
    """Wraps a black box: counts calls against a budget, records them, replays a saved run.

    Args:
        fun: callable x (d,) physical units -> float.
        lower, upper: (d,) bounds, used to compare replayed points in unit coordinates.
        method, seed: written into every record and checked on replay.
        budget: the maximum number of calls; the call after it raises BudgetExhausted.
        history_path: JSON-lines file to append to (and to replay from, if it exists).
    """

    def __init__(self, fun, lower, upper, method: str, seed: int, budget: int, history_path=None):
        if int(budget) < 1:
            raise ConfigError(f"budget = {budget}: must be >= 1 call")
        self.fun = fun
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        self.method, self.seed, self.budget = str(method), int(seed), int(budget)
        self.path = None if history_path is None else Path(history_path)
        self.records: list = []
        self._replay = [] if self.path is None else read_jsonl(self.path)
        for r in self._replay:
            if r.get("method") != self.method or int(r.get("seed", -1)) != self.seed:
                raise ConfigError(
                    f"history {self.path}: holds method={r.get('method')!r} seed={r.get('seed')}, "
                    f"not method={self.method!r} seed={self.seed}; use another file"
                )

    @property
    def n_calls(self) -> int:
        return len(self.records)

    @property
    def remaining(self) -> int:
        return self.budget - self.n_calls

    @property
    def n_replayed(self) -> int:
        """How many calls of this run came from the history file rather than the black box."""
        return min(len(self._replay), self.n_calls)

    def __call__(self, x, **extras) -> float:
        """Value at x (d,), physical units; extras are JSON-able fields added to a new record."""
        if self.n_calls >= self.budget:
            raise BudgetExhausted(f"{self.method}: budget of {self.budget} calls used")
        x = np.asarray(x, dtype=float).reshape(-1)
        i = self.n_calls
        if i < len(self._replay):
            rec = self._replay[i]
            du = (x - np.asarray(rec["x"], float)) / (self.upper - self.lower)
            if int(rec.get("call", -1)) != i or not np.all(np.abs(du) <= _REPLAY_TOL):
                raise ConfigError(
                    f"history {self.path}: call {i} asks for x = {x.tolist()} but the file "
                    f"recorded {rec['x']}; it belongs to other settings (delete it to restart)"
                )
            self.records.append(rec)
            return _f_of(rec)
        t0 = time.perf_counter()
        error = None
        try:
            f = float(np.asarray(self.fun(x)))
        except SimulationError as e:  # a failed simulation is a data point, not a crash
            f, error = float("nan"), str(e)
        rec = {"method": self.method, "seed": self.seed, "call": i, "x": x.tolist(),
               "f": f if math.isfinite(f) else None, "wall_s": time.perf_counter() - t0}
        if error is not None:
            rec["error"] = error
        rec.update(extras)
        if self.path is not None:
            append_jsonl(self.path, rec)
        self.records.append(rec)
        return f if math.isfinite(f) else float("nan")

    def result(self, stop_reason: str) -> OptimizeResult:
        """OptimizeResult from the records so far (best = smallest finite f)."""
        f = np.array([_f_of(r) for r in self.records], dtype=float)
        ok = np.isfinite(f)
        if ok.any():
            k = int(np.flatnonzero(ok)[np.argmin(f[ok])])
            x_best, f_best = np.asarray(self.records[k]["x"], float), float(f[k])
        else:
            x_best, f_best = np.full(self.lower.shape, np.nan), float("inf")
        return OptimizeResult(x_best=x_best, f_best=f_best, n_calls=self.n_calls,
                              history=list(self.records), stop_reason=stop_reason,
                              method=self.method, seed=self.seed)
