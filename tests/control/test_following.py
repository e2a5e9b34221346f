"""Report 004's car-following controllers: the PID law, sampling, limits, and the BP-NN PID's
incremental law and back-propagation."""

import copy
import math
from dataclasses import replace

import numpy as np
import pytest
from twins import twin_inputs

from ego.control.following import (
    BPPIDAcc,
    BPPIDAccParams,
    FollowingObservation,
    FollowingPID,
    FollowingPIDParams,
    PlatoonControl,
)
from ego.models import SpacingPolicy
from ego.params import ConfigError

DT = 0.01


def _obs(gap=8.0, speed=10.0, accel=0.0, lead_speed=10.0, max_accel=2.5, max_decel=8.0):
    return FollowingObservation(
        gap=gap,
        speed=speed,
        accel=accel,
        lead_speed=lead_speed,
        policy=SpacingPolicy(standstill_gap=3.0, headway=0.2),
        max_accel=max_accel,
        max_decel=max_decel,
    )


def _free(gap, speed=10.0):
    """An observation of a car without actuator limits (to see the control law itself)."""
    return _obs(gap=gap, speed=speed, max_accel=math.inf, max_decel=math.inf)


def test_observation_spacing_error_and_rate():
    o = _obs(gap=8.0, speed=10.0, accel=1.0, lead_speed=12.0)
    assert o.desired_gap == pytest.approx(5.0)
    assert o.spacing_error == pytest.approx(3.0)
    assert o.spacing_error_rate == pytest.approx(12.0 - 10.0 - 0.2 * 1.0)


def test_pid_law_with_the_reports_gains():
    ctrl = FollowingPID(FollowingPIDParams(period=0.1), DT)
    ctrl.reset(seed=0)
    o = _obs(gap=6.0, speed=10.0, lead_speed=10.5)  # e = 1 m, de = 0.5 m/s
    u, steer = ctrl.step(o)
    assert steer == 0.0
    # the integral is updated after the output (the PID class's discrete law)
    assert u == pytest.approx(0.85 * 1.0 + 0.3 * 0.5)
    assert ctrl.pid.integral == pytest.approx(0.1 * 1.0)


def test_command_is_held_for_one_control_period():
    ctrl = FollowingPID(FollowingPIDParams(period=0.05), DT)
    ctrl.reset()
    outputs = [ctrl.step(_obs(gap=5.0 + 0.1 * k))[0] for k in range(10)]
    assert outputs[:5] == [outputs[0]] * 5 and outputs[5:] == [outputs[5]] * 5
    assert outputs[5] != outputs[0]


def test_period_must_be_a_whole_multiple_of_dt():
    with pytest.raises(ConfigError, match="period: 0.015"):
        FollowingPID(FollowingPIDParams(period=0.015), DT)
    with pytest.raises(ConfigError, match="period"):
        BPPIDAcc(BPPIDAccParams(period=0.025), DT)


def test_pid_saturates_at_the_cars_limits_without_winding_up():
    ctrl = FollowingPID(FollowingPIDParams(period=0.1), DT)
    ctrl.reset()
    far = _obs(gap=60.0)  # 55 m too far back
    for _ in range(6000):
        u, _ = ctrl.step(far)
    assert u == 2.5
    # back-calculation (tracking time constant T_t = sqrt(Ti Td) = sqrt(kd/ki)): the integral
    # settles where u_unsat = u_sat + ki T_t e instead of growing by e T every period
    # (without it: 55 m x 60 s = 3300 m s)
    t_t = math.sqrt(0.3 / 0.2)
    assert ctrl.pid.integral == pytest.approx((2.5 - 0.85 * 55.0 + 0.2 * t_t * 55.0) / 0.2, rel=1e-6)
    close = _obs(gap=1.0, speed=10.0, lead_speed=5.0)
    for _ in range(500):
        u, _ = ctrl.step(close)
    assert u == -8.0


def _bp(period=1.0, **kw):
    ctrl = BPPIDAcc(BPPIDAccParams(period=period, **kw), period)
    ctrl.reset(seed=3)
    return ctrl


def test_bp_initial_weights_follow_the_report():
    ctrl = _bp()
    assert ctrl.w1.shape == (5, 3) and ctrl.w2.shape == (3, 5)  # 3-5-3
    assert np.all(np.abs(ctrl.w1) <= 0.5) and np.all(np.abs(ctrl.w2) <= 0.5)
    again = _bp()
    np.testing.assert_array_equal(ctrl.w1, again.w1)  # seeded
    other = BPPIDAcc(BPPIDAccParams(period=1.0), 1.0)
    other.reset(seed=4)
    assert not np.array_equal(ctrl.w1, other.w1)


