"""ego's pytest plugin: scenario runs as test items in a user's own pytest.

Registered as the ``pytest11`` entry point ``ego`` (loaded by every pytest of an environment
where ego is installed; ``-p ego.pytest_plugin`` loads it explicitly). It does nothing to a
test suite that does not ask for it:

* a marker on a test function runs a scenario once per seed before the function's body::

      @pytest.mark.ego_scenario(scenario="cut-in", controller="pid", params={"cut_in_gap": 10},
                                seeds=[0, 1], require=["keep_gap: always (gap_front >= 2 m)"])
      def test_cut_in(ego_result):          # ego_result: the run (ego.results.RunResult)
          assert ego_result.metrics["final_speed"] > 15

  one item per seed (``test_cut_in[seed0]``...); ``require`` adds requirements to the
  scenario's defaults (``defaults=False``: only these); ``params`` are ``--set`` values;
* with ``--ego-xosc`` (or the ini option ``ego_xosc = true``) every ``.xosc`` file under the
  collected paths is an item per seed (ini ``ego_seeds``, default ``0``) with the controller
  of ini ``ego_controller`` (default ``pid``) and the scenario's default requirements; a
  variation file (``ParameterValueDistribution``) is an item per row and seed, the rows
  ``ego sweep FILE.xosc`` runs (ini ``ego_sample``: a seeded subsample of them).

An item fails when a requirement is violated (robustness < 0) or the run did not complete;
its message names the violated requirement, its robustness, its first violation time and
the ``ego run`` command that reproduces it. Every item's metrics go to its
``user_properties`` (``ego.<metric>``: JUnit XML ``<property>`` elements with
``--junitxml``), which pytest-xdist carries from its workers. ``--ego-record failed`` runs a
failing item once more with a recording (the run is deterministic per seed) into
``--ego-record-dir`` (default ``ego-recordings``).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest

MARKER = "ego_scenario"
#: the metrics every item reports as JUnit properties (besides every requirement's robustness)
PROPERTIES = (
    "status",
    "collision",
    "collision_preventable",
    "min_gap",
    "min_gap_front",
    "min_ttc",
    "min_ttc_front",
    "max_decel",
    "final_speed",
    "sim_time",
)


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("ego", "ego scenario tests")
    group.addoption(
        "--ego-xosc", action="store_true", default=None, help="collect every .xosc file as ego scenario items"
    )
    group.addoption(
        "--ego-record",
        choices=("none", "failed"),
        default="none",
        help="failed: keep a Rerun recording of each failing ego item (default none)",
    )
    group.addoption(
        "--ego-record-dir", default="ego-recordings", help="where --ego-record writes (default %(default)s)"
    )
    parser.addini("ego_xosc", "collect every .xosc file as ego scenario items", type="bool", default=False)
    parser.addini("ego_controller", "the controller of collected .xosc items", default="pid")
    parser.addini("ego_seeds", "the seeds of collected .xosc items (space-separated)", type="args", default=["0"])
    parser.addini(
        "ego_sample",
        "collected variation files: a seeded subsample (seed 0) of this many rows (default 0: every row)",
        default="0",
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        f"{MARKER}(scenario, controller, params=None, seeds=(0,), require=None, defaults=True): "
        "run an ego scenario per seed before the test; fail on a violated requirement",
    )


# -- the run and its verdict -----------------------------------------------------------------


class ScenarioCase:
    """One run an item stands for: scenario, controller, ``--set`` values, seed, requirements
    (``None``: the scenario's defaults; else (name, formula) pairs)."""

    def __init__(
        self,
        scenario: str,
        controller: str,
        params: Mapping[str, Any] | None,
        seed: int,
        require: Sequence[str] | None,
        defaults: bool = True,
    ) -> None:
        from ego.requirements import from_options, with_defaults

        self.scenario, self.controller, self.seed = str(scenario), str(controller), int(seed)
        self.params = {str(k): str(v).lower() if isinstance(v, bool) else str(v) for k, v in (params or {}).items()}
        texts = list(require or ())
        self.extra = tuple(from_options(texts).items()) if texts else ()
        if defaults:
            self.requirements = with_defaults(self.scenario, texts)
        else:
            self.requirements = self.extra

    def spec(self, record: str | None = None) -> Any:
        from ego.runner import RunSpec

        return RunSpec(
            self.scenario, self.controller, self.seed, self.params, record=record, requirements=self.requirements
        )

    def command(self) -> str:
        """The ``ego run`` command that reproduces this run."""
        from ego.runner import run_command

        return run_command(self.scenario, self.controller, self.seed, self.params, self.extra)


class ScenarioFailure(Exception):
    """An ego item's verdict: the run did not pass."""


def _run(case: ScenarioCase) -> Any:
    from ego.runner import run

    return run(case.spec())


def _properties(result: Any) -> list[tuple[str, Any]]:
    m = result.metrics
    out: list[tuple[str, Any]] = []
    for name in PROPERTIES:
        if name in m and m[name] is not None:
            value = m[name]
            out.append((f"ego.{name}", value if isinstance(value, (str, bool, int, float)) else str(value)))
    for name, rob in (m.get("requirements") or {}).items():
        out.append((f"ego.requirements.{name}", rob))
    for name, at in (m.get("first_violation") or {}).items():
        if at is not None:  # a violated requirement's first violation (s)
            out.append((f"ego.first_violation.{name}", at))
    return out


def _violations(result: Any) -> list[tuple[str, float, float | None, str]]:
    """(name, robustness, first violation time, formula text) of each violated requirement."""
    first: dict[str, tuple[float, str]] = {}
    for e in result.events:
        if e.kind == "requirement" and e.text.startswith("requirement "):
            name = e.text.split()[1]
            first.setdefault(name, (e.t, e.text.partition("): ")[2]))
    times = result.metrics.get("first_violation") or {}
    out = []
    for name, rob in (result.metrics.get("requirements") or {}).items():
        if rob is not None and rob < 0.0:
            at, formula = first.get(name, (None, ""))
            out.append((name, float(rob), times.get(name, at), formula))
    return out


def verdict(case: ScenarioCase, result: Any) -> str | None:
    """The failure message of a run (None: it passed)."""
    from ego.scenarios.base import NOT_FAILED

    lines = []
    status = result.metrics.get("status")
    for name, rob, at, formula in _violations(result):
        when = "-" if at is None else f"{at:.2f} s"
        lines.append(f"requirement {name} violated: robustness {rob:g}, first violation at {when}: {formula}")
    if status not in NOT_FAILED and not (status == "collision" and lines):
        detail = result.metrics.get("status_detail") or ""
        lines.append(f"run ended with status {status}{': ' + detail if detail else ''}")
    if not lines:
        return None
    head = f"ego scenario {case.scenario} with {case.controller}, seed {case.seed}:"
    return "\n".join([head, *("  " + ln for ln in lines), f"reproduce: {case.command()}"])


def _check(item: pytest.Item, case: ScenarioCase) -> Any:
    """Run ``case`` for ``item``: its properties recorded; ScenarioFailure when it fails
    (after a recording, with ``--ego-record failed``)."""
    result = _run(case)
    item.user_properties.extend(_properties(result))
    item.user_properties.append(("ego.command", case.command()))
    message = verdict(case, result)
    if message is not None:
        if item.config.getoption("ego_record") == "failed":
            from ego.runner import run

            folder = Path(item.config.getoption("ego_record_dir"))
            folder.mkdir(parents=True, exist_ok=True)
            safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in item.name)
            path = folder / f"{safe}.rrd"
            run(case.spec(record=str(path)))
            item.user_properties.append(("ego.recording", str(path)))
            message += f"\nrecording: {path}"
        raise ScenarioFailure(message)
    return result


