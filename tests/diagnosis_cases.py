"""Shared helpers of the rigid-ring diagnosis tests (test_rigid_ring_diagnosis*.py): a row edited for
a case, the diagnosis of a comparison, and a small case folder for the checks that read the shell's
own records. Their fixtures, `char` (the synthetic characterization) and `rated` (its rated row),
are in conftest.py."""

import dataclasses
import json

from jtire.rigid_ring import diagnosis as dg
from jtire.rigid_ring import validation
from jtire.rigid_ring.table import Characterization


def with_row(char, row, **q):
    """The characterization with `row` replaced by a copy whose quantities are updated by q."""
    new = dataclasses.replace(row, q=row.q | q)
    return Characterization(char.tire, tuple(new if r is row else r for r in char.rows)), new


def explain(char, row, shell, ring, char_dir=None, shell_signals=None, ring_signals=None):
    rows = validation.compare(shell, ring)
    return {d.metric: d for d in dg.explain(char, row.load_N, row.pressure_Pa, rows, char_dir, shell_signals,
                                            ring_signals)}


def write_case(root, experiment, row, result, signals=None):
    d = root / experiment / "cases" / "000"
    d.mkdir(parents=True)
    result = {"condition": {"load_N": row.load_N, "pressure_Pa": row.pressure_Pa}} | result
    (d / "result.json").write_text(json.dumps(result))
    if signals:
        keys = list(signals)
        lines = [",".join(keys)] + [",".join(f"{signals[k][i]:.17g}" for k in keys) for i in range(len(signals[keys[0]]))]
        (d / "signals.csv").write_text("\n".join(lines) + "\n")
