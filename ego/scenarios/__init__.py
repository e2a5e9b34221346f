"""Scenarios: the registry of names the CLI accepts."""

from __future__ import annotations

from ego.params import ConfigError, did_you_mean
from ego.scenarios.base import CommonConfig, Event, RunResult, Scenario
from ego.scenarios.curve import CurveConfig, CurveScenario
from ego.scenarios.cut_in import CutIn, CutInConfig
from ego.scenarios.lane_centering import LaneCenteringConfig, LaneCenteringScenario
from ego.scenarios.platoon import PlatoonConfig, PlatoonScenario
from ego.scenarios.evasive import EmergencyBrake, EmergencyBrakeConfig, FastFollower, FastFollowerConfig
from ego.scenarios.tracking import Report000, Report000Config, SineTracking, SineTrackingConfig

SCENARIOS: dict[str, type[Scenario]] = {
    cls.name: cls for cls in (EmergencyBrake, FastFollower, CutIn, CurveScenario, LaneCenteringScenario, PlatoonScenario,
                               SineTracking, Report000)
}


def scenario_class(name: str) -> type[Scenario]:
    """The registered scenario ``name``, or a ConfigError naming the known ones. A name
    ending in ``.xosc`` is an OpenSCENARIO file (:mod:`ego.openscenario`)."""
    from ego.openscenario import is_scenario_file

    if is_scenario_file(name):
        from ego.openscenario.scenario import file_scenario_class

        return file_scenario_class(name)
    try:
        return SCENARIOS[name]
    except KeyError:
        raise ConfigError(f"unknown scenario {name!r} (known: {', '.join(SCENARIOS)})"
                          f"{did_you_mean(name, SCENARIOS)}") from None


__all__ = [
    "SCENARIOS",
    "CommonConfig",
    "CurveConfig",
    "CurveScenario",
    "CutIn",
    "CutInConfig",
    "EmergencyBrake",
    "EmergencyBrakeConfig",
    "FastFollower",
    "FastFollowerConfig",
    "LaneCenteringConfig",
    "LaneCenteringScenario",
    "PlatoonConfig",
    "PlatoonScenario",
    "Report000",
    "Report000Config",
    "SineTracking",
    "SineTrackingConfig",
    "Event",
    "RunResult",
    "Scenario",
    "scenario_class",
]
