"""``ego/Scenario-v0``: any scenario ego runs with traffic as an environment.

    env = gym.make("ego/Scenario-v0", config={"scenario": "scenarios/openscenario/ccrb.xosc",
                                              "randomize": {"EgoSpeed": [8.3, 22.2]}})

``config["scenario"]`` names a built-in scenario of ``ego list`` (its parameters in the same
dict, as for its own id), an OpenSCENARIO ``.xosc`` file (its declared parameters in the same
dict, as ``ego run FILE --set`` takes them) or a ``path/to/file.py:Class`` reference. The env
is :class:`ego.gym.EgoEnv` on that scenario: the same observation and action types, reward,
outcome flags and ``randomize`` (over a file's declared parameters, drawn from each episode's
seed). See docs/gym.md.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any, ClassVar

from ego.gym.env import ENV_KEYS, EgoEnv
from ego.params import ConfigError, did_you_mean
from ego.scenarios import SCENARIOS, Scenario, scenario_class

#: what ``config["scenario"]`` may be, for the errors
_ALLOWED = "a scenario of ego list with traffic ({names}) or an OpenSCENARIO .xosc file"


def env_scenarios() -> list[str]:
    """The built-in scenarios an env can run: every one of ``ego list`` with a traffic
    simulator (report 000's bare-model experiments have none)."""
    return [name for name, cls in SCENARIOS.items() if runs_traffic(cls)]


def runs_traffic(cls: type[Scenario]) -> bool:
    """The scenario runs a traffic simulator (a network of its own, or a file's road)."""
    return cls.network is not None or cls._make_bridge is not Scenario._make_bridge


def check_scenario(value: Any) -> str:
    """``config["scenario"]`` checked: the scenario's name or file path, or a one-line
    ConfigError naming the value and what is allowed."""
    allowed = _ALLOWED.format(names=", ".join(env_scenarios()))
    if value is None:
        raise ConfigError(f"missing config key scenario (expected {allowed})")
    if not isinstance(value, (str, os.PathLike)) or not os.fspath(value):
        raise ConfigError(f"bad value for scenario: {value!r} (expected {allowed})")
    name = os.fspath(value)
    try:
        cls = scenario_class(name)
    except ConfigError as exc:
        if name.lower().endswith(".xosc") or ":" in name:  # a file's own error names it (and its line)
            raise ConfigError(f"bad value for scenario: {exc}") from None
        raise ConfigError(
            f"bad value for scenario: {name!r} (expected {allowed}){did_you_mean(name, env_scenarios())}"
        ) from None
    if not runs_traffic(cls):
        raise ConfigError(f"bad value for scenario: {name!r} runs no traffic simulator (expected {allowed})")
    return name


class ScenarioEnv(EgoEnv):
    """``ego/Scenario-v0``: :class:`EgoEnv` on the scenario ``config["scenario"]`` names (see
    the module docstring); ``scenario`` is the same, for a caller that passes it apart. The
    scenario is fixed when the env is made: a reset that configures another is refused."""

    own_keys: ClassVar[tuple[str, ...]] = (*ENV_KEYS, "scenario")

    def __init__(
        self, scenario: str | None = None, config: Mapping[str, Any] | None = None, render_mode: str | None = None
    ) -> None:
        if config is not None and not isinstance(config, Mapping):
            raise ConfigError(f"bad value for config: {config!r} (expected a dict)")
        name = check_scenario((config or {}).get("scenario", scenario))
        super().__init__(name, {**(config or {}), "scenario": name}, render_mode)

    @classmethod
    def default_config(cls, scenario: str = "emergency-brake") -> dict:
        """Every key with its default for ``scenario``: ``scenario`` itself, then
        :meth:`EgoEnv.default_config`'s (a file's declared parameters among the scenario's;
        ``randomize`` the built-in env's distribution, ``{}`` for a file: the file as written)."""
        return {"scenario": scenario, **EgoEnv.default_config(scenario)}

    @property
    def declared_parameters(self) -> dict[str, Any]:
        """A file's declared parameters (name -> the value the file declares; ``{}`` for a
        built-in scenario): what ``randomize`` and plain keys of the config may set."""
        base = self.scenario_cls.config_cls()
        return {name: getattr(base, name) for name in getattr(self.scenario_cls, "file_params", ())}

    def _build(self) -> None:
        if self.config.get("scenario") != self.scenario_name:
            raise ConfigError(
                f"bad value for scenario: {self.config.get('scenario')!r} (the scenario is fixed when the env is "
                f"made, here {self.scenario_name!r}: make a new env for another)"
            )
        super()._build()
