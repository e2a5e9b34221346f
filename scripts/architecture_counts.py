"""The counts docs/architecture.md states, from the code as it is.

    python scripts/architecture_counts.py

- import circles between modules (tests/test_layers.py's graph: lazy and TYPE_CHECKING
  imports included);
- functions longer than 80 lines (definition to last line, nested ones on their own);
- attribute names the C kernels (ego/_native.c's FIELDS table) read or write on Python
  objects (the records they take), and how many of them are private (``_name``);
- classes deeper than base -> concrete: an ego class with two or more ego classes above it
  in a chain (exceptions counted apart: their hierarchies are the error vocabulary).
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]


def long_functions(limit: int = 80) -> list[tuple[str, str, int]]:
    out = []
    for path in sorted((ROOT / "ego").rglob("*.py")):
        for n in ast.walk(ast.parse(path.read_text())):
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.end_lineno is not None:
                length = n.end_lineno - n.lineno + 1
                if length > limit:
                    out.append((str(path.relative_to(ROOT)), n.name, length))
    return out


def c_fields() -> list[tuple[str, str]]:
    """(record, field) of ego/_native.c's FIELDS table: what the glue kernels read and write."""
    text = (ROOT / "ego" / "_native.c").read_text()
    return re.findall(r'\{"([\w.]+)", (?:&\w+|NULL), "(\w+)"\}', text)


def deep_classes() -> tuple[list[str], list[str]]:
    """(classes, exceptions) with two or more ego classes above them in a chain."""
    import ego

    for info in pkgutil.walk_packages(ego.__path__, "ego."):
        if info.name.endswith("__main__") or info.name == "ego._entry":
            continue
        try:
            importlib.import_module(info.name)
        except Exception:  # noqa: BLE001 - an optional extra (ray, torch...) missing: its classes are not counted
            pass
    seen: dict[type, int] = {}

    def depth(cls: type) -> int:
        if cls not in seen:
            ours = [b for b in cls.__bases__ if b.__module__.startswith("ego")]
            seen[cls] = 1 + max((depth(b) for b in ours), default=0)
        return seen[cls]

    classes = {
        c
        for m in list(sys.modules.values())
        if getattr(m, "__name__", "").startswith("ego")
        for c in vars(m).values()
        if isinstance(c, type) and c.__module__.startswith("ego")
    }
    deep = sorted(f"{c.__module__}.{c.__qualname__} ({depth(c)})" for c in classes if depth(c) >= 3)
    errors = [d for d in deep if issubclass(_by_name(d, classes), BaseException)]
    return [d for d in deep if d not in errors], errors


def _by_name(text: str, classes) -> type:
    name = text.rsplit(" (", 1)[0]
    return next(c for c in classes if f"{c.__module__}.{c.__qualname__}" == name)


def main() -> int:
    from test_layers import _module_graph, import_circles

    circles = import_circles(_module_graph())
    print(f"import circles between modules: {len(circles)}")
    longs = long_functions()
    print(f"functions over 80 lines: {len(longs)}")
    for path, name, n in longs:
        print(f"  {path} {name} {n}")
    fields = c_fields()
    names = sorted({name for _, name in fields})
    records = sorted({record for record, _ in fields})
    private = [n for n in names if n.startswith("_")]
    print(
        f"attribute names read or written from C: {len(names)} ({len(fields)} fields of {len(records)} records),"
        f" private: {len(private)} ({', '.join(private)})"
    )
    deep, errors = deep_classes()
    print(f"classes deeper than base -> concrete: {len(deep)} (exceptions apart: {len(errors)})")
    for d in deep:
        print(f"  {d}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
