"""Scenarios: the registry of names the CLI accepts."""

from __future__ import annotations

from ego.params import ConfigError, did_you_mean
from ego.plugins import is_reference
from ego.results.run import Event, RunResult
from ego.scenarios.base import CommonConfig, Scenario
from ego.scenarios.curve import CurveConfig, CurveScenario
from ego.scenarios.cut_in import CutIn, CutInConfig
from ego.scenarios.emergency_brake import EmergencyBrake, EmergencyBrakeConfig
from ego.scenarios.fast_follower import FastFollower, FastFollowerConfig
from ego.scenarios.lane_centering import LaneCenteringConfig, LaneCenteringScenario
from ego.scenarios.platoon import PlatoonConfig, PlatoonScenario
from ego.scenarios.references import load_scenario_plugins, resolve_scenario
from ego.scenarios.tracking import Report000, Report000Config, SineTracking, SineTrackingConfig

SCENARIOS: dict[str, type[Scenario]] = {
    cls.name: cls
    for cls in (
        EmergencyBrake,
        FastFollower,
        CutIn,
        CurveScenario,
        LaneCenteringScenario,
        PlatoonScenario,
        SineTracking,
        Report000,
    )
}


#: modules moved to ego.results, kept for users' scripts (importing them warns): no scenarios
_MOVED = ("metrics", "trace", "traffic_log")


def _discover() -> None:
    """Register every named Scenario subclass defined in a module of this package (after the
    ones above, in module order): a new scenario is one module here, touching no other file."""
    import importlib
    import pkgutil

    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name in _MOVED:
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        for obj in vars(module).values():
            if isinstance(obj, type) and issubclass(obj, Scenario) and obj.name and obj.__module__ == module.__name__:
                SCENARIOS.setdefault(obj.name, obj)


_discover()


def scenario_class(name: str) -> type[Scenario]:
    """The registered scenario ``name`` (entry-point plugins included), the scenario class a
    ``package.module:Name`` or ``path/to/file.py:Name`` reference names, or a ConfigError
    naming the known ones. A name ending in ``.xosc`` is an OpenSCENARIO file
    (:mod:`ego.openscenario`)."""
    from ego.plugins import SCENARIO_FILES, file_resolver

    resolver = file_resolver(name, SCENARIO_FILES) if isinstance(name, str) else None
    if resolver is not None:  # a file (ego.openscenario), looked up by name: nothing above imported here
        cls: type[Scenario] = resolver(name)
        return cls
    load_scenario_plugins(SCENARIOS)
    try:
        return SCENARIOS[name]
    except KeyError:
        if is_reference(name):
            return resolve_scenario(name)
        raise ConfigError(
            f"unknown scenario {name!r} (known: {', '.join(SCENARIOS)}){did_you_mean(name, SCENARIOS)}"
        ) from None


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