def test_bp_gains_are_in_0_1_and_apply_the_reports_incremental_law():
    """At period T = 1 s (the report's) and no learning: u(k) = u(k-1) + Kp (e - e1) + Ki e +
    Kd (e - 2 e1 + e2) with the network's gains."""
    ctrl = _bp(learning_rate=0.0, momentum=0.0)
    errors = [0.5, 1.2, -0.4, 0.9]
    u_prev, e1, e2 = 0.0, 0.0, 0.0
    for e in errors:
        o = _free(gap=5.0 + e)
        x = np.array([o.gap - 3.0, 0.2 * o.speed, o.spacing_error])
        gains = 0.5 * (1 + np.tanh(ctrl.w2 @ np.tanh(ctrl.w1 @ x)))
        u, _ = ctrl.step(o)
        expected = u_prev + gains[0] * (e - e1) + gains[1] * e + gains[2] * (e - 2 * e1 + e2)
        assert u == pytest.approx(expected, rel=1e-12)
        assert np.all((gains > 0) & (gains < 1))
        assert [ctrl.signals()[k] for k in ("kp", "ki", "kd")] == pytest.approx(list(gains))
        u_prev, e1, e2 = u, e, e1


def test_bp_gains_are_continuous_ones_at_any_period():
    """Kp (e - e1) + Ki T e + Kd (e - 2 e1 + e2)/T: the same PID in continuous terms."""
    T = 0.1
    ctrl = BPPIDAcc(BPPIDAccParams(period=T, learning_rate=0.0), DT)
    ctrl.reset(seed=1)
    o = _free(gap=6.0)  # e = 1 after e1 = e2 = 0
    x = np.array([3.0, 2.0, 1.0])
    kp, ki, kd = 0.5 * (1 + np.tanh(ctrl.w2 @ np.tanh(ctrl.w1 @ x)))
    assert ctrl.step(o)[0] == pytest.approx(kp + ki * T + kd / T)


def test_bp_update_is_gradient_descent_on_the_squared_error():
    """dW = eta e du/dW (plant Jacobian sign +1): the back-propagated step equals finite
    differences of the network's command with respect to every weight."""
    ctrl = _bp(learning_rate=0.25, momentum=0.0)
    ctrl.step(_obs(gap=5.7))  # a history: e1 = 0.7
    w1, w2 = ctrl.w1.copy(), ctrl.w2.copy()
    u_before, e1, e2 = ctrl.u, ctrl.e1, ctrl.e2
    o = _obs(gap=4.1, speed=9.0)
    e = o.spacing_error
    x = np.array([o.gap - 3.0, 0.2 * o.speed, e])
    terms = np.array([e - e1, e, e - 2 * e1 + e2])

    def command(a, b):
        return u_before + 0.5 * (1 + np.tanh(b @ np.tanh(a @ x))) @ terms

    ctrl.step(o)
    h = 1e-7
    for w, moved, grad_of in (
        (w2, ctrl.w2, lambda d: command(w1, w2 + d)),
        (w1, ctrl.w1, lambda d: command(w1 + d, w2)),
    ):
        numeric = np.zeros_like(w)
        for idx in np.ndindex(w.shape):
            d = np.zeros_like(w)
            d[idx] = h
            numeric[idx] = (grad_of(d) - grad_of(-d)) / (2 * h)
        np.testing.assert_allclose(moved - w, 0.25 * e * numeric, rtol=1e-6, atol=1e-10)


def test_bp_momentum_carries_the_previous_step():
    """dW(k) = eta g(k) + alpha dW(k-1): a twin without momentum, from the same state,
    takes the plain step eta g(k)."""
    ctrl = _bp(learning_rate=0.25, momentum=0.5)
    ctrl.step(_obs(gap=5.7))
    previous = (ctrl.dw1.copy(), ctrl.dw2.copy())
    assert np.any(previous[1] != 0.0)
    twin = copy.deepcopy(ctrl)
    twin.params = replace(ctrl.params, momentum=0.0)
    before = (ctrl.w1.copy(), ctrl.w2.copy())
    o = _obs(gap=5.2, speed=10.5)
    ctrl.step(o)
    twin.step(o)
    for k in range(2):
        plain = (twin.dw1, twin.dw2)[k]
        np.testing.assert_allclose((ctrl.dw1, ctrl.dw2)[k], plain + 0.5 * previous[k], rtol=1e-12)
        np.testing.assert_allclose((ctrl.w1, ctrl.w2)[k] - before[k], (ctrl.dw1, ctrl.dw2)[k], atol=1e-15)


