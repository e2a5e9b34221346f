"""Report 004's platoon in real SUMO: the hard brake, settling, string (in)stability against
the theory, the scale-model variant, several controlled vehicles, bad input, divergence."""

import math
import subprocess
import sys

import numpy as np
import pytest

from ego.control.following import FollowingObservation, PlatoonControl
from ego.params import ConfigError
from ego.runner import RunSpec, resolve, run
from ego.scenarios import string_stability as ss
from ego.scenarios.platoon import PlatoonScenario

pytestmark = pytest.mark.sumo

CONTROLLERS = ("pid", "bp-pid-acc")


def _run(controller="pid", seed=0, record=None, **overrides):
    return run(RunSpec("platoon", controller, seed, overrides, record=record))


@pytest.fixture(scope="module")
def default_runs():
    return {(c, s): _run(c, s) for c in CONTROLLERS for s in (0, 1, 2)}


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_hard_brake_to_a_stop_without_collision_at_the_default_headway(default_runs, controller):
    for seed in (0, 1, 2):
        r = default_runs[controller, seed]
        m = r.metrics
        assert r.status == "completed" and m["collision"] is False, (seed, m["status_detail"])
        stop = r.column("t") >= 60.0  # the leader brakes at 6 m/s^2 from 50 km/h to rest
        peak_decel = [-r.column(f"accel_{vid}")[stop].min() for vid in ("f1", "f2", "f3")]
        assert peak_decel[0] > 4.0 and peak_decel[0] > peak_decel[1] > peak_decel[2] > 2.5
        for vid in ("f1", "f2", "f3"):
            assert r.column(f"gap_{vid}")[stop].min() > 2.5
            # and come to rest d_s behind the car ahead (the PID's integral creeps the last cm)
            assert r.column(f"speed_{vid}")[-1] < 0.05
            assert abs(r.column(f"gap_{vid}")[-1] - 3.0) < 0.2
        assert m["min_gap"] > 2.5 and m["min_ttc"] > 1.0


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_spacing_error_settles_after_the_stop(default_runs, controller):
    for seed in (0, 1, 2):
        m = default_runs[controller, seed].metrics
        assert m["settle_times"]["stop@60s"] is not None and m["settle_times"]["stop@60s"] < 25.0
        for f in m["followers"].values():
            assert abs(f["settle_times"]["stop@60s"]) < 25.0


def test_pid_settles_after_every_manoeuvre_and_is_string_stable_at_two_seconds(default_runs):
    m = default_runs["pid", 0].metrics
    assert set(m["settle_times"]) == {"brake@10s", "accelerate@35s", "stop@60s"}
    assert all(t is not None and t < 22.0 for t in m["settle_times"].values())
    assert m["string_stable"] is True
    for pair in ("f1->f2", "f2->f3"):
        assert m["amplification"][pair]["peak_spacing_error"] < 1.0
        assert m["amplification"][pair]["l2_spacing_error"] < 1.0
    assert m["followers"]["f3"]["max_abs_spacing_error"] < m["followers"]["f1"]["max_abs_spacing_error"]


def test_metrics_per_follower_are_computed_from_the_trace(default_runs):
    r = default_runs["pid", 0]
    f2 = r.metrics["followers"]["f2"]
    e = r.column("e_f2")
    assert f2["rms_spacing_error"] == pytest.approx(math.sqrt(np.mean(e * e)), abs=1e-6)
    assert f2["max_abs_spacing_error"] == pytest.approx(np.max(np.abs(e)), abs=1e-6)
    assert f2["min_gap"] == pytest.approx(r.column("gap_f2").min(), abs=1e-4)
    a = r.column("accel_f2")
    assert f2["max_abs_jerk"] == pytest.approx(np.max(np.abs(np.diff(a))) / 0.01, abs=1e-5)
    # the spacing error is report 004's, from the gap SUMO measured and the car's own speed
    np.testing.assert_allclose(e, r.column("gap_f2") - 3.0 - 2.0 * r.column("speed_f2"), atol=1e-9)


def _sine_run(headway, omega, controller="pid"):
    return _run(
        controller,
        headway=headway,
        manoeuvres="none",
        sine_amplitude=1.0,
        sine_omega=omega,
        duration=150.0,
        sine_transient=60.0,
    )


