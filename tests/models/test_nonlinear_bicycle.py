"""Report 000's nonlinear bicycle against facts derived by hand, not against itself."""

import math

import numpy as np
import pytest

from ego.models import FixedStepIntegrator, NonlinearBicycle, NonlinearBicycleParams, State, rk4_step

P = NonlinearBicycleParams()
CAR = NonlinearBicycle(P)


def test_derivatives_returns_float_array_of_six():
    d = CAR.derivatives([0, 20, 0, 0, 0, 0], [0, 0])
    assert isinstance(d, np.ndarray) and d.dtype == float and d.shape == (6,)


def test_axle_loads_sum_to_weight():
    assert P.Fzf + P.Fzr == pytest.approx(P.m * P.g)
    assert P.Fzf == pytest.approx(1.45 / 2.8 * 1400 * 9.806)


@pytest.mark.parametrize("axle, expected_kn_per_rad", [("front", 92.4), ("rear", 86.0)], ids=["front", "rear"])
def test_small_slip_cornering_stiffness(axle, expected_kn_per_rad):
    # C_alpha = By*Cy*Dy*Fz per degree -> *180/pi per radian (SPEC: ~92.4 and ~86.0 kN/rad).
    fz = P.Fzf if axle == "front" else P.Fzr
    t = P.tyre
    closed_form = t.By * t.Cy * t.Dy * fz * 180.0 / math.pi
    assert closed_form / 1000.0 == pytest.approx(expected_kn_per_rad, abs=0.1)
    slip = 1e-4  # deg
    numeric = (t.force(slip, fz) - t.force(-slip, fz)) / (2 * math.radians(slip))
    assert numeric == pytest.approx(closed_form, rel=1e-6)


def test_friction_peak_is_0_7_near_7_9_degrees():
    alphas = np.linspace(0.0, 30.0, 30001)
    mu = np.array([P.tyre.force(a, 1.0) for a in alphas])
    peak = alphas[np.argmax(mu)]
    assert peak == pytest.approx(7.9, abs=0.1)
    assert mu.max() == pytest.approx(0.70, abs=1e-6)


def test_rolling_resistance_is_balanced_by_68_6_newtons():
    fx = P.f * P.m * P.g / P.Nw
    assert fx == pytest.approx(68.6, abs=0.05)
    d = CAR.derivatives([0, 20, 0, 0, 0, 0], [fx, 0])
    assert d[State.U] == pytest.approx(0.0, abs=1e-12)
    # and the speed holds over a long integration
    x = (0.0, 20.0, 0.0, 0.0, 0.0, 0.0)
    for _ in range(1000):
        x = rk4_step(CAR.rhs, x, (fx, 0.0), 0.01)
    assert x[State.U] == pytest.approx(20.0, abs=1e-9)
    assert x[State.X] == pytest.approx(200.0, abs=1e-6)


def test_coasting_loses_speed_at_f_times_g():
    d = CAR.derivatives([0, 20, 0, 0, 0, 0], [0.0, 0.0])
    assert d[State.U] == pytest.approx(-P.f * P.g)


def test_left_right_mirror_symmetry():
    x = np.array([3.0, 18.0, 1.2, 0.4, 0.05, 0.1])
    u = np.array([500.0, 0.03])
    mirror_x = np.array([1, 1, -1, -1, -1, -1.0])
    d = CAR.derivatives(x, u)
    d_m = CAR.derivatives(x * mirror_x, u * np.array([1, -1.0]))
    np.testing.assert_allclose(d_m, d * mirror_x, rtol=1e-12, atol=1e-12)


def test_friction_circle_scales_rear_force_and_traction_together():
    # Large traction plus a rear slip: combined force exceeds mu*m*g and is scaled back.
    x = (0.0, 20.0, 0.0, 1.0, 0.0, 0.0)
    fx = 8000.0
    _, alpha_r, _, F_yr, Fx_eff = CAR.tyre_forces(x, (fx, 0.0))
    unscaled_yr = P.tyre.force(alpha_r, P.Fzr)
    total = math.hypot(P.Nw * fx, unscaled_yr)
    assert total > P.F_max
    assert math.hypot(P.Nw * Fx_eff, F_yr) == pytest.approx(P.F_max)
    assert Fx_eff / fx == pytest.approx(F_yr / unscaled_yr)
    # below the circle nothing is scaled
    _, _, _, F_yr2, Fx2 = CAR.tyre_forces(x, (100.0, 0.0))
    assert Fx2 == 100.0 and F_yr2 == pytest.approx(P.tyre.force(alpha_r, P.Fzr))


def test_steady_state_cornering_is_neutral_steer():
    # Load-proportional tyres with a = 1.35, b = 1.45: C_f/Fzf == C_r/Fzr, so the
    # stability factor K = m/L * (b/C_f - a/C_r) / ... vanishes and r = u*delta/L.
    u0, delta = 20.0, 0.01
    x = (0.0, u0, 0.0, 0.0, 0.0, 0.0)
    fx = P.f * P.m * P.g / P.Nw
    integ = FixedStepIntegrator(CAR.rhs, 0.01, substeps=2)
    for _ in range(1500):
        x = integ.step(x, (fx, delta))
    # small-angle steady state of the linearised bicycle
    assert x[State.R] == pytest.approx(x[State.U] * delta / P.wheelbase, rel=0.02)


def test_positive_steer_turns_left():
    d = CAR.derivatives([0, 20, 0, 0, 0, 0], [0.0, 0.02])
    assert d[State.V] > 0 and d[State.R] > 0


def test_integrator_rejects_bad_settings():
    with pytest.raises(ValueError, match="substeps"):
        FixedStepIntegrator(CAR.rhs, 0.01, substeps=0)
    with pytest.raises(ValueError, match="dt"):
        FixedStepIntegrator(CAR.rhs, 0.0)


def test_rk4_is_fourth_order():
    # dx/dt = -x has the exact solution exp(-t): error ratio for h and h/2 is ~16.
    def rhs(x, u):
        return (-x[0],)

    def err(h):
        x = (1.0,)
        for _ in range(round(1.0 / h)):
            x = rk4_step(rhs, x, (), h)
        return abs(x[0] - math.exp(-1.0))

    assert err(0.1) / err(0.05) == pytest.approx(16.0, rel=0.05)
