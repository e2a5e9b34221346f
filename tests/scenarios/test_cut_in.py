"""cut-in: a car overtakes and cuts in ahead of the ego, slower; the ego brakes in lane."""

import numpy as np
import pytest

from ego.runner import RunSpec, build, run

pytestmark = pytest.mark.sumo


@pytest.mark.parametrize("controller", ["pid", "fuzzy", "rbf-smc"])
def test_defaults_brake_in_lane_without_collision(controller, fuzzy_ready):
    r = run(RunSpec("cut-in", controller, 0))
    m = r.metrics
    assert m["status"] == "completed" and not m["collision"], m["status_detail"]
    assert m["response"] == "brake" and m["target_side"] is None
    # the sensor sees the car once its outline intrudes into the ego's lane: 0.8 s into its 2 s move
    assert 0.5 < m["reaction_time"] < 1.0
    assert 0.0 < m["min_gap"] < 15.0 and m["min_ttc"] < 3.0
    assert 0.5 < m["max_decel"] < 7.5  # it brakes, within what the tyres carry
    assert m["aeb_time"] is None  # a controlled brake, no emergency
    # the ego ends at the cutting car's speed (25 - 5 m/s), behind it
    assert m["final_speed"] == pytest.approx(20.0, abs=0.3)


def test_the_cutting_car_moves_across_smoothly_in_the_set_time(fuzzy_ready):
    scenario = build(RunSpec("cut-in", "pid", 0, {"traffic_density": "0"}))
    try:
        scenario.reset()
        ys, ts = [], []
        while not scenario.done and scenario.t < 16.0:
            scenario.step(scenario.controller.step(scenario.obs))
            if scenario.k % scenario.config.control_per_sumo == 0:
                box = scenario.view.sensor.box("cutter")
                ts.append(scenario.t)
                ys.append(box[1])
        t0 = scenario.cutter.cut_in_time
    finally:
        scenario.close()
    ts, ys = np.array(ts), np.array(ys)
    moving = (ts > t0 + 0.05) & (ts < t0 + 2.0 - 0.05)
    steps = np.abs(np.diff(ys))
    assert steps.max() < 0.35  # never more than 3.5 m/s sideways in a 0.1 s step: no jump
    assert np.all(np.diff(ys[moving]) < 0.0)  # it moves right the whole time
    done = ys[ts >= t0 + 2.1]
    assert np.all(np.abs(done - done[-1]) < 0.05)  # and stops there, in the ego's lane
    assert abs(ys[0] - done[-1]) == pytest.approx(3.5, abs=0.01)


def test_a_cut_in_closer_than_physics_allows_is_reported_as_a_collision(fuzzy_ready):
    m = run(RunSpec("cut-in", "pid", 0, {"cut_in_gap": "12", "cut_in_speed": "12", "traffic_density": "0"})).metrics
    assert m["status"] == "collision" and m["collision_with"] == "cutter"


def test_bad_side_is_one_line(tmp_path):
    import subprocess
    import sys

    p = subprocess.run(
        [sys.executable, "-m", "ego", "run", "cut-in", "-c", "pid", "--set", "ego_lane=2"],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and "cut_in_side" in p.stderr