# -- the marker ------------------------------------------------------------------------------------


@pytest.fixture
def ego_seed() -> int:
    """The seed of an ``ego_scenario`` item (parametrised by the plugin)."""
    return 0


@pytest.fixture
def ego_result() -> Any:
    """The run of an ``ego_scenario`` item (:class:`ego.results.RunResult`), filled in by the
    plugin before the test's body runs."""
    return None


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    marker = metafunc.definition.get_closest_marker(MARKER)
    if marker is None:
        return
    seeds = [int(s) for s in marker.kwargs.get("seeds", (0,))]
    if "ego_seed" not in metafunc.fixturenames:
        metafunc.fixturenames.append("ego_seed")
    metafunc.parametrize("ego_seed", seeds, ids=[f"seed{s}" for s in seeds])


def _case_of(item: pytest.Function) -> ScenarioCase:
    marker = item.get_closest_marker(MARKER)
    assert marker is not None
    kw = dict(marker.kwargs)
    args = list(marker.args)
    scenario = kw.pop("scenario", args[0] if args else None)
    controller = kw.pop("controller", args[1] if len(args) > 1 else None)
    if scenario is None or controller is None:
        raise pytest.UsageError(f"{item.nodeid}: {MARKER} needs scenario= and controller=")
    called: dict[str, Any] = item.callspec.params if hasattr(item, "callspec") else {}
    seed = int(called.get("ego_seed", 0))
    return ScenarioCase(scenario, controller, kw.get("params"), seed, kw.get("require"), bool(kw.get("defaults", True)))


