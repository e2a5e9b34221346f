"""No scenario class deeper than Scenario -> concrete scenario: every registered scenario, every
scenario in the users' scripts (scenarios/*.py) and a scenario file's class subclass Scenario
directly, with no mixin; what they share are parts they compose (world, sensors, manoeuvre,
safety layer), not base classes with hooks."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

from ego.scenarios import SCENARIOS, Scenario, scenario_class

ROOT = Path(__file__).resolve().parents[2]


def between(cls: type) -> list[type]:
    """The classes of ``cls``'s MRO between it and ``object`` other than Scenario: base
    templates or mixins (none allowed)."""
    return [k for k in cls.__mro__[1:] if k not in (Scenario, object)]


def script_scenarios() -> list[type]:
    """The Scenario subclasses the scripts in scenarios/ define (only the scripts that name
    Scenario are imported)."""
    out = []
    for path in sorted((ROOT / "scenarios").glob("*.py")):
        if "Scenario" not in path.read_text():
            continue
        spec = importlib.util.spec_from_file_location(f"_script_{path.stem}", path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module  # its dataclasses look their module up
        spec.loader.exec_module(module)
        out += [
            obj
            for obj in vars(module).values()
            if isinstance(obj, type) and issubclass(obj, Scenario) and obj is not Scenario
        ]
    return out


def test_the_check_sees_a_level_in_between():
    class Template(Scenario):
        pass

    class Concrete(Template):
        pass

    class Mixin:
        pass

    class Mixed(Mixin, Scenario):
        pass

    assert between(Concrete) == [Template] and between(Mixed) == [Mixin] and between(Template) == []


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_registered_scenarios_subclass_scenario_directly(name):
    cls = SCENARIOS[name]
    assert cls.__bases__ == (Scenario,) and between(cls) == [], [k.__name__ for k in cls.__mro__]


def test_the_scripts_scenarios_subclass_scenario_directly():
    found = script_scenarios()
    assert "TruckMerge" in {cls.__name__ for cls in found}  # scenarios/slow_truck_merge.py
    for cls in found:
        assert cls.__bases__ == (Scenario,) and between(cls) == [], [k.__name__ for k in cls.__mro__]


def test_a_scenario_files_class_subclasses_scenario_directly():
    cls = scenario_class(str(ROOT / "scenarios" / "openscenario" / "ccrs.xosc"))
    assert cls.__bases__ == (Scenario,) and between(cls) == [], [k.__name__ for k in cls.__mro__]
    # emergency-brake's parts and declarations, composed, not inherited
    assert cls.metric_specs == SCENARIOS["emergency-brake"].metric_specs
    assert cls.columns == SCENARIOS["emergency-brake"].columns
