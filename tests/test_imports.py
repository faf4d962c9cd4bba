"""Every import of a jtire module in the package resolves, function-level ones included (those run only
when their function does, so a moved module can break a long job at its end: a calibration once
failed 8 minutes in on a lazy `from ..experiments.program import reverse_mode` the move missed)."""

import ast
import importlib
import importlib.util

from .conftest import REPO

ROOTS = (("jtire", "jtire"), ("calibration", "jtire.calibration"), ("surrogates", "jtire.surrogates"))


def _imports():
    for root, pkg in ROOTS:
        for f in sorted((REPO / root).rglob("*.py")):
            parts = list(f.relative_to(REPO / root).with_suffix("").parts)
            is_init = parts[-1] == "__init__"
            mod = ".".join([pkg] + (parts[:-1] if is_init else parts))
            package = mod if is_init else mod.rsplit(".", 1)[0]
            for n in ast.walk(ast.parse(f.read_text())):
                if isinstance(n, ast.ImportFrom):
                    name = importlib.util.resolve_name("." * n.level + (n.module or ""), package) if n.level else n.module
                    if name.startswith("jtire"):
                        yield f"{f.relative_to(REPO)}:{n.lineno}", name, [a.name for a in n.names]
                elif isinstance(n, ast.Import):
                    for a in n.names:
                        if a.name.startswith("jtire"):
                            yield f"{f.relative_to(REPO)}:{n.lineno}", a.name, []


def test_every_jtire_import_resolves():
    bad = []
    for where, name, names in _imports():
        try:
            m = importlib.import_module(name)
        except Exception as e:  # noqa: BLE001 - any failure is a broken import
            bad.append(f"{where}: {name}: {e!r}")
            continue
        for a in names:
            if a != "*" and not hasattr(m, a) and importlib.util.find_spec(f"{name}.{a}") is None:
                bad.append(f"{where}: {name} has no {a}")
    assert not bad, "\n".join(bad)

