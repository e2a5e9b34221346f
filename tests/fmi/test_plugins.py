"""Plugins: a package installed into a temporary environment (pip install --target, on the
PYTHONPATH) registers a controller, a scenario, a metric and a backend through the
``ego.controllers``, ``ego.scenarios``, ``ego.metrics`` and ``ego.backends`` entry points;
ego run, ego compare --jobs 2 and ego sweep --engine ray find them, their workers importing
the plugin themselves."""

import csv
import json
import os
import subprocess
import sys

import pyarrow.parquet as pq
import pytest
from process_group import survivors

pytestmark = pytest.mark.sumo

PYPROJECT = """
[build-system]
requires = ["setuptools"]
build-backend = "setuptools.build_meta"

[project]
name = "ego-demo-plugin"
version = "0.1"

[project.entry-points."ego.controllers"]
demo-pid = "ego_demo_plugin:DemoPID"

[project.entry-points."ego.scenarios"]
demo-brake = "ego_demo_plugin:DemoBrake"

[project.entry-points."ego.metrics"]
demo-rows = "ego_demo_plugin:DEMO_ROWS"

[project.entry-points."ego.backends"]
demo-road = "ego_demo_plugin:DEMO_ROAD"
demo-bare = "ego_demo_plugin:DEMO_BARE"
"""

MODULE = '''
"""A plugin: ego's pid under another name, emergency-brake as a scenario of its own, a
metric (the trace's rows) and two backends (SUMO under other names, one of them declaring
no scripted actors)."""
from ego.control.pid import PIDController, PIDParams
from ego.results.metrics import TraceMetric
from ego.results.trace import Metric
from ego.scenarios import EmergencyBrake
from ego.sim.registry import Backend, Capabilities

DEMO_ROWS = TraceMetric(Metric("demo_rows", "-", "rows of the trace"), ("t",), lambda trace: len(trace["t"]))
DEMO_ROAD = Backend("demo-road", "ego.sumo.bridge:make_sim", Capabilities(any_network=True))
DEMO_BARE = Backend("demo-bare", "ego.sumo.bridge:make_sim", Capabilities(any_network=True, scripted_actors=False))


class DemoPID(PIDController):
    """the demo plugin's pid"""

    Params = PIDParams
    task = "tracking"


class DemoBrake(EmergencyBrake):
    """emergency-brake, from the demo plugin"""

    name = "demo-brake"
'''


@pytest.fixture(scope="module")
def plugin_env(tmp_path_factory):
    """Environment variables of a Python that has the plugin installed."""
    root = tmp_path_factory.mktemp("plugin")
    pkg = root / "src" / "ego_demo_plugin"
    pkg.mkdir(parents=True)
    (root / "src" / "pyproject.toml").write_text(PYPROJECT)
    (pkg / "__init__.py").write_text(MODULE)
    site = root / "site"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--no-build-isolation",
            "--no-index",
            "--target",
            str(site),
            str(root / "src"),
        ],
        check=True,
        capture_output=True,
    )
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(site), env.get("PYTHONPATH", "")) if p)
    return env


def ego(env, *args):
    proc = subprocess.Popen(
        [sys.executable, "-m", "ego", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env=env,
    )
    out, err = proc.communicate(timeout=600)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), survivors(proc.pid)


def test_ego_list_and_run_find_the_plugins(plugin_env):
    listed, _ = ego(plugin_env, "list")
    assert "demo-pid: the demo plugin's pid" in listed.stdout and "demo-brake" in listed.stdout
    # the plugin's metric among every scenario's metrics, its backends with their capabilities
    assert "demo_rows" in listed.stdout
    assert "  demo-road: scripted_actors, any_network\n" in listed.stdout
    assert "  demo-bare: any_network\n" in listed.stdout
    runs = {}
    for scenario, controller in (("emergency-brake", "pid"), ("demo-brake", "demo-pid")):
        proc, left = ego(plugin_env, "run", scenario, "-c", controller, "--set", "duration=4", "--json")
        assert proc.returncode == 1, proc.stderr  # timeout: 4 s is too short for the lane change
        assert not left
        runs[controller] = json.loads(proc.stdout)
    for key in ("status", "min_gap_front", "max_abs_lateral_accel", "steps"):
        assert runs["pid"][key] == runs["demo-pid"][key]
    assert runs["demo-pid"]["scenario"] == "demo-brake"
    # the plugin's metric: one trace row per control step, 4 s / 0.01 s
    assert runs["demo-pid"]["demo_rows"] == runs["demo-pid"]["steps"] == 400
    # the plugin's backend is a --backend choice (the parser reads the registry when it is
    # built), and a built-in scenario whose needs it covers runs on it as on SUMO (the backend
    # is SUMO under another name); one whose needs it lacks is refused naming the need
    proc, _ = ego(
        plugin_env, "run", "emergency-brake", "-c", "pid", "--set", "duration=4", "--json", "--backend", "demo-road"
    )
    assert proc.returncode == 1, proc.stderr
    on_road = json.loads(proc.stdout)
    assert on_road["backend"] == "demo-road" and runs["pid"]["backend"] == "sumo"
    for key in ("status", "min_gap_front", "max_abs_lateral_accel", "steps"):
        assert on_road[key] == runs["pid"][key], key
    proc, _ = ego(plugin_env, "run", "platoon", "-c", "pid", "--backend", "demo-road")
    assert proc.returncode == 2
    assert proc.stderr.strip().endswith("(scenario platoon needs several_egos; backend demo-road lacks it)"), (
        proc.stderr
    )
    # without the plugin, the names are unknown
    plain, _ = ego(dict(os.environ), "run", "emergency-brake", "-c", "demo-pid")
    assert plain.returncode == 2 and "unknown controller 'demo-pid'" in plain.stderr
    plain, _ = ego(dict(os.environ), "run", "emergency-brake", "-c", "pid", "--backend", "demo-road")
    assert plain.returncode == 2 and "invalid choice: 'demo-road'" in plain.stderr