def test_a_short_headway_amplifies_as_the_theory_predicts():
    """lambda = 1 s is below the sqrt(2/kp) = 1.53 s the report's gains need: a leader
    oscillating at the theory's worst frequency grows by |H(jw)| per car."""
    theory = lambda w: ss.pid_transfer(w, 0.85, 0.2, 0.3, 1.0, lag=0.2, delay=0.05)  # noqa: E731 - T/2
    peak, omega = ss.peak_gain(theory)
    assert peak > 1.4
    r = _sine_run(1.0, omega)
    m = r.metrics
    assert r.status == "completed" and m["string_stable"] is False
    for pair in ("f1->f2", "f2->f3"):
        assert m["frequency_gain"][pair] == pytest.approx(peak, rel=0.02)
    amplitudes = [np.ptp(r.column(f"speed_{v}")[r.column("t") >= 60.0]) for v in ("f1", "f2", "f3")]
    assert amplitudes[0] < amplitudes[1] < amplitudes[2]  # it grows down the platoon


def test_the_default_headway_attenuates_as_the_theory_predicts():
    omega = 0.9
    expected = abs(ss.pid_transfer(omega, 0.85, 0.2, 0.3, 2.0, lag=0.2, delay=0.05))
    m = _sine_run(2.0, omega).metrics
    assert expected < 0.7 and m["string_stable"] is True
    for pair in ("f1->f2", "f2->f3"):
        assert m["frequency_gain"][pair] == pytest.approx(expected, rel=0.02)


@pytest.mark.parametrize("controller", CONTROLLERS)
def test_the_reports_own_headway_is_string_unstable_and_crashes(controller):
    """lambda = 0.2 s (report 004) with its gains: already the first 2 m/s^2 braking grows
    down the platoon until a follower runs into the car ahead."""
    m = _run(controller, headway=0.2).metrics
    assert m["status"] == "collision" and m["string_stable"] is False
    assert 10.0 < m["sim_time"] < 16.0  # a few seconds into the first braking
    assert m["amplification"]["leader->f1"]["peak_accel"] > 1.0


def test_controller_off_runs_into_the_leader():
    r = _run("none")
    assert r.status == "collision" and r.metrics["collision_with"] == "leader"
    assert "f1" in r.metrics["status_detail"] and r.metrics["string_stable"] is None


def test_same_seed_same_metrics_and_trace():
    a, b = _run("bp-pid-acc", seed=4, duration=30), _run("bp-pid-acc", seed=4, duration=30)
    strip = lambda m: {k: v for k, v in m.items() if k != "wall_time"}  # noqa: E731
    assert strip(a.metrics) == strip(b.metrics)
    np.testing.assert_array_equal(a.trace, b.trace)
    c = _run("bp-pid-acc", seed=5, duration=30)
    assert not np.array_equal(a.trace, c.trace)  # other random initial weights


def test_scale_model_variant_is_the_reports_three_car_test():
    r = _run("pid", variant="scale-model")
    m = r.metrics
    assert r.status == "completed" and set(m["followers"]) == {"f1", "f2"}  # 3 cars
    cruise = (r.column("t") > 5.0) & (r.column("t") < 40.0)
    np.testing.assert_allclose(r.column("lead_speed")[cruise], 0.5, atol=1e-9)  # 50 cm/s
    assert m["min_gap"] == pytest.approx(0.4, abs=0.02)  # 40 cm at standstill, never less
    assert all(t is not None for t in m["settle_times"].values())
    # explicit settings still win over the variant's preset
    config = resolve(RunSpec("platoon", "pid", 0, {"variant": "scale-model", "followers": "3"})).config
    assert config.followers == 3 and config.standstill_gap == 0.4 and config.variant == "scale-model"


