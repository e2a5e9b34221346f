"""A run is resolved once: ``resolve(RunSpec) -> ResolvedRun`` checks every name and value,
is frozen and picklable, and nothing downstream (the CLI, compare's and sweep's workers,
the plots, the exports) configures the run again."""

import dataclasses
import pickle

import pytest

from ego.cli import main
from ego.compare import compare
from ego.parallel.executor import InlineExecutor
from ego.params import ConfigError
from ego.runner import ResolvedRun, RunSpec, parameter_namespace, resolve, run
from ego.sweep.pipeline import RunTask, execute


@pytest.fixture
def counted(point_mass, monkeypatch):
    """How many times the point-mass scenario's configuration was resolved: every
    resolution checks the configuration once (``check_config``), nothing else does."""
    calls = []
    original = point_mass.check_config.__func__

    def check_config(cls, config):
        calls.append(config)
        return original(cls, config)

    monkeypatch.setattr(point_mass, "check_config", classmethod(check_config))
    return calls


def test_ego_run_resolves_once(counted, capsys):
    assert main(["run", "point-mass", "-c", "pid", "--set", "duration=1"]) == 0
    assert "point-mass with pid" in capsys.readouterr().out
    assert len(counted) == 1


def test_ego_run_json_resolves_once(counted, capsys, tmp_path):
    trace = tmp_path / "t.csv"
    assert main(["run", "point-mass", "-c", "fuzzy", "--set", "duration=1", "--json", "--trace", str(trace)]) == 0
    assert trace.exists()
    assert len(counted) == 1


def test_compare_resolves_each_controller_once_and_its_workers_never(counted, tmp_path):
    rows = compare(
        "point-mass", ["pid", "fuzzy"], 3, {"duration": 1.0}, tmp_path / "out", progress=None, executor=InlineExecutor()
    )
    assert [r.status for r in rows] == ["completed"] * 6
    assert len(counted) == 2  # one per controller; not per seed, not in the workers, not for the plots
    assert (tmp_path / "out" / "metrics.md").exists() and (tmp_path / "out" / "speed.png").exists()


def test_a_worker_runs_the_resolved_run_without_resolving_it(counted, tmp_path):
    resolved = resolve(RunSpec("point-mass", "pid", 2, {"duration": 1.0}))
    assert len(counted) == 1
    # through a pickle, as a process or Ray worker receives it
    task = pickle.loads(
        pickle.dumps(RunTask(resolved, keep=("speed",), details=True, record_failed=str(tmp_path / "x.rrd")))
    )
    row = execute(task)
    assert row.status == "completed" and row.error == ""
    assert len(counted) == 1
    # the same metrics as a run from the spec (which resolves it: one more)
    direct = run(RunSpec("point-mass", "pid", 2, {"duration": 1.0}))
    assert len(counted) == 2
    flat = {k: v for k, v in row.metrics.items() if k != "wall_time"}
    from ego.results.metrics import flatten

    assert flat == {k: v for k, v in flatten(direct.metrics).items() if k != "wall_time"}
    assert list(row.traces) == ["t", "speed"]


def test_the_resolved_run_is_frozen_picklable_and_complete(point_mass):
    r = resolve(RunSpec("point-mass", "fuzzy", 1, {"duration": "2", "ref_speed": 12}))
    assert r.scenario_cls is point_mass and r.controller.name == "fuzzy"
    assert r.config.duration == 2.0 and r.config.ref_speed == 12.0
    assert type(r.controller_params).__name__ == "FuzzyParams"
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.config = None  # type: ignore[misc]
    back = pickle.loads(pickle.dumps(r))
    assert back == r and back.scenario_cls is point_mass
    assert [m.name for m in r.metrics_declared()][:1] and r.plots()


def test_with_outputs_changes_only_outputs_and_checks_them(point_mass, tmp_path):
    r = resolve(RunSpec("point-mass", "pid", 0, {"duration": 1.0}))
    s = r.with_outputs(seed=5, record=str(tmp_path / "a.rrd"), label="pid@x")
    assert (s.seed, s.name, s.config) == (5, "pid@x", r.config)
    with pytest.raises(ConfigError, match="bad value for seed"):
        r.with_outputs(seed=-1)
    with pytest.raises(ConfigError, match=r"\.rrd"):
        r.with_outputs(record=str(tmp_path / "a.txt"))
    with pytest.raises(ConfigError, match="cannot change 'overrides'"):
        r.with_outputs(overrides={"duration": 2.0})


def test_resolve_names_the_bad_value_before_anything_is_built(point_mass):
    with pytest.raises(ConfigError, match="bad value for ref_speed"):
        resolve(RunSpec("point-mass", "pid", 0, {"ref_speed": 99}))
    with pytest.raises(ConfigError, match="unknown parameter 'ref_sped'.*did you mean 'ref_speed'"):
        resolve(RunSpec("point-mass", "pid", 0, {"ref_sped": 1}))


def test_one_parameter_namespace(point_mass):
    names = parameter_namespace("point-mass", ["pid", "fuzzy"])
    assert {"duration", "ref_speed", "mass"} <= set(names)  # the scenario's
    from ego.control import controller_spec
    from ego.params import describe

    for c in ("pid", "fuzzy"):
        assert {i.name for i in describe(controller_spec(c).params)} <= set(names)
    assert names["duration"].unit == "s"
    with pytest.raises(ConfigError, match="unknown controller"):
        parameter_namespace("point-mass", ["nope"])


def test_resolved_runs_are_what_ego_runner_builds(point_mass):
    r = resolve(RunSpec("point-mass", "pid", 0, {"duration": 1.0}))
    assert isinstance(r, ResolvedRun)
    from ego.runner import build

    scenario = build(r)
    assert scenario.config is r.config