def test_a_plugin_backend_runs_the_scenarios_whose_needs_it_has(plugin_env):
    """demo-brake runs on every backend with the capabilities it needs: demo-road (scripted
    actors) runs it as SUMO does; demo-bare lacks the scripted actors emergency-brake's lead needs, and the registry
    refuses it when the run is resolved, in one line naming both."""
    runs = {}
    for backend in ("sumo", "demo-road"):
        args = ("run", "demo-brake", "-c", "demo-pid", "--set", "duration=4", "--json", "--backend", backend)
        proc, left = ego(plugin_env, *args)
        assert proc.returncode == 1 and not left, proc.stderr
        runs[backend] = json.loads(proc.stdout)
    assert runs["demo-road"]["backend"] == "demo-road"
    for key in ("status", "min_gap_front", "max_abs_lateral_accel", "demo_rows"):
        assert runs["demo-road"][key] == runs["sumo"][key], key
    proc, _ = ego(plugin_env, "run", "demo-brake", "-c", "pid", "--backend", "demo-bare")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.strip() == (
        "ego: error: bad value for --backend: 'demo-bare' (scenario demo-brake needs scripted_actors; "
        "backend demo-bare lacks it)"
    )


def test_sweep_on_a_process_pool_has_the_plugin_metric_in_its_results(plugin_env, tmp_path):
    """The plugin's metric, computed in the sweep's worker processes (each loads the
    entry points itself), is a column of results.parquet."""
    spec = tmp_path / "sweep.toml"
    spec.write_text('scenario = "demo-brake"\ncontrollers = ["demo-pid", "pid"]\nseeds = 1\n[set]\nduration = 3\n')
    args = ("sweep", str(spec), "--jobs", "2", "--record", "none", "--out", str(tmp_path / "sw"))
    proc, left = ego(plugin_env, *args)
    assert proc.returncode == 0 and not left, proc.stderr
    rows = pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist()
    assert sorted(r["controller"] for r in rows) == ["demo-pid", "pid"]
    assert [r["demo_rows"] for r in rows] == [r["steps"] for r in rows] == [300, 300]


def test_compare_jobs_2_runs_the_plugin_in_its_workers(plugin_env, tmp_path):
    proc, left = ego(
        plugin_env,
        "compare",
        "demo-brake",
        "--controllers",
        "pid,demo-pid",
        "--jobs",
        "2",
        "--set",
        "duration=4",
        "--out",
        str(tmp_path / "cmp"),
    )
    assert proc.returncode == 0, proc.stderr  # every run gave a result
    assert not left
    rows = {r["controller"]: r for r in csv.DictReader(open(tmp_path / "cmp" / "metrics.csv"))}
    assert rows["demo-pid"]["min_gap_front"] == rows["pid"]["min_gap_front"]
    assert rows["demo-pid"]["status"] == rows["pid"]["status"] == "timeout"
    assert rows["demo-pid"]["demo_rows"] == rows["pid"]["demo_rows"] == "400"  # the workers' plugin metric


@pytest.mark.long  # Ray start-up; test_compare_jobs_2_runs_the_plugin_in_its_workers runs by default
def test_sweep_on_ray_runs_the_plugin_in_its_workers(plugin_env, tmp_path):
    spec = tmp_path / "sweep.toml"
    spec.write_text('scenario = "demo-brake"\ncontrollers = ["demo-pid", "pid"]\nseeds = 2\n[set]\nduration = 3\n')
    proc, left = ego(
        plugin_env,
        "sweep",
        str(spec),
        "--engine",
        "ray",
        "--jobs",
        "2",
        "--record",
        "none",
        "--out",
        str(tmp_path / "sw"),
    )
    assert proc.returncode == 0, proc.stderr
    assert not left
    rows = pq.read_table(tmp_path / "sw" / "results.parquet").to_pylist()
    assert sorted((r["controller"], r["seed"]) for r in rows if r["status"] != "error") == [
        ("demo-pid", 0),
        ("demo-pid", 1),
        ("pid", 0),
        ("pid", 1),
    ]
    by = {(r["controller"], r["seed"]): (r["status"], r["min_gap_front"]) for r in rows}
    assert by[("demo-pid", 0)] == by[("pid", 0)] and by[("demo-pid", 1)] == by[("pid", 1)]
    # the plugin's metric, computed in the Ray workers: one trace row per control step
    assert [r["demo_rows"] for r in rows] == [r["steps"] for r in rows] == [300] * 4


def test_a_scenario_named_by_file_reference(tmp_path):
    path = tmp_path / "my_scenarios.py"
    path.write_text(MODULE)
    from ego.runner import RunSpec, run

    mine = run(RunSpec(f"{path}:DemoBrake", "pid", overrides={"duration": 3.0})).metrics
    builtin = run(RunSpec("emergency-brake", "pid", overrides={"duration": 3.0})).metrics
    assert mine["min_gap_front"] == builtin["min_gap_front"] and mine["scenario"] == "demo-brake"
