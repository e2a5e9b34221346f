"""The surround sensor: gaps from the vehicles' outlines, never more than the clearance."""

import math

import numpy as np
import pytest

from ego.lane_frame import LanePolyline
from ego.runner import RunSpec, build
from ego.scenarios.sensor import Detection, SurroundSensor

LANE = LanePolyline([(0.0, 0.0), (1000.0, 0.0)], 3.5)
BANDS = {0: (-5.25, -1.75), 1: (-1.75, 1.75), 2: (1.75, 5.25)}


def _sensor():
    return SurroundSensor(LANE, BANDS, cg_to_front=2.25, length=4.5, width=1.8)


def corners(x, y, psi, length, width, cg_to_front=None):
    """Corners of a box whose reference point (centre, or CG when cg_to_front is given) is at
    (x, y)."""
    front = 0.5 * length if cg_to_front is None else cg_to_front
    rear = front - length
    c, s = math.cos(psi), math.sin(psi)
    return [
        (x + c * lx - s * ly, y + s * lx + c * ly)
        for lx, ly in ((front, 0.5 * width), (front, -0.5 * width), (rear, -0.5 * width), (rear, 0.5 * width))
    ]


def _seg_dist(p, a, b):
    (px, py), (ax, ay), (bx, by) = p, a, b
    dx, dy = bx - ax, by - ay
    t = min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


def outline_distance(a, b):
    """Distance between two disjoint convex quadrilaterals (corner lists)."""
    return min(min(_seg_dist(p, q[i], q[(i + 1) % 4]) for p in r for i in range(4)) for r, q in ((a, b), (b, a)))


def test_the_car_the_ego_is_leaving_stays_the_front_object():
    # the ego is half into the left lane, turned 0.1 rad left; the lead, in the ego's old
    # lane, still overlaps its right side by ~0.5 m: SUMO's lane leader would be the left
    # lane's car, the sensor's front object is the lead
    sensor = _sensor()
    ids = ["lead", "left_car"]
    rows = [
        (30.0, 0.0, 0.0, 10.0, 4.5, 1.8),  # centre x, y, yaw, speed, length, width
        (60.0, 3.5, 0.0, 20.0, 4.5, 1.8),
    ]
    sensor.sync(0.0, ids, rows)
    sensor.scan(0.0, s=10.0, d=1.75, heading_error=0.1)
    assert sensor.front.id == "lead"
    ego = corners(10.0, 1.75, 0.1, 4.5, 1.8, cg_to_front=2.25)
    lead = corners(30.0, 0.0, 0.0, 4.5, 1.8)
    true_gap = min(p[0] for p in lead) - max(p[0] for p in ego)
    assert sensor.front.gap == pytest.approx(true_gap, abs=1e-9)
    assert sensor.front.gap <= outline_distance(ego, lead)
    assert sensor.front.speed == pytest.approx(10.0)
    # it reaches 0.27 m into the ego's extent across the lane, from the right
    assert sensor.front.overlap == pytest.approx(0.9 - min(p[1] for p in ego), abs=1e-9)
    assert 0.2 < sensor.front.overlap < 0.3 and sensor.front.side == -1.0
    # the left lane's leader is the other car, for gap acceptance
    lead_left, lag_left = Detection(), Detection()
    assert sensor.lane_neighbours(2, lead_left, lag_left)
    assert lead_left.id == "left_car" and lag_left.gap == math.inf
    assert not sensor.lane_neighbours(3, lead_left, lag_left)


def test_once_the_ego_has_cleared_it_the_lead_is_no_longer_ahead_of_it():
    sensor = _sensor()
    sensor.sync(0.0, ["lead"], [(30.0, 0.0, 0.0, 10.0, 4.5, 1.8)])
    sensor.scan(0.0, s=10.0, d=3.0, heading_error=0.0)  # the ego's right edge at 2.1 m
    assert sensor.front.id == "" and sensor.front.gap == math.inf


