"""Scenario references and ``ego.scenarios`` entry points (:mod:`ego.plugins` has the forms
a reference takes)."""

from __future__ import annotations

import inspect
import sys
from typing import TYPE_CHECKING, Any

from ego.params import ConfigError
from ego.plugins import SCENARIO_GROUP, entry_points, load_object

if TYPE_CHECKING:
    from ego.scenarios.base import Scenario


def resolve_scenario(ref: str) -> type[Scenario]:
    """The scenario class a ``module:Name`` or ``file.py:Name`` reference names."""
    from ego.scenarios.base import Scenario

    obj = load_object(ref, "scenario")
    if not (inspect.isclass(obj) and issubclass(obj, Scenario)):
        raise ConfigError(f"bad scenario reference {ref!r}: not an ego Scenario subclass")
    return obj


def load_scenario_plugins(registry: dict[str, Any]) -> None:
    """Register the ``ego.scenarios`` entry points into ``registry`` (name -> class), once."""
    from ego.scenarios.base import Scenario

    for ep in entry_points(SCENARIO_GROUP):
        try:
            obj = ep.load()
            if not (inspect.isclass(obj) and issubclass(obj, Scenario)):
                raise TypeError("not an ego Scenario subclass")
            registry.setdefault(ep.name, obj)
        except Exception as exc:  # noqa: BLE001
            print(
                f"ego: warning: scenario plugin {ep.name!r} ({ep.value}) not loaded: {type(exc).__name__}: {exc}",
                file=sys.stderr,
            )
