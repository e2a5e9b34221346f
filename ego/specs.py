"""What a sweep spec and a falsification spec share (:mod:`ego.sweep.spec`,
:mod:`ego.falsify.spec`): reading the TOML file, the header (known keys, the scenario, the
controllers), the values checked as ``--set`` checks them, the parameter types and a run's
stable id. Every check raises a one-line ConfigError through the spec's ``bad`` (which
prefixes the spec's name).

:class:`SpecReader` is the one reader both specs are parsed with: the header, the ``[set]``
table, a parameter's ``[low, high]`` range, whole numbers, the requirement period and the
requirements against the first run, each said the same way in both kinds of spec; what a
spec adds of its own (a sweep's grid and sample, a search's dimensions and seeds) is the
spec module's.
"""

from __future__ import annotations

import hashlib
import json
import os
import tomllib
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

from ego.control import controller_spec
from ego.params import ConfigError, apply_overrides, describe, did_you_mean

#: SUMO takes seeds 0..2^31-1
MAX_SEED = 2**31 - 1
#: a spec larger than this is not a spec (``ego sweep /dev/zero``)
MAX_SPEC_BYTES = 1 << 20

Bad = Callable[[str], ConfigError]


def run_id(scenario: str, controller: str, seed: int, overrides: dict) -> str:
    """A stable id: the first 16 hex digits of SHA-256 over the canonical JSON of the run."""
    canon = json.dumps(
        {
            "scenario": scenario,
            "controller": controller,
            "seed": int(seed),
            "overrides": {k: overrides[k] for k in sorted(overrides)},
        },
        sort_keys=True,
        separators=(",", ":"),
        default=str,
    )
    return hashlib.sha256(canon.encode()).hexdigest()[:16]


def param_types(scenario: str, controllers: Iterable[str]) -> dict:
    """Parameter name -> its description, for the scenario and every controller."""
    from ego.runner import parameter_namespace

    return parameter_namespace(scenario, controllers)


def read_spec(path: Path, what: str) -> dict:
    """:func:`read_toml`, with a ``scenario`` that is an OpenSCENARIO file named relative to
    the spec's folder (sweep and falsification specs alike)."""
    data = read_toml(path, what)
    scenario = data.get("scenario")
    if isinstance(scenario, str) and scenario.lower().endswith(".xosc") and not Path(scenario).is_absolute():
        data["scenario"] = os.path.normpath(path.parent / scenario)
    return data