def test_between_sumo_steps_objects_move_at_their_velocity():
    sensor = _sensor()
    # a car cutting in from the left: 2 m/s across, 15 m/s along, heading turned accordingly
    yaw = math.atan2(-2.0, 15.0)
    v = math.hypot(2.0, 15.0)
    # turned, the box reaches 1.19 m across either side of its centre: 0.06 m short of the
    # ego's lane (its left edge at 1.75 m)
    sensor.sync(0.0, ["cut"], [(25.0, 3.0, yaw, v, 4.5, 1.8)])
    sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.id == ""  # not yet over the ego's lane
    sensor.scan(0.08, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.id == "cut"
    assert sensor.front.speed == pytest.approx(15.0)
    assert sensor.front.lateral_speed == pytest.approx(-2.0)


def _half_across(yaw: float, length: float = 4.5, width: float = 1.8) -> float:
    """How far a box turned by ``yaw`` from the lane reaches across it from its centre (m)."""
    return 0.5 * (length * abs(math.sin(yaw)) + width * math.cos(yaw))


def test_a_car_intruding_into_the_ego_s_lane_is_a_target_before_it_is_beside_the_ego():
    # R157 5.2.5.2 measures a cut-in's TTC from its intrusion into the ego's lane: from then
    # on it is the front object, while it is still 0.8 m clear of the ego's own extent
    # (which ends 0.9 m left of the lane centre)
    yaw = math.atan2(-0.5, 8.0)
    v = math.hypot(0.5, 8.0)
    half = _half_across(yaw)
    sensor = _sensor()
    for edge, seen in ((1.75 + 0.01, False), (1.75 - 0.01, True)):
        sensor.sync(0.0, ["cut"], [(12.0, edge + half, yaw, v, 4.5, 1.8)])
        sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
        assert (sensor.front.id == "cut") is seen
    assert sensor.front.gap == pytest.approx(12.0 - 0.5 * _along(yaw) - 2.25, abs=1e-9)
    # its overlap is still with the ego's own extent, which it has not reached: the ego
    # clears it sideways unless one of them moves across
    assert sensor.front.overlap == pytest.approx(0.9 - (1.74), abs=1e-9)
    assert sensor.front.side == 1.0
    # behind the ego the same: a car intruding into its lane from behind is the rear object
    sensor.sync(0.0, ["cut"], [(-12.0, 1.74 + half, yaw, v, 4.5, 1.8)])
    sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.id == "" and sensor.rear.id == "cut"


def test_a_lead_leaving_the_lane_stops_hiding_the_car_ahead_of_it_once_clear_of_the_ego():
    # a cut-out: the lead moves left at 1 m/s; a standing car 40 m ahead. While the lead's
    # outline still reaches into the ego's lane, but no longer over the ego's own extent, the
    # standing car is the front object (the lead, moving out, cannot be hit keeping the line)
    yaw = math.atan2(1.0, 16.0)
    v = math.hypot(1.0, 16.0)
    half = _half_across(yaw)
    sensor = _sensor()
    for edge, front in ((0.9 - 0.01, "lead"), (0.9 + 0.01, "target")):  # its right edge
        rows = [(15.0, edge + half, yaw, v, 4.5, 1.8), (40.0, 0.0, 0.0, 0.0, 4.5, 1.8)]
        sensor.sync(0.0, ["lead", "target"], rows)
        sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
        assert sensor.front.id == front
    # the same car coming in (moving right) at the same place is a target: a cut-in
    rows = [(15.0, 0.9 + 0.01 + half, -yaw, v, 4.5, 1.8), (40.0, 0.0, 0.0, 0.0, 4.5, 1.8)]
    sensor.sync(0.0, ["lead", "target"], rows)
    sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.id == "lead"


def _along(yaw: float, length: float = 4.5, width: float = 1.8) -> float:
    """A box turned by ``yaw`` from the lane: its extent along the lane (m)."""
    return length * math.cos(yaw) + width * abs(math.sin(yaw))


def test_a_neighbour_wandering_within_its_own_lane_is_not_a_target():
    # R157's lateral wandering distance (0.375 m) towards the ego leaves a car 0.475 m clear
    # of the ego's lane: not in its path
    sensor = _sensor()
    sensor.sync(0.0, ["left"], [(12.0, 3.5 - 0.375, 0.0, 8.0, 4.5, 1.8)])
    sensor.scan(0.0, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.id == "" and sensor.rear.id == ""
    # the ego changing lanes: its lane is the one the middle of its front bumper is over, so
    # a car in the left lane (here 0.375 m beyond its centre, clear of the ego's outline) is
    # ahead of it once its nose has crossed the marking, not before
    sensor.sync(0.0, ["left"], [(12.0, 3.5 + 0.375, 0.0, 8.0, 4.5, 1.8)])
    for d, seen in ((1.4, False), (1.6, True)):  # the nose at d + 2.25 sin(0.1) = d + 0.22 m
        sensor.scan(0.0, s=0.0, d=d, heading_error=0.1)
        assert sensor.ego_extents(0.0, d, 0.1)[3] < 3.875 - 0.9
        assert (sensor.front.id == "left") is seen


def test_accelerations_are_measured_between_sumo_steps():
    sensor = _sensor()
    sensor.sync(0.0, ["lead"], [(30.0, 0.0, 0.0, 20.0, 4.5, 1.8)])
    sensor.sync(0.1, ["lead"], [(32.0, 0.0, 0.0, 19.4, 4.5, 1.8)])
    sensor.scan(0.1, s=0.0, d=0.0, heading_error=0.0)
    assert sensor.front.accel == pytest.approx(-6.0)


def test_a_gap_never_exceeds_the_distance_between_the_outlines():
    rng = np.random.default_rng(0)
    sensor = _sensor()
    checked = 0
    for _ in range(2000):
        ego_d, ego_psi = rng.uniform(-2.0, 2.0), rng.uniform(-0.3, 0.3)
        x, y, yaw = rng.uniform(3.0, 25.0), rng.uniform(-3.0, 3.0), rng.uniform(-0.3, 0.3)
        sensor.sync(0.0, ["o"], [(x, y, yaw, 10.0, 4.5, 1.8)])
        sensor.scan(0.0, s=0.0, d=ego_d, heading_error=ego_psi)
        det = sensor.front if sensor.front.id else sensor.rear
        if not det.id or det.gap <= 0.0:
            continue
        ego = corners(0.0, ego_d, ego_psi, 4.5, 1.8, cg_to_front=2.25)
        other = corners(x, y, yaw, 4.5, 1.8)
        assert det.gap <= outline_distance(ego, other) + 1e-9
        checked += 1
    assert checked > 300


@pytest.mark.sumo
def test_in_sumo_the_sensor_sees_the_overlapping_lead_that_sumo_s_leader_misses(fuzzy_ready):
    """A constructed overlap in real SUMO: the ego placed half into the left lane, turned
    left, the braking lead still overlapping its right side."""
    scenario = build(
        RunSpec("emergency-brake", "none", 0, {"traffic_density": "0", "lead_gap": "12", "lead_brake_time": "0"})
    )
    try:
        scenario.reset()
        x = list(scenario.ego.state)
        psi = 0.1
        x[2] += 1.6  # CG 1.6 m left of the lane centre, front bumper over the lane line
        x[4] = psi
        scenario.ego.state = tuple(x)
        scenario.view.frame()
        for _ in range(scenario.config.control_per_sumo):
            scenario.step((0.0, 0.0))
        assert scenario.status == "running"
        bridge = scenario.bridge
        lane_leader = bridge.libsumo.vehicle.getLeader("ego", 100.0)
        assert bridge.libsumo.vehicle.getLaneIndex("ego") == 2  # SUMO has it in the left lane
        assert not lane_leader or lane_leader[0] != "lead"  # ... so its leader is not the lead
        view = scenario.view
        assert view.sensor.front.id == "lead"
        assert view.gap_front < 12.0 and math.isfinite(view.ttc_front)
        box = view.sensor.box("lead")
        g = scenario.geometry
        s = scenario.ego.state
        ego = corners(s[0], s[2], s[4], g.length, g.width, cg_to_front=g.cg_to_front)
        assert view.gap_front <= outline_distance(ego, corners(*box)) + 1e-9
    finally:
        scenario.close()
