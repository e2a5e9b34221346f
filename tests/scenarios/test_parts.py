"""The parts a motorway scenario is composed of, each on its own: the surround view and its
observation builder, the manoeuvre's state machine, the safety layer's filter.

The view is fed by hand (``sensor.sync`` with the rows a simulator step would give), so
every transition is driven by a constructed scene with hand-checked numbers."""

from __future__ import annotations

import math

import pytest

from ego.control.base import Observation
from ego.lane_frame import LanePolyline
from ego.models import VehicleGeometry
from ego.scenarios.emergency_brake import BrakeInLane, EmergencyBrakeConfig
from ego.scenarios.events import INF
from ego.scenarios.manoeuvre import (
    CLEAR_SIDEWAYS_DISTANCE,
    CRUISE,
    DONE,
    IN_LANE,
    LANE_CHANGE,
    PHASE_NAMES,
    TRANSITIONS,
    EvasiveManoeuvre,
)
from ego.scenarios.motorway import SurroundView, ego_plant
from ego.scenarios.safety import SafetyLayer, braking_impact_speed, braking_need, braking_reach, friction_limit
from ego.scenarios.sensor import Detection

WIDTH = 3.2
G = VehicleGeometry()


def scene(config, others=()):
    """A view of three straight lanes (0 right at y = 0), the ego's CG at x = 300 in the
    middle lane at ``ego_speed``, and ``others`` (id, lane, front-bumper x, speed) seen."""
    lanes = {i: LanePolyline([(0.0, WIDTH * i), (3000.0, WIDTH * i)], WIDTH, f"motorway_{i}") for i in range(3)}
    plant = ego_plant(config, G, (300.0, WIDTH * config.ego_lane, 0.0))
    view = SurroundView(config, G)
    view.setup(None, lanes, plant)
    ids = [o[0] for o in others]
    rows = [(x - 2.25, WIDTH * lane, 0.0, v, 4.5, 1.8) for _, lane, x, v in others]
    view.sensor.sync(0.0, ids, rows)
    return view, plant


def manoeuvre(config, view, plant, events):
    in_lane = BrakeInLane(config, lambda: False)
    m = EvasiveManoeuvre(
        config,
        view,
        "front",
        in_lane,
        lambda kind, text, level="INFO": events.append(kind),
        on_trigger=lambda man: in_lane.start(man),
    )
    m.reset(plant)
    return m


def test_every_state_has_a_name_and_transitions_go_forward_only():
    assert len(PHASE_NAMES) == 4 and set(TRANSITIONS) == {CRUISE, LANE_CHANGE, IN_LANE, DONE}
    assert TRANSITIONS[DONE] == () and CRUISE not in sum(TRANSITIONS.values(), ())


def test_a_transition_not_in_the_table_is_refused():
    config = EmergencyBrakeConfig()
    view, plant = scene(config)
    m = manoeuvre(config, view, plant, [])
    with pytest.raises(RuntimeError, match="no transition from cruise to done"):
        m.enter(DONE)
    m.enter(IN_LANE)
    with pytest.raises(RuntimeError, match="in-lane manoeuvre to lane change"):
        m.enter(LANE_CHANGE)


def test_the_view_measures_gap_and_ttc_from_the_outlines():
    config = EmergencyBrakeConfig()  # ego_speed 20 m/s
    # the lead's rear 30 m ahead of the ego's front bumper, at 10 m/s: TTC 30 / 10 = 3 s
    lead_front = 300.0 + G.cg_to_front + 30.0 + 4.5
    view, _ = scene(config, [("lead", 1, lead_front, 10.0)])
    assert view.look(0.0) is None
    assert view.gap_front == pytest.approx(30.0, abs=1e-9)
    assert view.ttc_front == pytest.approx(3.0, abs=1e-9) and math.isinf(view.ttc_rear)


