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
from ego.scenarios.manoeuvre import CRUISE, DONE, IN_LANE, LANE_CHANGE, PHASE_NAMES, TRANSITIONS, EvasiveManoeuvre
from ego.scenarios.motorway import SurroundView, ego_plant
from ego.scenarios.safety import SafetyLayer, braking_need

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
