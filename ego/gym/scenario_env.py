"""``ego/Scenario-v0``: any scenario ego runs with traffic as an environment.

    env = gym.make("ego/Scenario-v0", config={"scenario": "scenarios/openscenario/ccrb.xosc",
                                              "randomize": {"EgoSpeed": [8.3, 22.2]}})

``config["scenario"]`` names a built-in scenario of ``ego list`` (its parameters in the same
dict, as for its own id), an OpenSCENARIO ``.xosc`` file (its declared parameters in the same
dict, as ``ego run FILE --set`` takes them), an OpenSCENARIO ParameterValueDistribution file
(its scenario file, randomised over its uniform ranges) or a ``path/to/file.py:Class``
reference. The env
is :class:`ego.gym.EgoEnv` on that scenario: the same observation and action types, reward,
outcome flags and ``randomize`` (over a file's declared parameters, drawn from each episode's
seed). See docs/gym.md.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

from ego.gym.env import ENV_KEYS, EgoEnv
from ego.params import ConfigError, describe, did_you_mean
from ego.scenarios import SCENARIOS, scenario_class

#: what ``config["scenario"]`` may be, for the errors
_ALLOWED = "a scenario of ego list with traffic ({names}) or an OpenSCENARIO .xosc file"


def env_scenarios() -> list[str]:
    """The built-in scenarios an env can run: every one of ``ego list`` with a traffic
    simulator (report 000's bare-model experiments have none)."""
    return [name for name, cls in SCENARIOS.items() if cls.runs_traffic()]


def check_scenario(value: Any) -> str:
    """``config["scenario"]`` checked: the scenario's name or file path, or a one-line
    ConfigError naming the value and what is allowed."""
    allowed = _ALLOWED.format(names=", ".join(env_scenarios()))
    if value is None:
        raise ConfigError(f"missing config key scenario (expected {allowed})")
    if not isinstance(value, (str, os.PathLike)) or not os.fspath(value):
        raise ConfigError(f"bad value for scenario: {value!r} (expected {allowed})")
    name = os.fspath(value)
    if name.lower().endswith(".xosc") and not Path(name).is_file():
        raise ConfigError(f"bad value for scenario: {name!r} is not a file (expected {allowed})")
    if _distribution_root(name) is not None:
        return name
    try:
        cls = scenario_class(name)
    except ConfigError as exc:
        if name.lower().endswith(".xosc") or ":" in name:  # a file's own error names it (and its line)
            raise ConfigError(f"bad value for scenario: {exc}") from None
        raise ConfigError(
            f"bad value for scenario: {name!r} (expected {allowed}){did_you_mean(name, env_scenarios())}"
        ) from None
    if not cls.runs_traffic():
        raise ConfigError(f"bad value for scenario: {name!r} runs no traffic simulator (expected {allowed})")
    return name


def _distribution_root(name: str):
    """The ``<ParameterValueDistribution>`` element of the .xosc file ``name``, or None (not
    such a file, or no file at all)."""
    from ego.openscenario.distribution import root_of

    try:
        return root_of(name)
    except ConfigError:
        return None  # malformed: the scenario loader names the line


def resolve_scenario(value: Any) -> tuple[str, dict[str, list[float]] | None]:
    """``config["scenario"]`` as (the scenario to run, a distribution's ranges or None): a
    ParameterValueDistribution file gives the scenario file it names and, per parameter of
    its ``<Stochastic>`` ``<UniformDistribution>``s, ``[lowerLimit, upperLimit]``; anything
    else is itself (:func:`check_scenario`). A distribution ego cannot draw is one line with
    the file and line."""
    name = check_scenario(value)
    root = _distribution_root(name)
    if root is None:
        return name, None
    from ego.openscenario.distribution import scenario_file, uniform_ranges

    target = scenario_file(name, root)
    check_scenario(target)
    params = {i.name for i in describe(scenario_class(target).config_cls)}
    return target, uniform_ranges(name, root, target, params)


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
        source = (config or {}).get("scenario", scenario)
        name, ranges = resolve_scenario(source)
        #: what ``config["scenario"]`` names (a distribution file: the scenario it draws is ``scenario_name``)
        self.source = os.fspath(source)
        given = {**(config or {}), "scenario": self.source}
        if ranges is not None:
            given = {"randomize": ranges, **given}
        super().__init__(name, given, render_mode)
        self.default_config = functools.partial(type(self).default_config, self.source)

    @classmethod
    def default_config(cls, scenario: str = "emergency-brake") -> dict:
        """Every key with its default for ``scenario``: ``scenario`` itself, then
        :meth:`EgoEnv.default_config`'s (a file's declared parameters among the scenario's;
        ``randomize`` the built-in env's distribution, ``{}`` for a file: the file as written,
        a distribution file's ranges)."""
        name, ranges = resolve_scenario(scenario)
        config = {"scenario": scenario, **EgoEnv.default_config(name)}
        if ranges is not None:
            config["randomize"] = ranges
        return config

    @property
    def declared_parameters(self) -> dict[str, Any]:
        """A file's declared parameters (name -> the value the file declares; ``{}`` for a
        built-in scenario): what ``randomize`` and plain keys of the config may set."""
        base = self.scenario_cls.config_cls()
        return {name: getattr(base, name) for name in getattr(self.scenario_cls, "file_params", ())}

    def _build(self) -> None:
        if self.config.get("scenario") != self.source:
            raise ConfigError(
                f"bad value for scenario: {self.config.get('scenario')!r} (the scenario is fixed when the env is "
                f"made, here {self.source!r}: make a new env for another)"
            )
        super()._build()
