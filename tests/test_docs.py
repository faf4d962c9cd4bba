"""The documentation site: it builds with `mkdocs build --strict` (a broken link, a missing page or an unresolved
API reference fails), every object the API page names is documented, and every page is in the navigation."""

import ast
import re
import subprocess
import sys

import pytest

from .conftest import REPO

API = REPO / "docs" / "api.md"
ROOTS = {"jtire": REPO / "jtire", "calibration": REPO / "calibration", "surrogates": REPO / "surrogates"}


def _module_file(dotted: str):
    parts = dotted.split(".")
    base = ROOTS.get(parts[0])
    if base is None:
        return None
    path = base.joinpath(*parts[1:])
    for cand in (path.with_suffix(".py"), path / "__init__.py"):
        if cand.is_file():
            return cand
    return None


def _resolve(target: str):
    """(file, [name, ...] inside it) of a `::: target` line: the longest prefix that is a module."""
    parts = target.split(".")
    for k in range(len(parts), 0, -1):
        f = _module_file(".".join(parts[:k]))
        if f is not None:
            return f, parts[k:]
    raise AssertionError(f"docs/api.md: ::: {target} names no module of the source tree")


def _undocumented(node, where: str) -> list:
    """Public functions and classes (and a class's public methods) under node without a docstring."""
    out = []
    for child in getattr(node, "body", []):
        if isinstance(child, (ast.FunctionDef, ast.ClassDef)) and not child.name.startswith("_"):
            if not ast.get_docstring(child):
                out.append(f"{where}.{child.name}")
            if isinstance(child, ast.ClassDef):
                out += [m for m in _undocumented(child, f"{where}.{child.name}") if m.count(".") > where.count(".") + 1]
    return out


def test_every_api_object_is_documented():
    targets = re.findall(r"^::: ([\w.]+)\s*$", API.read_text(), flags=re.M)
    assert len(targets) >= 15  # the page is not empty
    missing = []
    for target in targets:
        path, names = _resolve(target)
        tree = ast.parse(path.read_text())
        if not names:  # a whole module: its docstring and every public member's
            if not ast.get_docstring(tree):
                missing.append(f"{target} (module)")
            missing += _undocumented(tree, target)
            continue
        node = tree
        for name in names:
            node = next((n for n in node.body if isinstance(n, (ast.FunctionDef, ast.ClassDef)) and n.name == name), None)
            if node is None:
                break
        if node is None:
            missing.append(f"{target} (not found)")
            continue
        if not ast.get_docstring(node):
            missing.append(target)
        if isinstance(node, ast.ClassDef):
            missing += [m for m in _undocumented(node, target) if m.count(".") == target.count(".") + 1]
    assert not missing, f"undocumented in the API reference (docs/api.md): {missing}"


def test_every_page_is_in_the_navigation():
    nav = (REPO / "mkdocs.yml").read_text()
    pages = sorted(p.relative_to(REPO / "docs").as_posix() for p in (REPO / "docs").rglob("*.md"))
    assert pages and all(f": {p}" in nav for p in pages), [p for p in pages if f": {p}" not in nav]


def test_site_builds_strict(tmp_path):
    """`mkdocs build --strict` (CI installs the docs extra; elsewhere: pip install -e '.[docs]')."""
    pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("mkdocstrings", reason="the docs extra: pip install -e '.[docs]'")
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                       cwd=REPO, capture_output=True, text=True, timeout=300,
                       env={**__import__("os").environ, "NO_MKDOCS_2_WARNING": "1"})
    assert r.returncode == 0, r.stderr[-3000:]
    assert (tmp_path / "site" / "api" / "index.html").is_file()
    assert "load_run_config" in (tmp_path / "site" / "api" / "index.html").read_text()