@pytest.hookimpl(tryfirst=True)
def pytest_pyfunc_call(pyfuncitem: pytest.Function) -> bool | None:
    if pyfuncitem.get_closest_marker(MARKER) is None:
        return None
    case = _case_of(pyfuncitem)
    failure = None
    try:
        result = _check(pyfuncitem, case)
    except ScenarioFailure as exc:
        failure = str(exc)
    if failure is not None:
        pytest.fail(failure, pytrace=False)
    funcargs = pyfuncitem.funcargs
    if "ego_result" in funcargs:
        funcargs["ego_result"] = result
    names = pyfuncitem._fixtureinfo.argnames
    pyfuncitem.obj(**{name: funcargs[name] for name in names})
    return True


# -- .xosc files ------------------------------------------------------------------------------------


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    if file_path.suffix != ".xosc":
        return None
    config = parent.config
    wanted = config.getoption("ego_xosc")
    if not (wanted if wanted is not None else config.getini("ego_xosc")):
        return None
    text = file_path.read_text(errors="replace")
    if "<ParameterValueDistribution" in text:
        return VariationFile.from_parent(parent, path=file_path)
    if "<Storyboard" not in text:
        return None  # a catalog, not a scenario
    return XoscFile.from_parent(parent, path=file_path)


class XoscFile(pytest.File):
    """An OpenSCENARIO file: one item per seed."""

    def collect(self) -> Iterator[pytest.Item]:
        config = self.config
        controller = str(config.getini("ego_controller"))
        for seed in config.getini("ego_seeds"):
            yield ScenarioItem.from_parent(self, name=f"seed{int(seed)}", controller=controller, seed=int(seed))


class VariationFile(pytest.File):
    """A ParameterValueDistribution file: one item per row and seed, the rows those ``ego
    sweep FILE.xosc`` runs (the combinations that meet the scenario file's value
    constraints; ini ``ego_sample``: a seeded subsample of them, as ``--sample N``)."""

    def collect(self) -> Iterator[pytest.Item]:
        from ego.params import ConfigError
        from ego.sweep.xosc import load

        config = self.config
        controller = str(config.getini("ego_controller"))
        sample = int(config.getini("ego_sample")) or None
        try:
            spec = load(str(self.path), [controller], sample=sample).spec
        except ConfigError as exc:
            raise self.CollectError(str(exc)) from None
        for i, point in enumerate(spec.listed or ()):
            values = ",".join(f"{k}={v}" for k, v in point.items())
            for seed in config.getini("ego_seeds"):
                yield ScenarioItem.from_parent(
                    self,
                    name=f"row{i}-{values}-seed{int(seed)}",
                    controller=controller,
                    seed=int(seed),
                    scenario=spec.scenario,
                    params=point,
                )


class ScenarioItem(pytest.Item):
    """One run of a collected scenario file (or of a variation file's row: ``scenario`` the
    file it varies, ``params`` the row's values)."""

    def __init__(
        self,
        *,
        controller: str,
        seed: int,
        scenario: str | None = None,
        params: Mapping[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(**kwargs)
        self.case = ScenarioCase(scenario or str(self.path), controller, params, seed, None)

    def runtest(self) -> None:
        _check(self, self.case)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> str:
        if isinstance(excinfo.value, ScenarioFailure):
            return str(excinfo.value)
        return str(super().repr_failure(excinfo))

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.path.name} with {self.case.controller}, seed {self.case.seed}"