def test_cruise_holds_the_speed_until_the_ttc_triggers_then_gap_acceptance_picks_a_free_lane():
    config = EmergencyBrakeConfig()  # ttc_threshold 3 s
    events: list[str] = []
    lead_front = 300.0 + G.cg_to_front + 40.0 + 4.5  # TTC 40 / 10 = 4 s: no trigger
    view, plant = scene(config, [("lead", 1, lead_front, 10.0), ("right", 0, 300.0, 20.0)])
    m = manoeuvre(config, view, plant, events)
    obs = Observation()
    view.look(0.0)
    m.plan(obs, 0.0)
    assert m.phase == CRUISE and obs.ds_ref == 20.0 and events == []
    view2, plant2 = scene(config, [("lead", 1, lead_front - 15.0, 10.0), ("right", 0, 300.0, 20.0)])
    m2 = manoeuvre(config, view2, plant2, events)
    view2.look(0.0)
    m2.plan(obs, 0.0)  # TTC 2.5 s: triggered; the right lane is taken beside the ego, the left free
    assert events == ["trigger", "lane"] and m2.phase == LANE_CHANGE and m2.chosen == "left"
    assert view2.target_lane == 2 and m2.trigger_ttc == pytest.approx(2.5, abs=1e-9)
    view2.observe(obs, 0.0)
    assert obs.d == pytest.approx(-WIDTH, abs=1e-9)  # measured from the target lane's centre


def test_with_both_lanes_taken_it_brakes_in_lane_and_is_done_a_second_after_settling():
    config = EmergencyBrakeConfig()
    events: list[str] = []
    lead_front = 300.0 + G.cg_to_front + 25.0 + 4.5
    view, plant = scene(config, [("lead", 1, lead_front, 10.0), ("l", 2, 300.0, 20.0), ("r", 0, 300.0, 20.0)])
    m = manoeuvre(config, view, plant, events)
    obs = Observation()
    view.look(0.0)
    m.plan(obs, 0.0)
    assert m.phase == IN_LANE and m.chosen is None and events == ["trigger", "lane"]
    assert obs.ds_ref < 20.0  # the braking ramp
    view.ds = 10.0  # settled: no faster than the lead
    for k in range(1, 102):
        m.plan(obs, 0.01 * k)
    assert m.phase == DONE and events[-1] == "done" and m.done_t == pytest.approx(0.01)
    assert m.final_status() == ("completed", "manoeuvre complete")


def test_the_safety_layer_passes_the_action_through_until_the_aeb_engages():
    config = EmergencyBrakeConfig()
    events: list[str] = []
    # closing at 15 m/s with 6 m left: TTC 0.4 s < aeb_ttc 1 s, straight behind it
    view, plant = scene(config, [("lead", 1, 300.0 + G.cg_to_front + 6.0 + 4.5, 5.0)])
    m = manoeuvre(config, view, plant, events)
    safety = SafetyLayer(config, view, lambda kind, text, level="INFO": events.append(kind), lambda: 1.5)
    safety.manoeuvre = m
    safety.reset(plant)
    p = plant.model.params
    assert safety.filter((123.0, 0.01)) == (123.0, 0.01)
    view.look(0.0)
    assert braking_need(view.sensor.front, view.ds) == pytest.approx(15.0**2 / (2 * 6.0))
    safety.update()
    assert safety.active and safety.time == 1.5 and safety.engagements == 1 and events == ["aeb"]
    assert safety.filter((123.0, 0.01)) == (-p.F_max / p.Nw, 0.01)  # full braking, steering kept


