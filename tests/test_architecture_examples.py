"""The worked examples of docs/architecture.md run as written: a controller, a metric and a
traffic simulator added from outside the package, each checked against facts derived by hand
(the scenario example: tests/test_kit_example.py; the OpenSCENARIO action example:
tests/openscenario/test_xosc_registry.py)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

from ego.control import CONTROLLERS
from ego.models import NonlinearBicycleParams
from ego.results.metrics import TRACE_METRICS, flatten
from ego.runner import RunSpec, resolve, run

ARCHITECTURE = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"
CAR = NonlinearBicycleParams()
DECEL = CAR.f * CAR.g  # m/s^2: the rolling resistance alone slows a coasting car (f g)


def block(section: str) -> str:
    """The first Python code block of the section headed ``section``."""
    text = ARCHITECTURE.read_text()
    return text.split(f"\n## {section}\n")[1].split("\n## ")[0].split("```python\n")[1].split("```")[0]


@pytest.fixture
def coast():
    """The controller example, registered as ``coast`` for the test."""
    exec(compile(block("Adding a controller"), str(ARCHITECTURE), "exec"), {})  # noqa: S102
    yield CONTROLLERS["tracking"]["coast"]
    del CONTROLLERS["tracking"]["coast"]


@pytest.fixture
def path_length():
    exec(compile(block("Adding a metric"), str(ARCHITECTURE), "exec"), {})  # noqa: S102
    yield TRACE_METRICS["path_length"]
    del TRACE_METRICS["path_length"]


def test_the_controller_example_runs_by_name(coast, capsys):
    from ego.cli import main

    # report-000's car from 20 m/s for 30 s: it keeps its speed, or coasts at -f g with share=0
    held = run(resolve(RunSpec("report-000", "coast"))).metrics
    assert held["status"] == "completed" and held["final_speed"] == pytest.approx(20.0, abs=1e-6)
    assert held["max_abs_lateral_accel"] == pytest.approx(0.0, abs=1e-9)
    assert main(["run", "report-000", "-c", "coast", "--set", "share=0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # final_speed is the last trace row's, at t = 29.99 s
    assert out["controller"] == "coast" and out["final_speed"] == pytest.approx(20.0 - DECEL * 29.99, abs=1e-4)
    with pytest.raises(Exception, match="share"):  # checked as every parameter is
        resolve(RunSpec("report-000", "coast", 0, {"share": 5.0}))


def test_the_metric_example_is_in_a_real_runs_metrics(coast, path_length, capsys):
    from ego.cli import main

    resolved = resolve(RunSpec("report-000", "coast", 0, {"share": 0.0}))
    m = run(resolved).metrics
    # x(t) = 20 t - f g t^2 / 2 from t = 0 to the last row at t = 29.99 s (the ego drives straight)
    t = 30.0 - resolved.config.dt
    assert m["path_length"] == pytest.approx(20.0 * t - 0.5 * DECEL * t * t, abs=1e-2)
    declared = resolved.metrics_declared()
    assert [d.unit for d in declared if d.name == "path_length"] == ["m"]
    assert list(flatten(m)) == [d.name for d in declared]  # reported where it is declared
    assert main(["run", "report-000", "-c", "coast", "--set", "share=0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["units"]["path_length"] == "m" and out["path_length"] == m["path_length"]
    # a scenario whose trace lacks the columns neither declares nor reports it
    assert "path_length" not in {d.name for d in resolve(RunSpec("platoon", "pid")).metrics_declared()}


@pytest.fixture
def empty_road(tmp_path, monkeypatch):
    """The backend example saved as the module ``empty_road`` and registered."""
    from ego.sim.registry import BACKENDS

    (tmp_path / "empty_road.py").write_text(block("Adding a traffic simulator"))
    monkeypatch.syspath_prepend(str(tmp_path))
    import empty_road  # noqa: F401 - registers the backend

    yield sys.modules["empty_road"]
    BACKENDS.pop("empty-road", None)
    sys.modules.pop("empty_road", None)


@pytest.mark.sumo
def test_the_backend_example_runs_a_scenario_as_sumo_does(empty_road):
    from ego.sim import TrafficSim, make_sim
    from ego.sim.registry import backend

    members = [n for n in vars(TrafficSim) if not n.startswith("_")]
    assert [n for n in members if not hasattr(empty_road.EmptyRoad, n)] == []
    assert backend("empty-road").capabilities.sublane is False
    # the ego alone on the motorway: the simulator only hosts it, the motion is ego's model
    overrides = {"traffic_density": 0.0, "duration": 10.0}
    on = {
        b: run(resolve(RunSpec("sine-tracking", "pid", 0, overrides, backend=b))).metrics
        for b in ("sumo", "empty-road")
    }
    assert on["empty-road"]["backend"] == "empty-road" and on["empty-road"]["status"] == on["sumo"]["status"]
    for name, value in on["sumo"].items():
        if name not in ("backend", "wall_time") and isinstance(value, float):
            assert on["empty-road"][name] == pytest.approx(value, rel=1e-6, abs=1e-6), name
    assert on["sumo"]["steps"] == on["empty-road"]["steps"] == 1000
    # a car it drives, and a collision from the outlines when the ego is pushed into it
    from ego.models import VehicleGeometry
    from ego.sim import SimSetup, VehicleSpec, VehicleType
    from ego.sumo.net import net_file

    sim = make_sim("empty-road", SimSetup(net_file("highway"), 0.1, 0))
    sim.start()
    sim.add_type(VehicleType("car", length=4.0, width=2.0))
    sim.add_route("r", ["motorway"])
    sim.add_vehicles([VehicleSpec("ego", "car", "r", 1, 100.0, 10.0), VehicleSpec("lead", "car", "r", 1, 120.0, 5.0)])
    assert sim.insert(required=["ego"]) == []
    sim.control("ego", VehicleGeometry(length=4.0, width=2.0, cg_to_front=2.0))
    x, y, psi = sim.cg_pose("ego")
    assert sim.step() == [] and sim.box("lead")[0] - sim.box("ego")[0] == pytest.approx(20.5 * math.cos(psi))
    sim.push("ego", x + 17.0 * math.cos(psi), y + 17.0 * math.sin(psi), psi, 10.0)  # its front 1.5 m into the lead
    hits = sim.step()
    assert [(c.collider, c.victim) for c in hits] == [("ego", "lead")]
