"""The evaluation history of a tire calibration: batches of simulator runs, recorded and replayed.

Same idea as `calibration.history` (one JSON line per evaluation, fsynced the moment it is
known; a killed run resumes by replaying the file), extended to batches of points with several
responses, and to Jacobian calls. One record per evaluated point:

    {"method": "arsm", "seed": 0, "eval": 7, "batch": 1, "phase": "minimizer",
     "theta": [...d], "params": {name: SI value}, "responses": {name: SI value or null},
     "errors_pct": {name: ...}, "total_error_pct": 12.3, "cost_forward": 1.0,
     "batch_wall_s": 0.8, "batch_size": 4, "piece": 0, ...extras}

A Jacobian call adds "jacobian": [[...d] x m] and costs the simulator's stated forward-run
equivalents. A batch goes to the simulator in pieces of its `points_per_call` (all at once when
that is 0); the records of a piece are written as soon as it returns ("batch_wall_s" and
"batch_size" are the piece's). Resume: asked for a batch, the log hands back the recorded rows for
the points it already holds (checking that each requested theta is the recorded one) and sends
only the missing points to the simulator; the optimizers are deterministic given their records,
so nothing is lost or repeated, and a kill inside a batch loses only the piece in flight.

The output folder also carries `fingerprint.json`: everything that determines the numbers
(config, tire, simulator description, code version). A run in a folder made by other settings
refuses with one line naming what differs.
"""

import json
import time
from pathlib import Path

import numpy as np

from ..history import BudgetExhausted
from .simulator import check_batch, pieces
from .targets import percent_errors
from ...errors import ConfigError
from ...fingerprint import claim_folder
from ...io import append_jsonl, atomic_write_json, atomic_write_text, read_jsonl

__all__ = ["RunLog", "check_fingerprint", "BudgetExhausted", "load_records", "records_arrays"]

# A replayed theta must match the requested one to this many log-box widths (round-off only).
_REPLAY_TOL = 1e-9


def check_fingerprint(out_dir, fingerprint: dict, name: str = "fingerprint.json") -> None:
    """Store the fingerprint in out_dir, or check it against the stored one (one-line error naming
    the fields that differ): `jtire.fingerprint.claim_folder`, as sweeps and characterizations do."""
    claim_folder(out_dir, fingerprint, name)


def load_records(path) -> list:
    """Complete records of a history file (a torn last line is dropped)."""
    return read_jsonl(path)


def records_arrays(records, names):
    """(thetas (n, d), responses (n, m) with nan for failed points) from records."""
    th = np.array([r["theta"] for r in records], dtype=float)
    y = np.array([[np.nan if r["responses"].get(n) is None else r["responses"][n] for n in names]
                  for r in records], dtype=float)
    return th.reshape(len(records), -1), y.reshape(len(records), len(names))


def _drop_torn_tail(path, n_complete):
    """A kill during an append leaves a torn last line; the next append would glue onto it and
    hide every later record from read_jsonl. Rewrite the file with its complete records only."""
    lines = path.read_text().splitlines(keepends=True)
    if len(lines) > n_complete or (lines and not lines[-1].endswith("\n")):
        keep = "".join(lines[:n_complete])
        if keep and not keep.endswith("\n"):
            keep += "\n"
        atomic_write_text(path, keep)


