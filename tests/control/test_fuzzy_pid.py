"""Report 000's fuzzy-adaptive PID: the rule base equals scikit-fuzzy; gains move as the
classic tables say."""

import numpy as np
import pytest
from skfuzzy import control as ctrl

from ego.control import FuzzyPIDController, FuzzyPIDParams, Observation, fuzzy_pid
from ego.control.fuzzy_pid import DKD, DKI, DKP

OUTPUTS = ["dkp", "dki", "dkd"]
TOL = 1e-6 * 2.0  # 1e-6 of the output range [-1, 1]


@pytest.fixture(scope="module")
def system():
    return fuzzy_pid.rule_base()


def test_tables_are_complete_7x7():
    for table in (DKP, DKI, DKD):
        assert len(table) == 7 and all(len(row) == 7 for row in table)


@pytest.mark.slow
@pytest.mark.long  # a minute; test_random_points_one_by_one_match_scikit_fuzzy runs by default
def test_dense_grid_and_edges_match_scikit_fuzzy(system):
    engine = fuzzy_pid.evaluator()
    axis = np.unique(np.concatenate([np.linspace(-11, 11, 45), np.linspace(-10, 10, 31)]))
    ee, cc = (a.ravel() for a in np.meshgrid(axis, axis))
    sim = ctrl.ControlSystemSimulation(system)
    sim.input["e"], sim.input["ec"] = ee, cc
    sim.compute()
    for o, name in enumerate(OUTPUTS):
        fast = engine.single2_output(o)
        got = np.array([fast(float(e), float(c)) for e, c in zip(ee, cc)])
        assert np.max(np.abs(got - sim.output[name])) < TOL, name


@pytest.mark.slow
def test_random_points_one_by_one_match_scikit_fuzzy(system):
    engine = fuzzy_pid.evaluator()
    sim = ctrl.ControlSystemSimulation(system, cache=False)
    rng = np.random.default_rng(4)
    for e, c in np.vstack([rng.uniform(-12, 12, (25, 2)), [[-10, 10], [10, -10], [0, 0]]]):
        sim.input["e"], sim.input["ec"] = e, c
        sim.compute()
        got = engine.evaluate2(float(e), float(c))
        for o, name in enumerate(OUTPUTS):
            assert got[o] == pytest.approx(sim.output[name], abs=TOL)


def test_large_error_raises_kp_and_lowers_ki():
    engine = fuzzy_pid.evaluator()
    dkp, dki, _ = engine.evaluate2(-10.0, -10.0)  # E = NB, EC = NB: dKp PB, dKi NB
    assert dkp > 0.8 and dki < -0.8
    assert engine.evaluate2(0.0, 0.0)[:2] == pytest.approx((0.0, 0.0), abs=1e-12)  # ZO, ZO


def test_gains_are_the_scales_at_zero_error_and_the_report_variant_uses_report_scales():
    c = FuzzyPIDController(FuzzyPIDParams(), 0.01)
    c.step(Observation())
    sig = c.signals()
    assert sig["kp_lon"] == pytest.approx(800.0) and sig["kp_lat"] == pytest.approx(0.008)
    r = FuzzyPIDController(FuzzyPIDParams(variant="report"), 0.01)
    r.step(Observation())
    assert r.signals()["kp_lat"] == pytest.approx(0.0005)
    assert r.signals()["kd_lat"] == pytest.approx(0.002 * (1 + 0.5 * fuzzy_pid.evaluator().evaluate2(0, 0)[2]))
