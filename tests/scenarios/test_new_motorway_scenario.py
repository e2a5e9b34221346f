"""A new motorway scenario is one module composed from the parts, touching no package file;
every shipped motorway scenario is a direct subclass of Scenario, its module short."""

import importlib.util
import textwrap
from pathlib import Path

import pytest

from ego.scenarios import CutIn, EmergencyBrake, FastFollower, SineTracking
from ego.scenarios.base import Scenario

PACKAGE = Path(__file__).resolve().parents[2] / "ego" / "scenarios"

MODULE = """
from dataclasses import dataclass

from ego.params import param
from ego.results.trace import Metric
from ego.scenarios.base import Scenario
from ego.scenarios.evasive import METRICS, EvasiveConfig, compose, evasive_metrics
from ego.scenarios.motorway import COLUMNS, EDGE, ROUTE
from ego.sim import VehicleSpec, VehicleType
from ego.sim.traffic import PacedVehicle

BROKEN = VehicleType("broken", length=4.5, width=1.8, sigma=0.0, color=(255, 0, 0))


@dataclass(frozen=True)
class StoppedCarConfig(EvasiveConfig):
    distance: float = param(80.0, "m", "the stopped car's rear ahead of the ego", min=20.0, max=500.0)
    evade: bool = param(False, "-", "never change lane: brake")


class StopBehind:
    action = "brake"

    def start(self, man):
        pass

    def reference(self, man):
        return man.behind_front(man.s0 + man.config.ego_speed * man.t, man.config.ego_speed)

    def settled(self, man):
        return man.view.ds <= 0.1


class StoppedCar(Scenario):
    name, config_cls, network, edge, columns = "stopped-car", StoppedCarConfig, "highway", EDGE, COLUMNS
    metric_specs = METRICS + (Metric("stopped_at", "m", "where the ego came to rest"),)

    def compose(self):
        return compose(self, "front", StopBehind(), self.populate)

    def populate(self, world):
        c = self.config
        front = c.ego_start + c.distance + BROKEN.length
        world.vehicle(VehicleSpec("broken", "broken", ROUTE, c.ego_lane, front, 0.0), BROKEN,
                      PacedVehicle("broken", 0.0))

    def _metrics(self, trace, names):
        return {**evasive_metrics(self, trace, names), "stopped_at": round(self.view.s, 2)}
"""


def test_shipped_motorway_scenarios_are_scenario_then_concrete():
    for cls in (EmergencyBrake, FastFollower, CutIn, SineTracking):
        assert cls.__mro__[1] is Scenario, cls
    # (two of its lines are the strict typing's asserts that the view's sensor is set)
    assert len((PACKAGE / "emergency_brake.py").read_text().splitlines()) <= 252
    # (cut-in's braking criterion is a part, ego.scenarios.envelope.ReachCriterion: wiring it is 11
    # lines; two more are the strict typing's imports)
    assert len((PACKAGE / "cut_in.py").read_text().splitlines()) <= 152


@pytest.mark.sumo
def test_a_new_scenario_in_one_module_runs_with_the_kit(tmp_path, fuzzy_ready):
    path = tmp_path / "stopped_car.py"
    path.write_text(textwrap.dedent(MODULE))
    spec = importlib.util.spec_from_file_location("stopped_car", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    from ego.control import FuzzyController, FuzzyParams

    config = module.StoppedCarConfig(traffic_density=0.0)
    result = module.StoppedCar(config, FuzzyController(FuzzyParams(), config.dt), seed=0).run()
    m = result.metrics
    assert m["status"] == "completed" and not m["collision"] and m["target_side"] is None
    assert m["trigger_time"] is not None and abs(m["final_speed"]) < 0.2
    assert 0.0 < m["min_gap_front"] < 80.0
    phases = set(result.column("phase"))
    assert phases == {0.0, 2.0, 3.0}  # cruise -> in-lane manoeuvre -> done


def test_every_named_scenario_of_the_package_is_registered_by_its_module_alone():
    import importlib
    import pkgutil

    import ego.scenarios as package

    found = {}
    for info in pkgutil.iter_modules(package.__path__):
        if info.name in package._MOVED:  # old names of ego.results modules (importing them warns)
            continue
        module = importlib.import_module(f"ego.scenarios.{info.name}")
        found.update(
            {
                obj.name: obj
                for obj in vars(module).values()
                if isinstance(obj, type)
                and issubclass(obj, Scenario)
                and obj.name
                and obj.__module__ == module.__name__
            }
        )
    assert found == package.SCENARIOS
