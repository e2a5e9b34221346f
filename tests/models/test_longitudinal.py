"""Report 004's longitudinal follower against kinematics, its transfer function and the lag."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ego.models import Longitudinal, LongitudinalParams, SpacingPolicy


def _fit_sine(t, y, omega):
    """Least-squares y ~ A sin(wt) + B cos(wt) + c0 + c1 t: returns A + jB (the complex
    gain for an input sin(wt)); the drift terms absorb a start that is not periodic."""
    basis = np.column_stack([np.sin(omega * t), np.cos(omega * t), np.ones_like(t), t])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return complex(coef[0], coef[1])


def _measured_response(model: Longitudinal, policy: SpacingPolicy, omega: float) -> complex:
    """Drive the model's ODE from rest with u = sin(wt) (scipy, tight tolerances) and measure
    the gain from u to -delta_d = s + lambda v + const (the predecessor held still)."""
    periods = 6
    t_settle = 12.0 * model.params.lag  # the lag's transient is gone after 12 tau
    t_end = t_settle + periods * 2 * math.pi / omega
    sol = solve_ivp(
        lambda t, x: model.derivatives(x, math.sin(omega * t)),
        (0.0, t_end),
        [0.0, 0.0, 0.0],
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    )
    t = np.linspace(t_settle, t_end, 4000)
    s, v, _ = sol.sol(t)
    return _fit_sine(t, s + policy.headway * v, omega)


@pytest.mark.parametrize("omega", [0.05, 0.3, 1.0, 3.0, 10.0])
def test_command_to_spacing_is_report_004s_transfer_function(omega):
    """G(s) = (0.2 s + 1)/s^2 from the command to -delta_d with no lag (report 004)."""
    model, policy = Longitudinal(), SpacingPolicy()
    assert policy.headway == 0.2 and policy.standstill_gap == 3.0  # the report's defaults
    s = 1j * omega
    expected = (0.2 * s + 1) / s**2
    measured = _measured_response(model, policy, omega)
    assert abs(measured - expected) <= 1e-6 * abs(expected)
    num, den = model.transfer_function(policy)
    assert np.polyval(num, s) / np.polyval(den, s) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("omega", [0.2, 1.0, 5.0])
def test_the_actuator_lag_adds_a_first_order_pole(omega):
    model, policy = Longitudinal(LongitudinalParams(lag=0.3)), SpacingPolicy(headway=0.5)
    s = 1j * omega
    expected = (0.5 * s + 1) / (s**2 * (0.3 * s + 1))
    measured = _measured_response(model, policy, omega)
    assert abs(measured - expected) <= 1e-6 * abs(expected)
    num, den = model.transfer_function(policy)
    assert np.polyval(num, s) / np.polyval(den, s) == pytest.approx(expected, rel=1e-12)


def test_exact_step_equals_the_integrated_ode():
    model = Longitudinal(LongitudinalParams(lag=0.25, max_accel=3.0, max_decel=6.0))
    dt = 0.1
    step = model.stepper(dt)
    rng = np.random.default_rng(4)
    x = (0.0, 15.0, 0.0)
    for u in rng.uniform(-5.0, 2.5, 40):  # within the limits: the ODE then needs no clipping
        sol = solve_ivp(
            lambda t, y, u=u: model.derivatives(y, u), (0.0, dt), x, method="DOP853", rtol=1e-12, atol=1e-12
        )
        x_ode = sol.y[:, -1]
        x = step(*x, u)
        assert x == pytest.approx(tuple(x_ode), abs=1e-9)
        x = tuple(x_ode)
    assert x[1] > 0  # never reached standstill


def test_constant_acceleration_kinematics_without_lag():
    step = Longitudinal().stepper(0.01)
    x = (10.0, 20.0, 0.0)
    for _ in range(300):
        x = step(*x, -1.5)
    t = 3.0
    assert x[0] == pytest.approx(10.0 + 20.0 * t - 0.75 * t * t, rel=1e-12)
    assert x[1] == pytest.approx(20.0 - 1.5 * t, rel=1e-12)
    assert x[2] == -1.5


def test_first_order_lag_step_and_ramp_delay():
    tau, u = 0.4, 2.0
    step = Longitudinal(LongitudinalParams(lag=tau)).stepper(0.001)
    x = (0.0, 0.0, 0.0)
    for _ in range(400):  # t = tau
        x = step(*x, u)
    assert x[2] == pytest.approx(u * (1 - math.exp(-1)), rel=1e-9)  # 63.2 % at one time constant
    for _ in range(7600):  # t = 8 s >> tau: the speed ramp is u (t - tau)
        x = step(*x, u)
    assert x[1] == pytest.approx(u * (8.0 - tau), rel=1e-3)


def test_energy_balance_under_random_commands():
    """sum of a v dt equals the change of v^2/2 (the work per unit mass is the kinetic energy)."""
    dt = 1e-3
    step = Longitudinal(LongitudinalParams(lag=0.2)).stepper(dt)
    rng = np.random.default_rng(1)
    x = (0.0, 12.0, 0.0)
    work = 0.0
    for u in np.repeat(rng.uniform(-3.0, 3.0, 50), 100):
        x1 = step(*x, u)
        work += 0.5 * (x[2] * x[1] + x1[2] * x1[1]) * dt  # trapezoid of a v
        x = x1
    assert work == pytest.approx(0.5 * (x[1] ** 2 - 12.0**2), abs=1e-4)


def test_braking_stops_the_car_at_the_stopping_distance_and_holds_it():
    step = Longitudinal(LongitudinalParams(max_decel=8.0)).stepper(0.01)
    x = (0.0, 20.0, 0.0)
    for _ in range(1000):  # 10 s of full braking, asking for more than the limit
        x = step(*x, -20.0)
    assert x == pytest.approx((20.0**2 / (2 * 8.0), 0.0, 0.0), abs=1e-9)  # v^2/(2b), no reversing


def test_braking_with_a_lag_stops_later_by_tau():
    tau, b, v0 = 0.3, 6.0, 15.0
    step = Longitudinal(LongitudinalParams(lag=tau)).stepper(1e-3)
    x = (0.0, v0, 0.0)
    stopped_at = None
    for k in range(6000):
        x = step(*x, -b)
        if stopped_at is None and x[1] == 0.0:
            stopped_at = (k + 1) * 1e-3
    # a deceleration ramp delayed by tau: stops tau later, v0 tau - b tau^2/2 farther
    assert stopped_at == pytest.approx(v0 / b + tau, abs=2e-3)
    assert x[0] == pytest.approx(v0**2 / (2 * b) + v0 * tau - b * tau**2 / 2, rel=1e-4)
    assert x[1] == 0.0 and x[2] == 0.0


def test_commands_beyond_the_limits_are_saturated():
    model = Longitudinal(LongitudinalParams(max_accel=2.0, max_decel=7.0))
    assert model.saturate(5.0) == 2.0 and model.saturate(-9.0) == -7.0 and model.saturate(1.0) == 1.0
    step = model.stepper(0.1)
    assert step(0.0, 10.0, 0.0, 50.0)[2] == 2.0


def test_spacing_policy_error_and_its_rate():
    policy = SpacingPolicy(standstill_gap=3.0, headway=0.2)
    assert policy.desired_gap(10.0) == pytest.approx(5.0)
    assert policy.error(8.0, 10.0) == pytest.approx(3.0)  # 3 m too far back
    # the rate is the derivative along a motion: lead at 12 m/s, follower 10 m/s accelerating at 1
    gap = lambda t: 8.0 + 12.0 * t - (10.0 * t + 0.5 * t * t)  # noqa: E731
    v = lambda t: 10.0 + t  # noqa: E731
    h = 1e-6
    numeric = (policy.error(gap(h), v(h)) - policy.error(gap(-h), v(-h))) / (2 * h)
    assert policy.error_rate(12.0, 10.0, 1.0) == pytest.approx(numeric, rel=1e-6)