@pytest.mark.parametrize(
    "gap, ds, front_speed, decel, expected",
    [
        # a car holding its speed: relative motion at a constant relative deceleration, the
        # relative speed left after closing the gap is sqrt(closing^2 - 2 decel gap)
        (20.0, 30.0, 10.0, 6.0, math.sqrt(20.0**2 - 2 * 6.0 * 20.0)),
        (40.0, 30.0, 10.0, 6.0, 0.0),  # 20^2 / (2 * 6) = 33.3 m < 40 m: it stops closing in time
        # a standing car: v^2 = v0^2 - 2 decel gap
        (30.0, 25.0, 0.0, 7.0, math.sqrt(25.0**2 - 2 * 7.0 * 30.0)),
        (50.0, 25.0, 0.0, 7.0, 0.0),
    ],
)
def test_braking_impact_speed_against_constant_deceleration_kinematics(gap, ds, front_speed, decel, expected):
    assert braking_impact_speed(gap, ds, front_speed, 0.0, decel) == pytest.approx(expected, rel=1e-9)


def test_braking_impact_speed_with_a_front_car_braking_to_a_stop():
    # the front car (10 m/s, 8 m/s^2) stops 6.25 m further on, at 26.25 m, 1.25 s from now, the
    # ego (25 m/s at 7 m/s^2) still 0.47 m behind it then: it hits it standing, at
    # sqrt(25^2 - 2 * 7 * 26.25)
    v = braking_impact_speed(20.0, 25.0, 10.0, -8.0, 7.0)
    assert v == pytest.approx(math.sqrt(25.0**2 - 2 * 7.0 * 26.25), rel=1e-9)
    # closing faster, it reaches the car while both still brake: relative motion at the
    # relative deceleration 8 - 7 = 1 m/s^2, the gap 30 - 12 tau - tau^2 / 2 closing at
    # tau = sqrt(12^2 + 2 * 30) - 12, the relative speed then 12 + tau
    tau = math.sqrt(12.0**2 + 2 * 30.0) - 12.0
    assert braking_impact_speed(30.0, 32.0, 20.0, -8.0, 7.0) == pytest.approx(12.0 + tau, rel=1e-9)
    # braking_need agrees: a stop behind needs more than 7 m/s^2 from 20 m, less from 40 m,
    # where the impact speed is 0
    assert braking_need(Detection("lead", 20.0, 10.0, -8.0), 25.0) > 7.0
    assert braking_need(Detection("lead", 40.0, 10.0, -8.0), 25.0) < 7.0
    assert braking_impact_speed(40.0, 25.0, 10.0, -8.0, 7.0) == 0.0
    assert braking_impact_speed(INF, 32.0, 20.0, -8.0, 7.0) == 0.0  # nothing ahead


def _braking_lead_scene(lead_decel, ego=28.0, lead_v=18.0, gap=22.0, follower=True):
    """ego ``ego`` m/s; the lead ``gap`` m ahead at ``lead_v`` m/s, braking at ``lead_decel``
    over the last 0.1 s; a follower in the left lane 22.6 m behind at 24 m/s (or that lane
    empty); the right lane taken."""
    config = EmergencyBrakeConfig(ego_speed=ego)
    lead = 300.0 + G.cg_to_front + gap + 4.5
    fol = 300.0 - 2.25 - 25.0
    others = [("lead", 1, lead, lead_v), ("r", 0, 300.0, ego)] + ([("fol", 2, fol, 24.0)] if follower else [])
    view, plant = scene(config, others)
    dt = 0.1
    moved = [
        ("lead", 1, lead + lead_v * dt - 0.5 * lead_decel * dt * dt, lead_v - lead_decel * dt),
        ("r", 0, 300.0 + ego * dt, ego),
    ] + ([("fol", 2, fol + 24.0 * dt, 24.0)] if follower else [])
    view.sensor.sync(dt, [o[0] for o in moved], [(x - 2.25, WIDTH * lane, 0.0, v, 4.5, 1.8) for _, lane, x, v in moved])
    events: list[str] = []
    m = manoeuvre(config, view, plant, events)
    view.look(dt)
    m.plan(Observation(), dt)
    return m, view


