"""One way into the scenario loop: every registered scenario (and a scenario file) calls its
loop object, and no method is replaced on a scenario instance, before or after a reset."""

from pathlib import Path

import pytest

from ego.runner import RunSpec, build
from ego.scenarios import SCENARIOS
from ego.scenarios.base import ComposedLoop, Loop, PartsLoop

pytestmark = pytest.mark.sumo
#: a scenario file shipped with the checkout (its scenario class is made from the file)
FILE = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario" / "emergency_brake.xosc"

LOOP_CALLS = [name for name in dir(Loop) if not name.startswith("_")]


def _shadowed(sc) -> list[str]:
    """Instance attributes that shadow a method of the scenario's class."""
    return [name for name in vars(sc) if callable(getattr(type(sc), name, None))]


@pytest.mark.parametrize("name", [*sorted(SCENARIOS), str(FILE)])
def test_every_scenario_runs_on_its_loop_object_with_no_method_replaced(name):
    controller = SCENARIOS[name].reference_controller() if name in SCENARIOS else "pid"
    sc = build(RunSpec(name, controller, 0, {"duration": "2"}))
    try:
        assert isinstance(sc.loop, (ComposedLoop, PartsLoop))
        assert (sc.parts is not None) == isinstance(sc.loop, ComposedLoop)
        assert all(callable(getattr(sc.loop, call)) for call in LOOP_CALLS)
        assert _shadowed(sc) == []
        sc.reset()
        for _ in range(20):
            sc.step(sc.controller.step(sc.obs))
        assert _shadowed(sc) == [] and _shadowed(sc.loop) == []
    finally:
        sc.close()
