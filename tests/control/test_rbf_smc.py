"""RBF adaptive sliding-mode control: sliding law, the sign(s_Y) fix, boundary layer."""

import math

import numpy as np
import pytest
from twins import twin_inputs

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


@pytest.mark.parametrize("variant", ["fixed", "report"])
def test_the_c_twin_gives_the_python_steps_to_the_bit(variant):
    rng = np.random.default_rng(12)
    for trial in range(12):
        params = RBFSMCParams(variant=variant, gamma=float(rng.choice([0.0, 1000.0, 1e6])))
        native, python = RBFSMCController(params, 0.01), RBFSMCController(params, 0.01)
        python.native = False
        native.reset(seed=trial)
        python.reset(seed=trial)
        assert native.native and not python.native
        scale = float(rng.choice([0.01, 1.0, 10.0, 1e3]))  # 1e3: the basis underflows to 0
        for v, replace in twin_inputs(rng, 8, 150, scale, trial, inject_at=100, replace_at=50):
            if replace:  # weights replaced between steps
                for c in (native, python):
                    c.w_lon = c.w_lon * 0.5
            obs = Observation(s_ref=v[0], s=v[1], ds_ref=v[2], ds=v[3], d_ref=v[4], d=v[5], dd_ref=v[6], dd=v[7])
            with np.errstate(all="ignore"):
                out_n, out_p = native.step(obs), python.step(obs)
                sig_n, sig_p = native.signals(), python.signals()
            assert np.array_equal(out_n, out_p, equal_nan=True)
            assert np.array_equal(native.w_lon, python.w_lon, equal_nan=True)
            assert np.array_equal(native.w_lat, python.w_lat, equal_nan=True)
            assert (native.w_lat is native.w_lon) == (python.w_lat is python.w_lon)
            assert np.array_equal(list(sig_n.values()), list(sig_p.values()), equal_nan=True)


def test_a_copy_mid_run_steps_on_as_the_original():
    import copy
    import pickle

    c = RBFSMCController(RBFSMCParams(), 0.01)
    obs = Observation(s_ref=1.0, s=0.5, ds_ref=20.0, ds=19.5, d_ref=0.2, d=0.1)
    for _ in range(10):
        c.step(obs)
    copies = [pickle.loads(pickle.dumps(c)), copy.deepcopy(c)]
    for _ in range(20):
        out = c.step(obs)
        for d in copies:
            assert d.step(obs) == out and np.array_equal(d.w_lon, c.w_lon) and d.signals() == c.signals()


def test_weights_of_another_dtype_are_refused_by_the_c_twin():
    c = RBFSMCController(RBFSMCParams(), 0.01)
    c.w_lon = np.zeros(20, dtype=np.float32)  # as many bytes as ten float64 weights
    with pytest.raises(TypeError, match="float64"):
        c.step(Observation(s_ref=1.0))


@pytest.mark.parametrize("native", [True, False], ids=["c-twin", "python"])
def test_weights_of_another_length_are_refused(native):
    c = RBFSMCController(RBFSMCParams(), 0.01)
    c.native = c.native and native
    c.w_lat = np.zeros(5)  # 10 nodes
    with pytest.raises(ValueError):
        c.step(Observation(s_ref=1.0))