def test_the_follower_check_weighs_the_impact_in_lane_against_the_followers():
    # the follower would come within 2 m closing at 13.4 m/s (the ego braking at the limit
    # behind the lead for CLEAR_SIDEWAYS_TIME): against a lead braking at 8 m/s^2 braking in lane
    # is the lesser risk (the ego would hit it slower, if at all) ...
    m, view = _braking_lead_scene(8.0)
    limit = friction_limit(m.plant.model.params)
    front = view.sensor.front
    assert front.accel == pytest.approx(-8.0, abs=1e-6)
    in_lane = braking_impact_speed(front.gap, view.ds, front.speed, front.accel, limit)
    assert m.chosen is None and "fol" in m.choice_reason and m.choice_reason.endswith("brake in lane")
    assert in_lane <= m.follower_contact == pytest.approx(13.4, abs=0.05)
    # ... against one braking at 9 m/s^2 the ego would hit it at 14.7 m/s: the lane change is
    m, view = _braking_lead_scene(9.0)
    front = view.sensor.front
    assert braking_impact_speed(front.gap, view.ds, front.speed, front.accel, limit) == pytest.approx(14.7, abs=0.05)
    assert m.chosen == "left" and m.phase == LANE_CHANGE
    assert "braking in lane would hit the front car at 14.7 m/s" in m.choice_reason and m.choice_reason.endswith(
        "change lane"
    )


def test_braking_reach_is_where_the_front_car_is_at_contact_or_the_stopping_distance():
    # the contact of the test above at tau = sqrt(12^2 + 2 * 30) - 12: the ego has travelled as
    # far as the front car (30 m ahead, 20 m/s braking at 8 m/s^2) has, plus the gap
    tau = math.sqrt(12.0**2 + 2 * 30.0) - 12.0
    assert braking_reach(30.0, 32.0, 20.0, -8.0, 7.0) == pytest.approx(30.0 + 20.0 * tau - 4.0 * tau * tau, rel=1e-9)
    # no contact: the stopping distance v^2 / (2 a)
    assert braking_reach(40.0, 25.0, 10.0, -8.0, 7.0) == pytest.approx(25.0**2 / 14.0, rel=1e-12)
    assert braking_reach(INF, 25.0, 10.0, 0.0, 7.0) == pytest.approx(25.0**2 / 14.0, rel=1e-12)


def test_no_lane_change_is_begun_that_cannot_clear_the_front_car_before_reaching_it():
    # ego 20 m/s, the lead 10 m ahead at 16 m/s braking at 9 m/s^2, the left lane free: braking at
    # the friction limit it would reach the lead after ~24 m, short of the 32 m a lane change
    # needs to clear it sideways; the left lane is accepted by gap acceptance, then refused
    m, view = _braking_lead_scene(9.0, ego=20.0, lead_v=16.0, gap=10.0, follower=False)
    front = view.sensor.front
    limit = friction_limit(m.plant.model.params)
    assert braking_need(front, view.ds) > limit
    reach = braking_reach(front.gap, view.ds, front.speed, front.accel, limit)
    assert reach < CLEAR_SIDEWAYS_DISTANCE
    assert m.chosen is None and m.phase == IN_LANE
    assert "left: lead gap free" in m.choice_reason and "accepted" in m.choice_reason
    assert m.choice_reason.endswith(
        f"reaches the front car within {reach:.1f} m, before a lane change clears it sideways (32 m): brake in lane"
    )
    # at 28 m/s, the lead 22 m ahead at 18 m/s braking at 9 m/s^2: the limit is not enough either,
    # but the ego travels ~40 m before it would reach the lead: the lane change is begun
    m, view = _braking_lead_scene(9.0, follower=False)
    front = view.sensor.front
    assert braking_need(front, view.ds) > limit
    assert braking_reach(front.gap, view.ds, front.speed, front.accel, limit) > CLEAR_SIDEWAYS_DISTANCE
    assert m.chosen == "left" and m.phase == LANE_CHANGE
