"""Every controller declares a unit for every signal it records (the recording draws one
panel per unit, so an undeclared signal would land in a unit-less panel)."""

import pytest

from ego.control import CONTROLLERS, PlatoonControl
from ego.control.base import signal_units

SPECS = [(task, spec) for task, specs in CONTROLLERS.items() for spec in specs.values()]


@pytest.mark.parametrize("task, spec", SPECS, ids=[f"{t}/{s.name}" for t, s in SPECS])
def test_every_signal_has_a_declared_unit(task, spec):
    controller = spec.build(spec.params(), 0.01)
    controller.reset(seed=0)
    units = signal_units(controller)
    assert set(units) == set(controller.signals())
    assert all(isinstance(u, str) and u for u in units.values()), units


def test_a_platoon_names_its_members_units_as_their_signals():
    spec = CONTROLLERS["car-following"]["bp-pid-acc"]
    platoon = PlatoonControl([spec.build(spec.params(), 0.01) for _ in range(2)], ("f1", "f2"))
    platoon.reset(seed=0)
    assert platoon.signal_units == {
        "kp_f1": "1/s^2",
        "ki_f1": "1/s^3",
        "kd_f1": "1/s",
        "kp_f2": "1/s^2",
        "ki_f2": "1/s^3",
        "kd_f2": "1/s",
    }
    assert set(platoon.signal_units) == set(platoon.signals())


def test_a_controller_without_the_declaration_has_no_units():
    class Bare:
        def signals(self):
            return {"x": 1.0}

    assert signal_units(Bare()) == {}
