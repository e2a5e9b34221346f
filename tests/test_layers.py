"""ego's packages import downwards only, and no two packages import each other (directly
or through others): every import in every module of ego, lazy ones in functions included.

    foundation (params, checks, outputs, processes, native, stl)
    < models, control, sim, results, parallel, record, sumo, highway_env, geometry
    < scenarios
    < runner, plots, requirements, specs
    < compare, sweep, falsify, gym, train, docs, cli, pytest_plugin
"""

import ast
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EGO = ROOT / "ego"

LAYERS = [
    {
        "ego",
        "ego.params",
        "ego.checks",
        "ego.outputs",
        "ego.processes",
        "ego.native",
        "ego._native",
        "ego.plugins",
        "ego.usercode",
        "ego.paths",
        "ego.reaper",
        "ego.stl",
    },
    {
        "ego.models",
        "ego.control",
        "ego.fmi",
        "ego.sim",
        "ego.results",
        "ego.parallel",
        "ego.record",
        "ego.sumo",
        "ego.highway_env",
        "ego.lane_frame",
        "ego.analytic_road",
        "ego.cluster",
    },
    {"ego.scenarios", "ego.openscenario"},
    {"ego.runner", "ego.plots", "ego.requirements", "ego.specs"},
    {
        "ego.compare",
        "ego.sweep",
        "ego.falsify",
        "ego.report",
        "ego.gym",
        "ego.train",
        "ego.docs",
        "ego.cli",
        "ego.__main__",
        "ego._entry",
        "ego.pytest_plugin",
    },
]
LEVEL = {unit: i for i, layer in enumerate(LAYERS) for unit in layer}
#: modules kept at an old path for compatibility: they only re-export a lower module
SHIMS = {"ego.scenarios.trace", "ego.scenarios.traffic_log", "ego.scenarios.metrics"}


def _module(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _unit(module: str) -> str:
    """The package (or top-level module) a module belongs to: ``ego.results.trace`` ->
    ``ego.results``."""
    return ".".join(module.split(".")[:2])


def _imports(path: Path, module: str) -> set[str]:
    tree = ast.parse(path.read_text(), str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            found.add(name)
    return {n for n in found if n == "ego" or n.startswith("ego.")}


@cache
def _graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {}
    for path in sorted(EGO.rglob("*.py")):
        module = _module(path)
        graph[module] = _imports(path, module)
    return graph


def test_every_unit_of_ego_has_a_layer():
    units = {_unit(m) for m in _graph()}
    assert units - set(LEVEL) == set(), "give the new package a layer in tests/test_layers.py"


def test_no_module_imports_from_a_layer_above_it():
    wrong = []
    for module, imports in _graph().items():
        if module in SHIMS:
            continue
        for name in imports:
            if LEVEL[_unit(name)] > LEVEL[_unit(module)]:
                wrong.append(f"{module} imports {name}")
    assert wrong == []


@pytest.mark.parametrize("low", ["ego.results", "ego.parallel", "ego.models", "ego.control"])
def test_the_lower_packages_never_import_scenarios(low):
    graph = _graph()
    assert not [(m, n) for m, imps in graph.items() if _unit(m) == low for n in imps if _unit(n) == "ego.scenarios"]


def test_no_import_cycle_between_packages():
    edges: dict[str, set[str]] = {}
    for module, imports in _graph().items():
        if module in SHIMS:
            continue
        edges.setdefault(_unit(module), set()).update(
            _unit(n) for n in imports if _unit(n) not in (_unit(module), "ego")
        )
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(u: str) -> None:
        state[u] = 1
        stack.append(u)
        for v in sorted(edges.get(u, ())):
            if state.get(v) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(v) :] + [v]))
            if v not in state:
                visit(v)
        stack.pop()
        state[u] = 2

    for u in sorted(edges):
        if u not in state:
            visit(u)


def _module_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """Module -> the ego modules it imports (every import: lazy ones in functions and those
    under ``TYPE_CHECKING`` included). ``from ego.a import b`` is an edge to the module
    ``ego.a.b`` where that is a module, else to ``ego.a``."""
    paths = {_module(path, root): path for path in sorted((root / "ego").rglob("*.py"))}
    graph: dict[str, set[str]] = {}
    for module, path in paths.items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        found = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    name = ".".join(base + ([node.module] if node.module else []))
                else:
                    name = node.module or ""
                found |= {f"{name}.{a.name}" if f"{name}.{a.name}" in paths else name for a in node.names}
        graph[module] = {n for n in found if n in paths and n != module}
    return graph


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import circles between modules: each strongly connected set of two or more
    modules (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            members = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                members.append(w)
                if w == v:
                    break
            if len(members) > 1:
                circles.append(sorted(members))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(circles)


def test_no_import_circle_between_modules():
    # inside a package too: ego.a.x -> ego.a.y -> ego.a.x is a circle even though the
    # package-level graph above cannot see it
    assert import_circles(_module_graph()) == []


def test_the_circle_check_sees_a_circle_inside_a_package(tmp_path):
    pkg = tmp_path / "ego" / "results"
    pkg.mkdir(parents=True)
    (tmp_path / "ego" / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("from ego.results.a import A\n")
    (pkg / "a.py").write_text("A = 1\ndef f():\n    from ego.results import b\n")
    (pkg / "b.py").write_text("from .a import A\n")
    graph = _module_graph(tmp_path)
    assert graph["ego.results.a"] == {"ego.results.b"}
    assert import_circles(graph) == [["ego.results.a", "ego.results.b"]]


def test_the_layer_check_sees_a_wrong_import(tmp_path):
    # the checker itself: an upward import written into a results module is found
    path = tmp_path / "ego" / "results" / "bad.py"
    path.parent.mkdir(parents=True)
    path.write_text("def f():\n    from ego.scenarios import SCENARIOS\n")
    imports = _imports(path, "ego.results.bad")
    assert imports == {"ego.scenarios"}
    assert LEVEL[_unit("ego.scenarios")] > LEVEL[_unit("ego.results.bad")]


if __name__ == "__main__":  # python tests/test_layers.py: the count docs/architecture.md states
    circles = import_circles(_module_graph())
    print(f"import circles between modules of ego: {len(circles)}")
    for circle in circles:
        print("  " + " <-> ".join(circle))
