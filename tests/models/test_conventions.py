"""One parameter convention for the bicycle family: the converters are exact and keep the
car's steady-state handling."""

import pytest

from ego.models import (
    DynamicBicycle,
    DynamicBicycleParams,
    LateralError,
    LateralErrorParams,
    dynamic_params_from_lateral,
    lateral_params_from_dynamic,
)

CARS = {
    "report-003": LateralErrorParams(),
    "report-002-converted": lateral_params_from_dynamic(DynamicBicycleParams()),
    "oversteer": LateralErrorParams(Cf=80000.0, Cr=50000.0),
}


def test_the_stiffness_changes_sign_and_nothing_else():
    lat = LateralErrorParams()
    dyn = dynamic_params_from_lateral(lat, slip_speed_floor=1.0)
    assert (dyn.m, dyn.Iz, dyn.lf, dyn.lr) == (lat.m, lat.Iz, lat.lf, lat.lr)
    assert (dyn.Cf, dyn.Cr) == (-65000.0, -65000.0)
    assert dyn.slip_speed_floor == 1.0


@pytest.mark.parametrize("name", CARS)
def test_a_round_trip_is_exact(name):
    lat = CARS[name]
    assert lateral_params_from_dynamic(dynamic_params_from_lateral(lat)) == lat
    dyn = DynamicBicycleParams()
    assert dynamic_params_from_lateral(lateral_params_from_dynamic(dyn)) == dyn


@pytest.mark.parametrize("name", CARS)
def test_both_models_have_the_same_understeer_gradient(name):
    lat = CARS[name]
    assert dynamic_params_from_lateral(lat).understeer_gradient == pytest.approx(lat.understeer_gradient, rel=1e-12)


@pytest.mark.parametrize("speed", [8.0, 25.0])
@pytest.mark.parametrize("name", CARS)
def test_both_models_have_the_same_steady_state_yaw_rate_gain(name, speed):
    lat = CARS[name]
    kappa = 1e-3
    state, delta = LateralError(lat, speed).steady_state(kappa)
    lateral_gain = state[3] / delta  # r / delta on the lane, r = v kappa
    dyn = dynamic_params_from_lateral(lat)
    assert dyn.yaw_rate_gain(speed) == pytest.approx(lateral_gain, rel=1e-9)


@pytest.mark.parametrize("speed", [8.0, 25.0])
def test_the_dynamic_model_settles_at_the_lateral_models_gain(speed):
    """Report 003's car, converted, driven by report 002's equations: r/delta settles at the
    lateral-error model's steady state (the small steer keeps cos(delta) ~ 1 and u ~ constant)."""
    lat = LateralErrorParams()
    model = DynamicBicycle(dynamic_params_from_lateral(lat))
    step = model.stepper(0.005, 1)
    delta = 1e-3
    x = (0.0, speed, 0.0, 0.0, 0.0, 0.0)
    for _ in range(2000):  # 10 s
        _, u, _, v, _, r = x
        x, _ = step(x, -r * v, delta)  # a_x cancels r v: the speed holds
    assert x[1] == pytest.approx(speed, rel=1e-7)
    kappa = 1e-3
    state, steer = LateralError(lat, speed).steady_state(kappa)
    assert x[5] / delta == pytest.approx(state[3] / steer, rel=1e-5)