def read_toml(path: Path, what: str) -> dict:
    """The TOML table in ``path`` (a ``what``: "sweep spec"), at most :data:`MAX_SPEC_BYTES`
    read; ConfigError (one line, naming the file) if it is a folder, larger, not text or not
    TOML."""
    from ego.checks import read_limited

    raw = read_limited(path, what, MAX_SPEC_BYTES)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"cannot read the {what} {str(path)!r}: not a text file (expected TOML)") from None
    except OSError as exc:
        raise ConfigError(f"cannot read the {what} {str(path)!r}: {exc.strerror or exc}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError(f"{path}: nested too deeply to be a {what}") from None


def check_keys(data: dict, allowed: Sequence[str], bad: Bad) -> None:
    """Every top-level key of the spec is one of ``allowed``."""
    unknown = [k for k in data if k not in allowed]
    if unknown:
        raise bad(f"unknown key {unknown[0]!r} (allowed: {', '.join(allowed)}){did_you_mean(unknown[0], allowed)}")


def scenario_of(data: dict, bad: Bad) -> tuple[str, Any]:
    """The spec's ``scenario`` and its class (a scenario file's road checked too)."""
    from ego.scenarios import scenario_class

    scenario = data.get("scenario")
    if not isinstance(scenario, str):
        raise bad('scenario must be a scenario name, e.g. scenario = "emergency-brake"')
    try:
        cls = scenario_class(scenario)
        cls.default_config({})  # a scenario file whose road is missing: said of the file, not of a key
    except ConfigError as exc:
        raise bad(str(exc)) from None
    return scenario, cls


def check_controllers(controllers: Iterable[str], cls: Any, bad: Bad) -> None:
    """Every controller drives the scenario's task."""
    for name in controllers:
        try:
            controller_spec(name, cls.task)
        except ConfigError as exc:
            raise bad(str(exc)) from None


def check_values(scenario: str, controllers: Iterable[str], overrides: dict, where: str, bad: Bad) -> None:
    """The values against the scenario's and every controller's parameters, as --set does."""
    from ego.scenarios import scenario_class

    cls = scenario_class(scenario)
    try:
        config, rest = apply_overrides(cls.default_config(overrides), overrides, strict=False)
        cls.check_config(config)
        for name in controllers:
            params = controller_spec(name, cls.task).params
            mine = {k: v for k, v in rest.items() if k in {i.name for i in describe(params)}}
            apply_overrides(params(), mine)
    except ConfigError as exc:
        raise bad(f"{where}: {exc}") from None
    except (TypeError, ValueError) as exc:
        raise bad(f"{where}: {exc}") from None


class SpecReader:
    """One spec's contents being read: ``data`` (the TOML table), ``source`` (its name, the
    prefix of every error) and the top-level keys it may have. Reading the header checks
    the keys and the scenario; :meth:`read_controllers` the controllers, after which the
    parameters are known (:attr:`infos`)."""

    def __init__(self, data: Any, source: str, top: Sequence[str]) -> None:
        self.source = source
        if not isinstance(data, dict):
            raise self.bad(f"expected a table of scenario, controllers, ... (got {type(data).__name__})")
        check_keys(data, top, self.bad)
        self.data = data
        self.scenario, self.cls = scenario_of(data, self.bad)
        self.controllers: list[str] = []
        self.infos: dict = {}

    def bad(self, msg: str) -> ConfigError:
        return ConfigError(f"{self.source}: {msg}")

    def read_controllers(self, value: Any) -> list[str]:
        """``controllers``: a non-empty list of distinct names, each driving the scenario's task."""
        if not isinstance(value, list) or not value or not all(isinstance(c, str) for c in value):
            raise self.bad('controllers must be a non-empty list of names, e.g. controllers = ["pid"]')
        if len(set(value)) != len(value):
            dup = next(c for c in value if value.count(c) > 1)
            raise self.bad(f"controller {dup!r} is listed twice")
        check_controllers(value, self.cls, self.bad)
        self.controllers = value
        self.infos = param_types(self.scenario, value)
        return value

    def table(self, section: str) -> dict:
        """``[section]``: a table of parameter = value (empty when the spec has none)."""
        value = self.data.get(section, {})
        if not isinstance(value, dict):
            raise self.bad(f"[{section}] must be a table of parameter = value")
        return value

    def known(self, name: str, section: str) -> Any:
        """The declaration of parameter ``name`` (of ``[section]``); one line naming the
        scenario and controllers when no parameter has that name."""
        info = self.infos.get(name)
        if info is None:
            raise self.bad(
                f"[{section}] unknown parameter {name!r} for {self.scenario} with "
                f"{', '.join(self.controllers)} (see ego list){did_you_mean(name, self.infos)}"
            )
        return info

    def check(self, overrides: dict, where: str) -> None:
        """The values ``overrides`` against the scenario's and the controllers' parameters."""
        check_values(self.scenario, self.controllers, overrides, where, self.bad)

    def fixed(self, section: str = "set") -> dict:
        """``[set]``: the values every run gets, each known and checked."""
        fixed = self.table(section)
        for name, value in fixed.items():
            self.known(name, section)
            self.check({name: value}, f"[{section}] {name}")
        return fixed

    def number_range(self, section: str, name: str, info: Any, rng: Any, instead: str) -> tuple[float, float]:
        """``name = [low, high]`` of ``[section]`` (a sample's or a search's range): a numeric
        parameter (else "not a number to ..., ``instead``") and two numbers low < high."""
        if info.type not in (int, float) or info.choices is not None:
            raise self.bad(f"[{section}] {name} is not a number to {section} ({instead})")
        if (
            not isinstance(rng, list)
            or len(rng) != 2
            or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in rng)
            or not rng[0] < rng[1]
        ):
            raise self.bad(f"[{section}] {name} must be a range [low, high] with low < high, got {rng!r}")
        return float(rng[0]), float(rng[1])

    def period(self) -> float:
        """``requirement_period`` (s; default 0: every sample of the trace)."""
        from ego.requirements import RequirementError, check_period

        try:
            return check_period(self.data.get("requirement_period", 0.0), "requirement_period")
        except RequirementError as exc:
            raise self.bad(str(exc).removeprefix("bad ")) from None

    def requirements(self) -> dict | None:
        """``[requirements]`` (name -> formula), None when the spec has none."""
        from ego.requirements import from_table

        return from_table(self.data["requirements"], self.source) if "requirements" in self.data else None


def is_whole(value: Any, lo: float, hi: float) -> bool:
    """``value`` is a whole number (not true/false) within ``lo..hi``."""
    return isinstance(value, int) and not isinstance(value, bool) and lo <= value <= hi


def check_requirements(
    scenario: str, controller: str, seed: int, overrides: dict, requirements: dict, bad: Bad
) -> None:
    """Every formula against the signals of one run of the spec (its first): one line on a
    problem."""
    from ego.runner import RunSpec, requirements_of, resolve

    spec = RunSpec(scenario, controller, seed, overrides, requirements=requirements)
    try:
        requirements_of(resolve(spec))
    except ConfigError as exc:
        raise bad(str(exc)) from None


def changed(stored: dict, now: dict) -> str | None:
    """The first entry of a spec's resume key (``name -> JSON-able value``) that differs
    between the stored results and this spec, said in a few words ("ranges changed from
    {...} to {...}"); None when they agree. Entries the stored key lacks are not compared."""
    for name, value in now.items():
        if name not in stored:
            continue
        old = stored[name]
        if json.dumps(old, sort_keys=True, default=str) != json.dumps(value, sort_keys=True, default=str):
            return f"{name} changed from {_short(old)} to {_short(value)}"
    return None


def _short(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, default=str)
    return text if len(text) <= 200 else text[:197] + "..."
