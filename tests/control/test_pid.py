"""PID behaviour from first principles."""

import math

import pytest

from ego.control import PID, Observation, PIDController, PIDParams


def test_proportional_only_is_a_gain():
    pid = PID(2.0, 0.0, 0.0, 0.01, -100, 100)
    assert pid.step(1.5, 0.0) == pytest.approx(3.0)


def test_integral_accumulates_error_times_time():
    pid = PID(0.0, 1.0, 0.0, 0.01, -100, 100)
    for _ in range(100):
        out = pid.step(2.0, 0.0)
    # integral after 100 steps of 0.01 s at e = 2: 2.0 (output uses the integral before update)
    assert pid.integral == pytest.approx(2.0)
    assert out == pytest.approx(1.98)


def test_derivative_filter_is_first_order_lag():
    tau, dt = 0.1, 0.001
    pid = PID(0.0, 0.0, 1.0, dt, -100, 100, tau_d=tau)
    t = 0.0
    for _ in range(100):  # 0.1 s = one time constant
        out = pid.step(0.0, 1.0)
        t += dt
    assert out == pytest.approx(1 - math.exp(-t / tau), abs=5e-3)


def test_anti_windup_limits_integrator_growth_under_saturation():
    dt = 0.01
    with_aw = PID(1.0, 1.0, 0.0, dt, -1, 1)
    naive_integral = 0.0
    for _ in range(1000):  # 10 s of a large error that saturates the output
        with_aw.step(10.0, 0.0)
        naive_integral += dt * 10.0
    assert naive_integral == pytest.approx(100.0)
    assert with_aw.integral < 5.0
    # so when the error reverses, the output leaves saturation almost at once
    steps = 0
    while with_aw.step(-0.5, 0.0) > 0.99:
        steps += 1
    assert steps < 100


def test_output_is_saturated():
    pid = PID(10.0, 0.0, 0.0, 0.01, -1, 2)
    assert pid.step(5.0, 0.0) == 2
    assert pid.step(-5.0, 0.0) == -1


def test_two_channel_controller_signs():
    c = PIDController(PIDParams(), 0.01)
    obs = Observation(s_ref=10.0, s=0.0, d_ref=1.0, d=0.0)
    fx, delta = c.step(obs)
    assert fx > 0 and delta > 0  # behind the reference: accelerate; reference to the left: steer left
