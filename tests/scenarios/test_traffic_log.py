"""The traffic log: every vehicle within 50 m of the ego at every SUMO step, as SUMO has it."""

import math
import pickle

import numpy as np
import pytest

from ego.results import traffic_log as tl
from ego.results.traffic_log import RADIUS, UNITS, TrafficCollector, TrafficLog
from ego.runner import RunSpec, build


def _rows(n, x0=0.0):
    return [(x0 + 10.0 * i, 0.0, 0.1 * i, 20.0 + i, 4.5, 1.8) for i in range(n)]


def test_the_collector_keeps_what_is_within_the_radius_in_first_seen_order(monkeypatch):
    monkeypatch.setattr(tl, "BATCH", 3)  # several batches and a remainder
    c = TrafficCollector()
    for k in range(7):
        ids = [f"v{i}" for i in range(8)][:: -1 if k % 2 else 1]
        rows = _rows(8)[:: -1 if k % 2 else 1]
        c.add(0.1 * k, [(k * 1.0, 0.0)], ids, rows)
    log = c.log()
    assert set(UNITS) == {"t", "vehicle", "x", "y", "heading", "speed", "length", "width"}
    assert log.t.dtype == np.float64 and log.vehicle.dtype == np.int32
    assert log.ids == tuple(f"v{i}" for i in range(6))  # v0..v5 first seen at step 0; v6, v7 never near
    for k in range(7):
        mine = log.t == 0.1 * k
        d = np.hypot(log.x[mine] - k, log.y[mine])
        assert (d <= RADIUS).all()
        assert mine.sum() == sum(1 for i in range(8) if abs(10.0 * i - k) <= RADIUS)
    v3 = log.of("v3")
    assert np.allclose(log.x[v3], 30.0) and np.allclose(log.heading[v3], 0.3)
    assert np.allclose(log.speed[v3], 23.0) and np.allclose(log.length[v3], 4.5)


def test_the_collector_measures_from_the_nearest_of_several_egos():
    c = TrafficCollector()
    c.add(
        0.0,
        [(0.0, 0.0), (100.0, 0.0)],
        ["a", "b", "c"],
        [(40, 0, 0, 1, 4, 2), (50, 60, 0, 1, 4, 2), (140, 0, 0, 1, 4, 2)],
    )
    assert c.log().ids == ("a", "c")
    assert len(TrafficCollector().log()) == 0


def _sumo_truth(scenario, radius=RADIUS):
    """Every vehicle within ``radius`` of the ego's box centre, from SUMO's own getters."""
    bridge = scenario.bridge
    ids, boxes = bridge.boxes()
    out = {}
    ego = dict(zip(ids, boxes))[scenario.agent_id]
    for vid, (x, y, yaw, length, width) in zip(ids, boxes):
        if vid in bridge.controlled:
            continue
        out[vid] = (math.hypot(x - ego[0], y - ego[1]), (x, y, yaw, bridge.speed(vid), length, width))
    return out


@pytest.mark.sumo
def test_the_log_holds_every_vehicle_within_50_m_and_none_beyond_as_sumo_has_it():
    scenario = build(RunSpec("emergency-brake", "fuzzy", 0, {"duration": 4.0, "traffic_density": 16.0}))
    truth = {}
    try:
        obs = scenario.reset()
        truth[0.0] = _sumo_truth(scenario)
        per = scenario.config.control_per_sumo
        while not scenario.done:
            obs = scenario.step(scenario.controller.step(obs))
            if scenario.k % per == 0:
                truth[round(scenario.t, 6)] = _sumo_truth(scenario)
        log = scenario.result().traffic
    finally:
        scenario.close()
    assert isinstance(log, TrafficLog) and "lead" in log.ids
    near = beyond = 0
    for t, seen in truth.items():
        rows = np.flatnonzero(np.isclose(log.t, t))
        logged = {log.ids[log.vehicle[j]]: j for j in rows}
        for vid, (dist, (x, y, yaw, speed, length, width)) in seen.items():
            if dist <= RADIUS - 1e-6:
                near += 1
                j = logged.pop(vid)
                assert (log.x[j], log.y[j], log.speed[j], log.length[j], log.width[j]) == pytest.approx(
                    (x, y, speed, length, width), abs=1e-6
                )
                assert math.remainder(log.heading[j] - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
            elif dist > RADIUS + 1e-6:
                beyond += 1
                assert vid not in logged
        assert not logged  # nothing else was logged
    assert near > 40 and beyond > 40  # both sides of the radius were exercised


@pytest.mark.sumo
def test_the_platoon_logs_the_leader_and_the_followers_as_sumo_has_them(monkeypatch):
    monkeypatch.setattr(tl, "BATCH", 4)  # filtered in batches, from two egos each step
    scenario = build(RunSpec("platoon", "pid", 0, {"duration": 2.0, "followers": 2}))
    try:
        obs = scenario.reset()
        while not scenario.done:
            obs = scenario.step(scenario.controller.step(obs))
        ids, boxes = scenario.bridge.boxes()
        log = scenario.result().traffic
    finally:
        scenario.close()
    assert log.ids == ("leader", "f1", "f2")
    assert len(log) == 3 * 21  # t = 0 and 20 SUMO steps
    last = np.flatnonzero(log.t == log.t[-1])
    for vid, (x, y, yaw, length, _width) in zip(ids, boxes):
        j = last[log.ids.index(vid)]
        assert (log.x[j], log.y[j], log.heading[j], log.length[j]) == pytest.approx((x, y, yaw, length), abs=1e-6)
    back = pickle.loads(pickle.dumps(log))  # it travels from compare's workers
    assert back.ids == log.ids and np.array_equal(back.x, log.x)


def test_a_scenario_without_sumo_has_no_traffic_log(point_mass):
    from ego.runner import run

    assert run(RunSpec("point-mass", "pid", 0, {"duration": 0.5})).traffic is None