class RunLog:
    """Counts, records and replays the simulator calls of one optimizer run.

    Args:
        sim: the Simulator; targets, weights: for the errors written into each record.
        method, seed: written into every record and checked on replay.
        budget: the most points (evaluate rows) this run may use; Jacobian calls count as
            their forward-run equivalents against `forward_budget` instead.
        path: JSON-lines history (None: in memory only).
    """

    def __init__(self, sim, targets, weights, method: str, seed: int, budget: int, path=None,
                 forward_budget: float = float("inf")):
        self.sim, self.targets = sim, tuple(targets)
        self.weights = np.ones(len(self.targets)) if weights is None else np.asarray(weights, float)
        self.method, self.seed, self.budget = str(method), int(seed), int(budget)
        self.forward_budget = float(forward_budget)
        self.path = None if path is None else Path(path)
        self.records: list = []
        self._replay = [] if self.path is None else read_jsonl(self.path)
        if self.path is not None and self.path.exists():
            _drop_torn_tail(self.path, len(self._replay))
        for r in self._replay:
            if r.get("method") != self.method or int(r.get("seed", -1)) != self.seed:
                raise ConfigError(f"history {self.path}: holds method={r.get('method')!r} "
                                  f"seed={r.get('seed')}, not method={self.method!r} "
                                  f"seed={self.seed}; use another --out folder")
        self.n_batches = 0

    # -- counts ------------------------------------------------------------------------------
    @property
    def n_evaluations(self) -> int:
        return sum(1 for r in self.records if "jacobian" not in r)

    @property
    def remaining(self) -> int:
        return self.budget - self.n_evaluations

    @property
    def cost_forward(self) -> float:
        return float(sum(r.get("cost_forward", 1.0) for r in self.records))

    @property
    def wall_s(self) -> float:
        """Simulator wall time of the records, each batch counted once."""
        seen, total = set(), 0.0
        for r in self.records:  # a batch's pieces each have their own wall time
            key = (r["batch"], r.get("piece", 0))
            if key not in seen:
                seen.add(key)
                total += float(r.get("batch_wall_s", 0.0))
        return total

    @property
    def n_replayed(self) -> int:
        return min(len(self._replay), len(self.records))

    # -- calls -------------------------------------------------------------------------------
    def _record(self, i, theta, values, phase, batch, wall, size, cost, extra):
        values = np.asarray(values, float)
        err = percent_errors(values, self.targets)
        ok = bool(np.all(np.isfinite(values)))
        rec = {"method": self.method, "seed": self.seed, "eval": int(i),
               "batch": batch, "phase": phase, "theta": np.asarray(theta, float).tolist(),
               "params": self.sim.space.values(theta),
               "responses": {t.name: (float(v) if np.isfinite(v) else None)
                             for t, v in zip(self.targets, values)},
               "errors_pct": {t.name: (float(e) if np.isfinite(e) else None)
                              for t, e in zip(self.targets, err)},
               "total_error_pct": float(np.sum(err * self.weights)) if ok else None,
               "cost_forward": float(cost), "batch_wall_s": float(wall), "batch_size": int(size)}
        rec.update(extra)
        return rec

    def _replayed(self, i, theta):
        rec = self._replay[i]
        du = (np.asarray(theta, float) - np.asarray(rec["theta"], float)) / self.sim.space.width
        if int(rec.get("eval", -1)) != i or not np.all(np.abs(du) <= _REPLAY_TOL):
            raise ConfigError(f"history {self.path}: evaluation {i} asks for another point than "
                              "the one recorded; the file belongs to other settings (use another "
                              "--out folder)")
        return rec

    def evaluate(self, thetas, phase, extras=None) -> np.ndarray:
        """Responses (n, m) of the points thetas (n, d), one batch (sent in pieces of the simulator's
        points_per_call); replayed where recorded.

        phase: a label for every record (str) or one per point (list of n str).
        extras: optional list of n dicts of JSON-able fields for the records. Raises
        BudgetExhausted when the budget (points, or forward-run equivalents) cannot take the whole
        batch (callers trim first).
        """
        thetas = np.atleast_2d(np.asarray(thetas, float))
        n = thetas.shape[0]
        if n > self.remaining:
            raise BudgetExhausted(f"{self.method}: budget of {self.budget} evaluations used")
        if self.cost_forward + n * self.sim.cost_forward_equivalents.get("evaluate", 1.0) > self.forward_budget:
            raise BudgetExhausted(f"{self.method}: forward budget {self.forward_budget:g} used")
        extras = extras or [{}] * n
        phases = [phase] * n if isinstance(phase, str) else list(phase)
        start = len(self.records)
        out = np.full((n, len(self.targets)), np.nan)
        todo = []
        for i in range(n):
            if start + i < len(self._replay):
                rec = self._replayed(start + i, thetas[i])
                if "jacobian" in rec:
                    raise ConfigError(f"history {self.path}: record {start + i} is a Jacobian "
                                      "call where an evaluation was asked; use another folder")
                out[i] = [np.nan if rec["responses"][t.name] is None else rec["responses"][t.name]
                          for t in self.targets]
            else:
                todo.append(i)
        batch = self.n_batches
        self.n_batches += 1
        for i in range(n):  # the replay is a prefix of the run: recorded points come first
            if i not in todo:
                self.records.append(self._replay[start + i])
        # the new points go to the simulator in pieces of its points_per_call, each recorded the
        # moment it returns (in evaluation order): a kill loses at most the piece in flight
        cost = self.sim.cost_forward_equivalents.get("evaluate", 1.0)
        for c, (a, b) in enumerate(pieces(self.sim, len(todo))):
            idx = todo[a:b]
            t0 = time.perf_counter()
            vals = check_batch(self.sim, thetas[idx], self.sim.evaluate(thetas[idx]))
            wall = time.perf_counter() - t0
            failed = getattr(self.sim, "last_failures", None) or {}
            for j, i in enumerate(idx):
                out[i] = vals[j]
                why = {"failures": failed[j]} if j in failed else {}
                rec = self._record(start + i, thetas[i], vals[j], phases[i], batch, wall, len(idx), cost,
                                   {"piece": c, **extras[i], **why})
                if self.path is not None:
                    append_jsonl(self.path, rec)
                self.records.append(rec)
        return out

    def jacobian(self, theta, phase: str = "jacobian", extra=None):
        """(values (m,), J (m, d)) at theta (d,) from the simulator, recorded; replayed if held."""
        cost = float(self.sim.cost_forward_equivalents.get("jacobian", np.nan))
        if self.cost_forward + (cost if np.isfinite(cost) else 0.0) > self.forward_budget:
            raise BudgetExhausted(f"{self.method}: forward budget {self.forward_budget:g} used")
        i = len(self.records)
        batch = self.n_batches
        self.n_batches += 1
        if i < len(self._replay):
            rec = self._replayed(i, theta)
            if "jacobian" not in rec:
                raise ConfigError(f"history {self.path}: record {i} is an evaluation where a "
                                  "Jacobian call was asked; use another --out folder")
            self.records.append(rec)
            vals = np.array([np.nan if rec["responses"][t.name] is None else rec["responses"][t.name]
                             for t in self.targets])
            return vals, np.array(rec["jacobian"], float)
        t0 = time.perf_counter()
        vals, jac = self.sim.jacobian(np.asarray(theta, float))
        wall = time.perf_counter() - t0
        # a simulator that measures its Jacobian's price (the shell model) states it after the call
        cost = float(self.sim.cost_forward_equivalents.get("jacobian", np.nan))
        vals, jac = np.asarray(vals, float), np.asarray(jac, float)
        rec = self._record(i, theta, vals, phase, batch, wall, 1, cost if np.isfinite(cost) else 0.0,
                           {"jacobian": jac.tolist(), **(extra or {})})
        if self.path is not None:
            append_jsonl(self.path, rec)
        self.records.append(rec)
        return vals, jac
