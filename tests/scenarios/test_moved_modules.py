"""ego.scenarios.trace, .metrics and .traffic_log moved to ego.results: the old names still
import (users' scripts) with a DeprecationWarning naming the new module, and nothing of the
project imports through them."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MOVED = ("trace", "metrics", "traffic_log")
OLD = {f"ego.scenarios.{n}" for n in MOVED}

CHECK = """
import warnings
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    from ego.scenarios import {name} as old
import ego.results.{name} as new
w = [c for c in caught if issubclass(c.category, DeprecationWarning) and "ego.scenarios.{name}" in str(c.message)]
print(len(w), old is new, w[0].filename if w else "", str(w[0].message) if w else "")
"""


@pytest.mark.parametrize("name", MOVED)
def test_the_old_name_warns_and_is_the_new_module(name):
    out = subprocess.run(
        [sys.executable, "-c", CHECK.format(name=name)], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.split(" ", 3)
    count, same, filename, message = out
    assert count == "1" and same == "True"
    assert filename == "<string>"  # the warning points at the importing line, not at importlib
    assert f"ego.results.{name}" in message


def imports_through_the_old_names(path: Path) -> list[int]:
    lines = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            lines += [node.lineno for a in node.names if a.name in OLD]
        elif isinstance(node, ast.ImportFrom) and node.module:
            if node.module in OLD or (node.module == "ego.scenarios" and any(a.name in MOVED for a in node.names)):
                lines.append(node.lineno)
    return lines


def test_the_check_finds_an_old_import(tmp_path):
    f = tmp_path / "x.py"
    f.write_text("from ego.scenarios import metrics as m\nfrom ego.scenarios.trace import Column\nimport ego.results\n")
    assert imports_through_the_old_names(f) == [1, 2]


def test_nothing_imports_through_the_old_names():
    here = Path(__file__).resolve()
    files = [p for d in ("ego", "tests", "scenarios", "benchmarks") for p in (ROOT / d).rglob("*.py") if p != here]
    found = {str(p.relative_to(ROOT)): imports_through_the_old_names(p) for p in files}
    assert {k: v for k, v in found.items() if v} == {}
