"""What a sweep spec and a falsification spec share (:mod:`ego.sweep.spec`,
:mod:`ego.falsify.spec`): reading the TOML file, the header (known keys, the scenario, the
controllers), the values checked as ``--set`` checks them, the parameter types and a run's
stable id. Every check raises a one-line ConfigError through the spec's ``bad`` (which
prefixes the spec's name).
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