def test_ten_followers_are_all_pushed_into_sumo():
    """The bridge holds every follower: where SUMO has each one is where its model is."""
    spec = RunSpec("platoon", "pid", 0, {"followers": "10", "duration": "40"})
    r = resolve(spec)
    cls, config, ctrl, params = r.scenario_cls, r.config, r.controller, r.controller_params
    scenario = cls(config, cls.build_controller(ctrl, params, config), seed=0)
    try:
        obs = scenario.reset()
        assert len(obs) == 10 and set(scenario.bridge.controlled) == set(scenario.ids)
        for _ in range(1500):  # 15 s: through the braking
            obs = scenario.step(scenario.controller.step(obs))
        veh = scenario.bridge.libsumo.vehicle
        for vid, plant in scenario.plants.items():
            assert veh.getLanePosition(vid) == pytest.approx(plant.state[0], abs=1e-6)
        assert [veh.getLeader(vid, 100.0)[0] for vid in scenario.ids] == ["leader", *scenario.ids[:-1]]
    finally:
        scenario.close()


class _NaNAfter:
    """A follower controller that breaks down after ``when`` s."""

    def __init__(self, when):
        self.when = when

    def reset(self, *, seed=None):
        pass

    def step(self, obs: FollowingObservation):
        return (math.nan if obs.t >= self.when else 0.0), 0.0

    def signals(self):
        return {}


def test_a_diverging_controller_ends_the_run_and_keeps_the_recording(tmp_path):
    from rerun.chunk import RrdReader

    from ego.record import RerunRecorder

    config = PlatoonScenario.config_cls(duration=20.0)
    ids = ("f1", "f2", "f3")
    control = PlatoonControl([_NaNAfter(9.0), _NaNAfter(5.0), _NaNAfter(9.0)], ids)
    path = tmp_path / "nan.rrd"
    result = PlatoonScenario(config, control, recorder=RerunRecorder(path, background=False)).run()
    assert result.status == "diverged" and "f2" in result.metrics["status_detail"]
    assert result.metrics["sim_time"] == pytest.approx(5.01, abs=0.011)
    assert RrdReader(path).recordings()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--set", "period=0.015"], "bad value for period: 0.015"),
        (["--set", "manoeuvres=10:20"], "bad value for manoeuvres"),
        (["--set", "followers=11"], "bad value for followers: 11"),
        (["--set", "variant=toy"], "bad value for variant: 'toy'"),
        (["--set", "manoeuvres=none", "--set", "start_speed=100", "--set", "duration=200"], "road"),
        (["--set", "start_error=-40"], "bad value for start_error"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message):
    p = subprocess.run(
        [sys.executable, "-m", "ego", "run", "platoon", "-c", "pid", *args], capture_output=True, text=True, timeout=120
    )
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ego: error:") and message in lines[0], p.stderr


def _step_response(period):
    """Report 004's simulation: one follower, lambda 0.2 s, no lag, 1 m too far back."""
    r = _run(
        "pid", followers=1, manoeuvres="none", start_error=1.0, headway=0.2, lag=0.0, period=period, duration=120.0
    )
    t, e = r.column("t"), np.abs(r.column("e_f1"))
    return r, [e[(t >= a) & (t < a + 20.0)].max() for a in range(0, 120, 20)]


def test_a_start_off_the_desired_gap_is_a_settling_window():
    m = _run("pid", followers=1, manoeuvres="none", start_error=3.0, duration=40.0, settle_band=0.15).metrics
    assert list(m["settle_times"]) == ["start@0s"] and 3.0 < m["settle_times"]["start@0s"] < 10.0
    m = _run("pid", start_error=-1.0, duration=30.0).metrics
    assert list(m["settle_times"]) == ["start@0s", "brake@10s"]


def test_the_reports_one_second_period_makes_its_own_pid_oscillate():
    """Sampled every 1 s the report's loop is unstable (largest closed-loop eigenvalue
    1.066 with a zero-order hold) and grows into a limit cycle held by the actuator limits;
    every 0.1 s (the default) it converges."""
    r, peaks = _step_response(1.0)
    assert r.status == "completed" and peaks[-1] > 5.0 > 1.0  # from 1 m to a 7 m swing
    r, peaks = _step_response(0.1)
    assert peaks[0] == pytest.approx(1.0, abs=1e-3) and peaks[-1] < 1e-3


def test_config_rejects_a_gap_that_starts_inside_the_car_ahead():
    with pytest.raises(ConfigError, match="start_error"):
        PlatoonScenario.config_cls(start_error=-30.0)
