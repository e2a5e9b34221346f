"""RBF adaptive sliding-mode control: sliding law, the sign(s_Y) fix, boundary layer."""

import math

import numpy as np
import pytest

from ego.control import Observation, RBFSMCController, RBFSMCParams


def test_report_variant_switches_the_lateral_channel_on_s_x():
    # s_X > 0, s_Y < 0: the report's u_Y uses sign(s_X) = +1, the fix sign(s_Y) = -1
    obs = Observation(s=1.0, s_ref=0.0, d=-1.0, d_ref=0.0)
    fixed = RBFSMCController(RBFSMCParams(phi_lat=0.0, phi_lon=0.0, w0=0.0), 0.01)
    report = RBFSMCController(RBFSMCParams(variant="report", w0=0.0), 0.01)
    _, d_fixed = fixed.step(obs)
    _, d_report = report.step(obs)
    s_y = 0.5 * -1.0
    assert d_fixed == pytest.approx(0.6 * (-s_y + 0.1))
    assert d_report == pytest.approx(0.6 * (-s_y - 0.1))


def test_boundary_layer_is_linear_inside_and_saturates_outside():
    c = RBFSMCController(RBFSMCParams(phi_lon=0.5, w0=0.0), 0.01)
    fx_in, _ = c.step(Observation(s=0.1, s_ref=0.0))  # s_X = 0.1 < phi
    assert fx_in == pytest.approx(1000 * (-0.1 - 2.0 * 0.1 / 0.5))
    fx_out, _ = c.step(Observation(s=3.0, s_ref=0.0))
    assert fx_out == pytest.approx(1000 * (-3.0 - 2.0))


def test_adaptive_law_moves_weights_along_s_times_h():
    c = RBFSMCController(RBFSMCParams(), 0.01)
    c.reset(seed=0)
    obs = Observation(s=0.2, s_ref=0.0, d=0.1, d_ref=0.0)
    h = c._basis(np.array([obs.s, obs.d, obs.ds, obs.dd]))
    before = c.w_lon.copy()
    c.step(obs)
    np.testing.assert_allclose(c.w_lon - before, 0.01 * 1000.0 * c.s_lon * h)


def test_sliding_mode_drives_a_double_integrator_to_its_reference():
    # x'' = u (per unit gain): on s = x - r + x' the error decays like exp(-t)
    c = RBFSMCController(RBFSMCParams(fx_gain=1.0, delta_gain=1.0), 0.001)
    x, v = 0.0, 0.0
    for _ in range(10000):
        fx, _ = c.step(Observation(s=x, ds=v, s_ref=2.0, ds_ref=0.0))
        v += 0.001 * fx
        x += 0.001 * v
    assert x == pytest.approx(2.0, abs=1e-3) and abs(v) < 1e-2
    assert math.isfinite(c.signals()["rbf_norm_lon"])