def test_bp_command_stays_within_the_cars_limits():
    ctrl = _bp(period=0.1)
    for _ in range(200):
        u, _ = ctrl.step(_obs(gap=80.0))
        assert -8.0 <= u <= 2.5 and math.isfinite(u)
    assert ctrl.u == u  # the stored command is the saturated one: no wind-up


def test_platoon_control_gives_each_follower_its_own_controller_and_seed():
    members = [BPPIDAcc(BPPIDAccParams(), DT) for _ in range(3)]
    platoon = PlatoonControl(members, ("f1", "f2", "f3"))
    platoon.reset(seed=7)
    assert not np.array_equal(members[0].w1, members[1].w1)
    again = [BPPIDAcc(BPPIDAccParams(), DT) for _ in range(3)]
    PlatoonControl(again, ("f1", "f2", "f3")).reset(seed=7)
    np.testing.assert_array_equal(members[2].w2, again[2].w2)
    actions = platoon.step([_obs(gap=5.0), _obs(gap=6.0), _obs(gap=4.0)])
    assert len(actions) == 3 and all(steer == 0.0 for _, steer in actions)
    assert list(platoon.signals()) == [f"{k}_{f}" for f in ("f1", "f2", "f3") for k in ("kp", "ki", "kd")]
    with pytest.raises(ValueError):
        PlatoonControl(members, ("f1",))


def test_bp_c_twin_gives_the_python_updates_to_the_bit():
    rng = np.random.default_rng(13)
    for trial in range(16):
        params = BPPIDAccParams(
            learning_rate=float(rng.choice([0.0, 0.25, 1.0])),
            momentum=float(rng.choice([0.0, 0.01, 0.9])),
            period=float(rng.choice([0.01, 0.1])),
        )
        native, python = BPPIDAcc(params, DT), BPPIDAcc(params, DT)
        python.native = False
        native.reset(seed=trial)
        python.reset(seed=trial)
        assert native.native and not python.native
        scale = float(rng.choice([0.1, 1.0, 10.0, 1e4]))  # 1e4: saturated tanh, clipped commands
        for v, swap in twin_inputs(rng, 5, 200, scale, trial, inject_at=150, replace_at=100):
            if swap:  # weights replaced between updates
                for c in (native, python):
                    c.w2 = c.w2 * 0.5
            o = FollowingObservation(
                gap=30.0 + v[0],
                speed=20.0 + v[1],
                accel=v[2],
                lead_speed=20.0 + v[3],
                lead_accel=v[4],
                policy=SpacingPolicy(),
                max_accel=float(rng.choice([2.5, math.inf])),
                max_decel=8.0,
            )
            with np.errstate(all="ignore"):
                out_n, out_p = native.step(o), python.step(o)
            assert np.array_equal(out_n, out_p, equal_nan=True)
            for a, b in (
                (native.w1, python.w1),
                (native.w2, python.w2),
                (native.dw1, python.dw1),
                (native.dw2, python.dw2),
                (native.gains, python.gains),
                ([native.u, native.e1, native.e2], [python.u, python.e1, python.e2]),
                (list(native.signals().values()), list(python.signals().values())),
            ):
                assert np.array_equal(a, b, equal_nan=True)


@pytest.mark.parametrize("native", [True, False], ids=["c-twin", "python"])
def test_bp_copy_mid_run_updates_on_as_the_original(native):
    import pickle

    ctrl = _bp(learning_rate=0.25, momentum=0.5, period=0.1)
    ctrl.native = ctrl.native and native
    ctrl.reset(seed=3)
    for k in range(30):
        ctrl.step(_obs(gap=5.0 + 0.1 * k))
    copies = [pickle.loads(pickle.dumps(ctrl)), copy.deepcopy(ctrl)]
    for k in range(40):
        o = _obs(gap=6.0 - 0.05 * k, speed=10.0 + 0.02 * k)
        out = ctrl.step(o)
        for twin in copies:
            assert twin.native == ctrl.native and twin.step(o) == out
            assert np.array_equal(twin.w1, ctrl.w1) and twin.signals() == ctrl.signals()
