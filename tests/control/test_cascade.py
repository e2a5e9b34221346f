"""Report 003's cascade PID and its differential-evolution tuner."""

import json
import math

import numpy as np
import pytest

from ego.control import Observation, controller_spec
from ego.control.cascade import (
    GAIN_NAMES,
    REPORT_GAINS,
    TUNED_PRESET,
    Cascade,
    CascadePID,
    CascadePIDParams,
    adaptive_gain,
    load_preset,
)
from ego.models import LateralErrorParams
from ego.params import ConfigError
from ego.train.lane_centering import (
    Setup,
    TuneSpec,
    cost,
    simulate_batch,
    simulate_drives,
    simulate_single,
    tune,
)

S8, S25 = Setup(speed=8.0), Setup(speed=25.0)


@pytest.fixture(scope="module")
def kappas():
    return S8.curvature(), S25.curvature()


@pytest.fixture(scope="module")
def population():
    rng = np.random.default_rng(11)
    return np.vstack([REPORT_GAINS, load_preset(), rng.uniform(0.0, 2.0, (22, 12))])


@pytest.mark.slow
@pytest.mark.long
def test_batch_equals_single_runs_member_by_member(kappas, population):
    """The tuner's vectorised simulation (both speeds in one time loop) against the plain
    single-run simulation with the scenario's controller: the same errors at every step."""
    stats, recs = simulate_drives(population, [S8, S25], list(kappas), record=True)
    for b, (setup, kappa) in enumerate(zip((S8, S25), kappas)):
        for j, gains in enumerate(population):
            single = simulate_single(gains, setup, kappa)
            np.testing.assert_allclose(recs[b][j], single, rtol=0, atol=1e-9)
            a = np.abs(single)
            assert stats[b][0][j] == pytest.approx(a.max(), abs=1e-9)
            assert stats[b][1][j] == pytest.approx(a.mean(), abs=1e-9)
            assert stats[b][2][j] == pytest.approx(a.std(), abs=1e-9)


def test_one_member_and_one_drive_agree_with_the_batch(kappas, population):
    (mx, mn, sd), rec = simulate_batch(population[:1], S8, kappas[0], record=True)
    np.testing.assert_allclose(rec[0], simulate_single(population[0], S8, kappas[0]), rtol=0, atol=1e-9)


def test_the_first_straight_is_skipped_exactly():
    """From rest on a straight nothing moves: a drive that starts with a straight and one
    whose curvature starts at once give the same errors once shifted."""
    kappa = np.r_[np.zeros(500), np.full(1500, 1 / 300)]
    gains = np.array([load_preset()])
    (_, rec) = simulate_batch(gains, S8, kappa, record=True)
    assert (rec[0, :500] == 0).all()
    single = simulate_single(gains[0], S8, kappa)
    np.testing.assert_allclose(rec[0], single, rtol=0, atol=1e-9)


def test_the_reports_50_seconds_never_reach_the_curve():
    # report 003 simulated 50 s at 8 m/s: 400 m of the 1000 m straight, where any gains
    # give exactly 0.000 m - which is all its differential evolution ever saw
    kappa = S8.curvature()[:5000]
    assert (kappa == 0).all()
    rng = np.random.default_rng(3)
    stats = simulate_batch(rng.uniform(0, 2, (5, 12)), S8, kappa)
    assert all((s == 0).all() for s in stats)


def test_cost_is_the_reports():
    c = cost(np.array([0.3, 0.7]), np.array([0.1, 0.2]), np.array([0.05, 0.1]))
    assert c[0] == pytest.approx(0.3 + 0.05 + 0.005)
    assert c[1] == pytest.approx(0.7 + 0.1 + 0.01 + 10 * 0.2)
    assert cost(np.array([np.nan]), np.array([0.0]), np.array([0.0]))[0] >= 1e4


@pytest.mark.slow
@pytest.mark.long
def test_a_quick_tuning_improves_on_its_initial_population(tmp_path):
    out = tmp_path / "quick.json"
    preset = tune(TuneSpec.quick(seed=1), out, log=lambda *_: None)
    assert preset["cost"] < preset["initial_population_best_cost"]
    saved = json.loads(out.read_text())
    assert set(saved["gains"]) == set(GAIN_NAMES)
    gains = load_preset(str(out))
    assert len(gains) == 12 and all(0.0 <= g <= 2.0 for g in gains)
    assert set(saved["drives"]) == {"8 m/s", "25 m/s, +1 m off"}


def test_the_shipped_preset_is_a_full_report_setting_tuning():
    preset = json.loads(TUNED_PRESET.read_text())
    de = preset["differential_evolution"]
    assert (de["popsize"], de["maxiter"]) == (15, 100)
    assert preset["members_per_generation"] == 180
    assert de["tol"] == 0 and preset["generations"] == 100
    drives = preset["drives"]
    assert drives["8 m/s"]["max_abs_lateral_error"] < 0.01  # on the lateral-error model
    # from 1 m off at 25 m/s: back to the centre without overshoot, then the curve
    assert drives["25 m/s, +1 m off"]["max_abs_lateral_error"] == pytest.approx(1.0, abs=1e-9)
    assert drives["25 m/s, +1 m off"]["mean_abs_lateral_error"] < 0.05
    # the report's gains oscillate on the curve
    assert preset["report_gains"]["8 m/s"]["max_abs_lateral_error"] > 1.0


def test_adaptive_gain_is_the_reports():
    assert adaptive_gain(0.6) == 1.5 and adaptive_gain(-0.6) == 1.5
    assert adaptive_gain(0.05) == 0.8 and adaptive_gain(0.3) == 1.0
    assert adaptive_gain(0.5) == 1.0 and adaptive_gain(0.1) == 1.0


def test_signs_feedforward_and_limits():
    p = LateralErrorParams()
    law = Cascade(load_preset(), 0.01)
    # on the centre line, aligned, on a curve: the feed-forward steer, rate-limited from 0
    delta = law.step(0.0, 0.0, 0.0, 0.0, 1 / 500, 8.0)
    assert delta == pytest.approx(min(p.feedforward(1 / 500, 8.0), math.radians(30) * 0.01))
    law.reset()
    for _ in range(300):
        delta = law.step(0.0, 0.0, 0.0, 0.0, 1 / 500, 8.0)
    # ...and settles at the feed-forward with the errors zero
    assert delta == pytest.approx(p.feedforward(1 / 500, 8.0), rel=1e-6)
    law.reset()
    # left of the lane: steer right, within 25 deg whatever the error
    for _ in range(200):
        delta = law.step(5.0, 0.0, 0.0, 0.0, 0.0, 8.0)
    assert -math.radians(25) - 1e-12 <= delta < 0


def test_controller_presets_and_registry(tmp_path):
    assert controller_spec("cascade-pid", "lane-centering").params is CascadePIDParams
    assert CascadePIDParams(preset="report").gains() == REPORT_GAINS
    assert CascadePIDParams().gains() == load_preset()
    c = CascadePID(CascadePIDParams(), 0.01)
    o = Observation(d=0.2, speed=8.0, accel_ref=0.1)
    a_x, delta = c.step(o)
    assert a_x == 0.1 and delta < 0
    assert set(c.signals()) == {"psi_err_ref", "vy_ref", "r_ref", "delta_fb"}
    with pytest.raises(ConfigError, match="no tuned gains"):
        CascadePIDParams(gains_file=str(tmp_path / "none.json")).gains()
