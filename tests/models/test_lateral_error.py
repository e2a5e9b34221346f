"""Report 003's lateral-error model against steady-state facts and the dynamic bicycle."""

import numpy as np
import pytest

from ego.models import (
    DynamicBicycle,
    DynamicBicycleParams,
    FixedStepIntegrator,
    LateralError,
    LateralErrorParams,
)

P = LateralErrorParams()


def test_understeer_gradient_and_feedforward_formula():
    caf, car = 2 * 65000.0, 2 * 65000.0
    L = 2.8
    assert P.understeer_gradient == pytest.approx(1650.0 * (1.55 * car - 1.25 * caf) / (L * caf * car))
    assert P.understeer_gradient == pytest.approx(1.3599e-3, rel=1e-3)  # slightly understeering
    assert P.feedforward(1 / 500, 8.0) == pytest.approx((L + P.understeer_gradient * 64) / 500)


@pytest.mark.parametrize("speed", [8.0, 25.0])
@pytest.mark.parametrize("kappa", [1 / 500, -1 / 200])
def test_feedforward_alone_holds_the_steady_state(speed, kappa):
    model = LateralError(P, speed)
    x, delta = model.steady_state(kappa)
    assert delta == pytest.approx(P.feedforward(kappa, speed), rel=1e-12)
    assert x[3] == pytest.approx(speed * kappa)
    Ad, Bd, Ed = model.discrete(0.01)
    for _ in range(3000):  # 30 s with the feedforward alone
        x = Ad @ x + Bd * delta + Ed * kappa
    assert x[0] == pytest.approx(0.0, abs=1e-9)  # no drift off the lane centre
    assert x[3] == pytest.approx(speed * kappa, rel=1e-9)  # yaw rate = v kappa
    assert model.lateral_accel(x, delta) == pytest.approx(speed**2 * kappa, rel=1e-9)


def test_the_restored_v_r_term_matters():
    # with it: the understeer term, 30 % more steer at 25 m/s on R 200 m
    model = LateralError(P, 25.0)
    _, delta = model.steady_state(1 / 200)
    assert delta == pytest.approx((2.8 + P.understeer_gradient * 625) / 200)
    # the report's equations (no -v r) claim a neutral-steering car: L kappa at any speed
    model.A[2, 3] += 25.0
    _, broken = model.steady_state(1 / 200)
    assert broken == pytest.approx(2.8 / 200)
    assert delta / broken == pytest.approx(1.30, abs=0.01)


@pytest.mark.parametrize("speed", [8.0, 25.0])
def test_feedforward_and_understeer_match_the_dynamic_bicycle(speed):
    """Report 002's model with report 003's car: K_us is the same formula, and the
    feed-forward steer makes its steady yaw rate v kappa."""
    dyn = DynamicBicycleParams(m=1650.0, Iz=3200.0, lf=1.25, lr=1.55, Cf=-65000.0, Cr=-65000.0)
    assert dyn.understeer_gradient == pytest.approx(P.understeer_gradient, rel=1e-12)
    kappa = 1 / 500
    delta = P.feedforward(kappa, speed)
    car = DynamicBicycle(dyn)
    integ = FixedStepIntegrator(car.rhs, 0.01, n_states=6)
    x = (0.0, speed, 0.0, 0.0, 0.0, 0.0)
    for _ in range(2000):
        x = integ.step(x, (-x[5] * x[3], delta))  # a_x = -r v holds the speed
    assert x[1] == pytest.approx(speed, rel=1e-6)
    assert x[5] == pytest.approx(speed * kappa, rel=2e-4)  # cos(delta) ~ 1 - 1e-5


def test_zero_order_hold_equals_fine_rk4():
    model = LateralError(P, 8.0)
    Ad, Bd, Ed = model.discrete(0.01)
    x0 = np.array([0.3, -0.02, 0.1, 0.05])
    exact = Ad @ x0 + Bd * 0.04 + Ed * 0.002
    integ = FixedStepIntegrator(model.rhs, 0.01, substeps=20, n_states=4)
    np.testing.assert_allclose(integ.step(tuple(x0), (0.04, 0.002)), exact, atol=1e-13)


def test_positive_steer_moves_left_and_mirror_symmetry():
    model = LateralError(P, 8.0)
    d = model.derivatives([0, 0, 0, 0], [0.05, 0.0])
    assert d[2] > 0 and d[3] > 0
    x, u = np.array([0.2, 0.01, -0.1, 0.03]), np.array([0.02, 1 / 300])
    np.testing.assert_allclose(model.derivatives(-x, -u), -model.derivatives(x, u), atol=1e-15)


def test_the_matrix_exponential_matches_scipy_and_its_bits_do_not_depend_on_the_blas_kernel():
    """The zero-order hold's matrix exponential is computed in one fixed order on plain floats:
    scipy's expm agrees to a few units in the last place, and the bits are the same whichever
    kernel OpenBLAS picks for the processor. (scipy's expm multiplies through BLAS: with
    OPENBLAS_CORETYPE=Haswell and SkylakeX it gave different bits, and report 003's unstable
    gains turned the last bit into a different results table.)"""
    import hashlib
    import os
    import subprocess
    import sys

    from scipy.linalg import expm

    from ego.models.lateral_error import LateralError, LateralErrorParams, expm_fixed_order

    for speed in (2.0, 8.3, 25.0, 40.0):
        model = LateralError(LateralErrorParams(), speed)
        M = np.zeros((6, 6))
        M[:4, :4], M[:4, 4], M[:4, 5] = model.A, model.B, model.E
        for dt in (0.001, 0.01, 0.1):
            np.testing.assert_allclose(expm_fixed_order(M * dt), expm(M * dt), rtol=1e-13, atol=1e-15)
    assert np.array_equal(expm_fixed_order(np.zeros((3, 3))), np.eye(3))
    np.testing.assert_allclose(expm_fixed_order(np.array([[1.0, 1.0], [0.0, 1.0]])), np.e * np.array([[1, 1], [0, 1]]))
    for bad in (np.zeros((2, 3)), np.array([[np.inf]])):
        with pytest.raises(ValueError):
            expm_fixed_order(bad)

    # the bits under two OpenBLAS kernels every x86-64 processor of these years runs (a fresh
    # process each: OpenBLAS reads the variable when it loads)
    code = (
        "import hashlib, numpy as np; from ego.models.lateral_error import LateralError; "
        "Ad, Bd, Ed = LateralError(speed=8.3).discrete(0.01); "
        "print(hashlib.sha256(np.concatenate([Ad.ravel(), Bd, Ed]).tobytes()).hexdigest())"
    )
    here = LateralError(LateralErrorParams(), 8.3).discrete(0.01)
    expected = hashlib.sha256(np.concatenate([here[0].ravel(), here[1], here[2]]).tobytes()).hexdigest()
    for kernel in ("Haswell", "Nehalem"):
        env = {**os.environ, "OPENBLAS_CORETYPE": kernel}
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
        assert out.stdout.strip() == expected, kernel


def test_the_matrix_exponential_wakes_no_blas_thread_pool():
    """It uses no BLAS at all: the libraries' thread counts stay as they were (scipy's expm of
    this 6 x 6 woke OpenBLAS's pool, whose threads then spun on the other core after every
    lane-centring reset)."""
    from threadpoolctl import threadpool_info

    from ego.models.lateral_error import LateralError, LateralErrorParams

    before = [(i["filepath"], i["num_threads"]) for i in threadpool_info()]
    LateralError(LateralErrorParams(), 8.3).discrete(0.01)
    assert [(i["filepath"], i["num_threads"]) for i in threadpool_info()] == before
