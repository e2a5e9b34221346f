"""Scenarios: the registry of names the CLI accepts."""

from __future__ import annotations

from ego.params import ConfigError
from ego.scenarios.base import CommonConfig, Event, RunResult, SumoScenario
from ego.scenarios.emergency_brake import EmergencyBrake, EmergencyBrakeConfig

SCENARIOS: dict[str, type[SumoScenario]] = {cls.name: cls for cls in (EmergencyBrake,)}


def scenario_class(name: str) -> type[SumoScenario]:
    """The registered scenario ``name``, or a ConfigError naming the known ones."""
    try:
        return SCENARIOS[name]
    except KeyError:
        raise ConfigError(f"unknown scenario {name!r} (known: {', '.join(SCENARIOS)})") from None


__all__ = [
    "SCENARIOS",
    "CommonConfig",
    "EmergencyBrake",
    "EmergencyBrakeConfig",
    "Event",
    "RunResult",
    "SumoScenario",
    "scenario_class",
]
