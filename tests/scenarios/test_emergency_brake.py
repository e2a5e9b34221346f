"""Emergency lane change, end to end in real SUMO traffic (headless)."""

import math

import numpy as np
import pytest

from ego.control import Observation
from ego.runner import RunSpec, build, run
from ego.scenarios import EmergencyBrake, EmergencyBrakeConfig

pytestmark = pytest.mark.sumo


def _run(controller, seed=0, **overrides):
    return run(RunSpec("emergency-brake", controller, seed, {k: str(v) for k, v in overrides.items()}))


@pytest.mark.parametrize("controller", ["fuzzy", "pid"])
def test_changes_lane_without_collision_and_settles(controller, fuzzy_ready):
    r = _run(controller)
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"]
    assert m["trigger_time"] is not None and m["trigger_ttc"] < 3.0
    assert m["target_side"] in ("left", "right") and m["target_lane"] in (0, 2)
    assert m["lane_change_completed"]
    # settled: the lateral error to the target lane centre stays within 0.2 m to the end
    t, d = r.column("t"), r.column("e_lat")
    after = t >= m["trigger_time"] + m["lane_change_duration"]
    assert np.all(np.abs(d[after]) < 0.2)
    assert m["min_gap_front"] > 0.0


def test_left_lane_blocked_goes_right(fuzzy_ready):
    r = _run("fuzzy", block_left=True, traffic_density=0)
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"]
    assert (m["target_side"], m["target_lane"]) == ("right", 0)
    assert "left: lead gap" in m["lane_choice"] and "-> rejected" in m["lane_choice"]
    assert m["lane_change_completed"]


@pytest.mark.parametrize("controller", ["fuzzy", "pid"])
def test_both_lanes_blocked_brakes_in_lane_without_hitting_the_leader(controller, fuzzy_ready):
    r = _run(controller, block_left=True, block_right=True)
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"]
    assert m["target_side"] is None and m["target_lane"] == 1
    assert m["lane_choice"].endswith("brake in lane")
    assert not m["lane_change_completed"] and m["lane_change_duration"] is None
    assert m["min_gap_front"] > 1.0
    assert m["final_speed"] == pytest.approx(5.0, abs=0.3)  # follows the lead car at its speed
    assert np.max(np.abs(r.column("d"))) < 0.2  # stayed in its lane


def test_controller_switched_off_hits_the_leader_and_says_so():
    # the AEB off too: with it, a lane change the car does not steer brakes at the friction
    # limit once only that keeps it behind the lead (issue 21), and stops in time
    r = _run("none", aeb=False)
    m = r.metrics
    assert m["status"] == "collision" and m["collision"] and m["collision_with"] == "lead"
    assert "hit" in m["status_detail"]
    assert r.events[-1].kind == "collision"
    assert m["sim_time"] < 25.0  # the run stops at the collision


def test_controller_switched_off_the_aeb_stops_it_behind_the_leader():
    # the lane change begins but nothing steers: the ego stays behind the braking lead, and the
    # AEB brakes at the friction limit once only that keeps it there
    r = _run("none")
    m = r.metrics
    assert not m["collision"] and m["aeb_time"] is not None
    assert m["min_gap_front"] > 1.0


def test_same_seed_same_metrics_and_trace(fuzzy_ready):
    a, b = _run("fuzzy", seed=3), _run("fuzzy", seed=3)
    strip = lambda m: {k: v for k, v in m.items() if k != "wall_time"}  # noqa: E731
    assert strip(a.metrics) == strip(b.metrics)
    np.testing.assert_array_equal(a.trace, b.trace)


def test_seed_changes_the_traffic(fuzzy_ready):
    choices = {_run("fuzzy", seed=s, duration=6).metrics["lane_choice"] for s in range(3)}
    assert len(choices) > 1


def test_steppable_with_an_external_policy():
    # reset/step without the scenario's own controller: hold the lane and brake gently
    from ego.control import NoController, NoParams

    sc = EmergencyBrake(EmergencyBrakeConfig(duration=2.0), NoController(NoParams(), 0.01), seed=0)
    try:
        obs = sc.reset()
        assert isinstance(obs, Observation) and obs.speed == pytest.approx(20.0)
        steps = 0
        while not sc.done:
            obs = sc.step((-300.0, 0.0))
            steps += 1
        assert steps == 200 and sc.status == "completed"
        assert obs.speed < 20.0
        with pytest.raises(RuntimeError, match="call reset"):
            sc.step((0.0, 0.0))
        obs = sc.reset(seed=1)  # runs again from scratch
        assert sc.t == 0.0 and obs.speed == pytest.approx(20.0)
    finally:
        sc.close()


class _SteerHard:
    """A broken controller: full left steer at speed."""

    def reset(self, *, seed=None):
        pass

    def step(self, obs):
        return 0.0, 0.5

    def signals(self):
        return {}


def test_diverging_controller_ends_cleanly_and_keeps_the_recording(tmp_path):
    from rerun.chunk import RrdReader

    from ego.record import RerunRecorder

    path = tmp_path / "div.rrd"
    sc = EmergencyBrake(
        EmergencyBrakeConfig(), _SteerHard(), seed=0, recorder=RerunRecorder(path), controller_name="steer-hard"
    )
    r = sc.run()
    assert r.status == "diverged"
    assert r.metrics["status_detail"].startswith(("left the road", "yaw rate", "heading"))
    assert r.events[-1].kind == "diverged" and f"t = {r.metrics['sim_time']:.2f} s" in r.events[-1].text
    assert math.isfinite(r.trace[-1, 1])
    paths = {c.entity_path for c in RrdReader(path).stream()}
    assert "/plots/lateral_error/ego" in paths and "/events" in paths


def test_bad_timing_is_rejected_before_sumo_starts():
    from ego.params import ConfigError

    with pytest.raises(ConfigError, match="whole multiple of dt"):
        build(RunSpec("emergency-brake", "pid", 0, {"sumo_step": "0.025"}))
