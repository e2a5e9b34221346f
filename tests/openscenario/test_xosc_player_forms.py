"""Forms the reference player's (esmini's) example files use: a vehicle catalog entry with a
trailer hitch and an empty trailer reference, GlobalAction EnvironmentActions, a step written
without value or dimension, a Condition without conditionEdge, a condition name that is not a
valid expression; and the refusals beside them (an attached trailer, a friction scale, an entity
turned against its lane). Each file here is hand-written for the test."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest
from xosc_scenes import event, lane_change, run_scene, scene, sim_time, speed, starts, trigger

from ego.openscenario import model as M
from ego.openscenario.dynamics import Transition, speed_duration
from ego.openscenario.loader import load
from ego.openscenario.xmltree import ScenarioFileError

PERF = '<Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/>'


def _edit(path, old: str, new: str, count: int = 1) -> None:
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, count))


def _line_of(path, needle: str) -> int:
    return next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if needle in ln)


def test_a_trailer_that_attaches_nothing_is_accepted(tmp_path):
    path = scene(tmp_path, [])
    hitch = (
        '<TrailerHitch dx="-1.2"/><Trailer><EntityRef entityRef=""/>'
        '<CatalogReference catalogName="VehicleCatalog" entryName=""/></Trailer>'
    )
    _edit(path, PERF, PERF + '<TrailerCoupler dx="3.0"/>' + hitch, count=-1)
    sc = load(path)
    assert sc.entities["A"].vehicle.length == 4.5


def test_an_attached_trailer_is_refused_in_one_line(tmp_path):
    path = scene(tmp_path, [])
    text = path.read_text().replace(PERF, PERF + '\n<Trailer><EntityRef entityRef="B"/></Trailer>', 1)
    path.write_text(text)
    with pytest.raises(ScenarioFileError, match=r"a trailer \(entityRef 'B'\) is not supported by ego") as exc:
        load(path)
    assert exc.value.line == _line_of(path, '<Trailer><EntityRef entityRef="B"/>')
    proc = subprocess.run(
        [sys.executable, "-m", "ego", "run", str(path), "-c", "pid", "--trace", str(tmp_path / "o.csv")],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "scene.xosc:" in proc.stderr
    assert not (tmp_path / "o.csv").exists()


ENV = (
    '<GlobalAction><EnvironmentAction><Environment name="e"><TimeOfDay animation="false" '
    'dateTime="2025-06-13T12:00:00"/><Weather cloudState="free"><Sun intensity="1000" azimuth="0" '
    'elevation="1.3"/><Fog visualRange="200"/><Precipitation precipitationType="dry" intensity="0"/>'
    "</Weather>{road}</Environment></EnvironmentAction></GlobalAction>"
)


def test_environment_actions_are_accepted_in_init_and_in_events(tmp_path):
    path = scene(tmp_path, [event("Brake", "A", speed(10, "linear", "rate", 4.0), trigger([sim_time(1)]))])
    _edit(path, "<Init><Actions>", "<Init><Actions>" + ENV.format(road='<RoadCondition frictionScaleFactor="1"/>'))
    # an event whose action is a GlobalAction: done at once
    _edit(
        path,
        '<Action name="BrakeAction">',
        '<Action name="Weather">' + ENV.format(road="") + '</Action><Action name="BrakeAction">',
    )
    sc = load(path)
    acts = [e for st in sc.stories for act in st.acts for g in act.groups for m in g.maneuvers for e in m.events]
    kinds = [type(a.action).__name__ for a in acts[0].actions]
    assert kinds == ["EnvironmentAction", "SpeedAction"]


def test_a_friction_scale_is_read_and_a_zero_one_refused_with_its_line(tmp_path):
    """A RoadCondition's friction scale is applied (test_xosc_environment.py); 0 is refused."""
    path = scene(tmp_path, [])
    _edit(path, "<Init><Actions>", "<Init><Actions>\n" + ENV.format(road='<RoadCondition frictionScaleFactor="0.5"/>'))
    assert load(path).init_globals[0].friction == 0.5
    _edit(path, 'frictionScaleFactor="0.5"', 'frictionScaleFactor="0"')
    with pytest.raises(ScenarioFileError, match=r"bad value for frictionScaleFactor in <RoadCondition>: 0") as exc:
        load(path)
    assert exc.value.line == _line_of(path, "<RoadCondition")


def test_a_step_without_value_or_dimension_and_a_condition_without_edge(tmp_path):
    path = scene(tmp_path, [event("Jump", "A", speed(20), trigger([sim_time(1)]))])
    _edit(
        path,
        'dynamicsShape="step" value="0.0" dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="20"',
        'dynamicsShape="step"/><SpeedActionTarget><AbsoluteTargetSpeed value="20"',
    )
    _edit(
        path,
        '<Condition name="c" delay="0.0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1"',
        '<Condition name="${Brake + _ + 1}" delay="0.0"><ByValueCondition><SimulationTimeCondition value="1"',
    )
    sc = load(path)
    ev = sc.stories[0].acts[0].groups[0].maneuvers[0].events[0]
    assert ev.actions[0].action.dynamics == M.Dynamics("step", "time", 0.0)  # type: ignore[union-attr]
    cond = ev.start.groups[0][0]  # type: ignore[union-attr]
    assert cond.edge == "none" and cond.name == "${Brake + _ + 1}"


def test_a_step_of_another_shape_still_needs_its_value(tmp_path):
    path = scene(tmp_path, [event("Slow", "A", speed(20, "linear", "time", 2.0), trigger([sim_time(1)]))])
    _edit(path, 'dynamicsShape="linear" value="2.0"', 'dynamicsShape="linear"')
    with pytest.raises(ScenarioFileError, match=r"<SpeedActionDynamics> needs attribute value"):
        load(path)


def test_an_entity_turned_against_its_lane_is_an_init_lane_start_only(tmp_path):
    """Turned round on its lane in Init: a car ego drives itself (test_xosc_against_lane.py);
    turned in any other position form it is refused with the Orientation's line."""
    path = scene(tmp_path, [])
    _edit(
        path,
        'laneId="-1" s="100.0" offset="0"/>',
        'laneId="-1" s="100.0" offset="0"><Orientation type="relative" h="3.141593"/></LanePosition>',
    )
    tp = load(path).init["A"][0]
    assert tp.position.turned == _line_of(path, 'h="3.141593"')  # type: ignore[union-attr]
    path = scene(tmp_path, [])
    _edit(
        path,
        '<LanePosition roadId="0" laneId="-1" s="100.0" offset="0"/>',
        '<RelativeLanePosition entityRef="C" dLane="2" ds="-300"><Orientation type="relative" h="3.141593"/>'
        "</RelativeLanePosition>",
    )
    with pytest.raises(ScenarioFileError, match=r"<Orientation> turning the entity against its lane's direction") as e:
        load(path)
    assert e.value.line == _line_of(path, 'h="3.141593"')
    # a small relative heading is accepted (the lane's heading is used)
    path = scene(tmp_path, [])
    _edit(
        path,
        'laneId="-1" s="100.0" offset="0"/>',
        'laneId="-1" s="100.0" offset="0"><Orientation type="relative" h="0.1"/></LanePosition>',
    )
    load(path)


@pytest.mark.sumo
def test_braking_at_a_rate_during_a_lane_change_follows_the_closed_form(tmp_path):
    """C changes to lane -2 over 3 s from t = 1 s and brakes from 15 to 7 m/s at -4 m/s^2 from
    t = 2 s (the reference player's cut-in: a brake while the car is moved sideways). Its speed
    is the linear profile within 1e-6 at every step (it was a stop in one step: SUMO takes a set
    speed at once while a script moves the car sideways)."""
    evs = [
        event("Change", "C", lane_change(-2, "sinusoidal", "time", 3.0), trigger([sim_time(0.95)])),
        event("Brake", "C", speed(7, "linear", "rate", -4.0), trigger([sim_time(1.95)])),
    ]
    sc = run_scene(scene(tmp_path, evs), 6.0)
    brake = Transition(2.0, 15.0, 7.0, speed_duration("linear", "rate", 4.0, 15.0, 7.0), "linear")
    hist = sc._history["C"]
    assert hist and max(t for t, _, _ in hist) > 4.5
    for t, v, _ in hist:
        assert v == pytest.approx(brake.value(t), abs=1e-6), t


def _cond(body: str) -> str:
    return (
        '<Condition name="k" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities '
        'triggeringEntitiesRule="any"><EntityRef entityRef="C"/></TriggeringEntities><EntityCondition>'
        f"{body}</EntityCondition></ByEntityCondition></Condition>"
    )


@pytest.mark.sumo
def test_stand_still_and_acceleration_conditions(tmp_path):
    """C brakes from 15 m/s at 5 m/s^2 from storyboard time 1 s: it stands at 4.0 s, so a
    StandStillCondition of 1 s holds from 5.0 s; its longitudinal acceleration is -5 m/s^2 from
    the step after the brake starts (1.1 s) until it stands, the magnitude 5 the same."""
    evs = [
        event("Brake", "C", speed(0, "linear", "rate", 5.0), trigger([sim_time(0.95)])),
        event("Still", "A", speed(25), trigger([_cond('<StandStillCondition duration="1"/>')])),
        event(
            "Lon",
            "B",
            speed(15),
            trigger([_cond('<AccelerationCondition value="-4.9" rule="lessThan" direction="longitudinal"/>')]),
        ),
        event("Total", "A", speed(25), trigger([_cond('<AccelerationCondition value="4.9" rule="greaterThan"/>')])),
    ]
    sc = run_scene(scene(tmp_path, evs), 6.0)
    assert starts(sc, "Still") == [pytest.approx(5.0)]
    assert starts(sc, "Lon") == [pytest.approx(1.1)]
    assert starts(sc, "Total") == [pytest.approx(1.1)]


def test_a_vertical_acceleration_condition_is_refused(tmp_path):
    evs = [
        event(
            "V",
            "A",
            speed(25),
            trigger([_cond('<AccelerationCondition value="1" rule="greaterThan" direction="vertical"/>')]),
        )
    ]
    with pytest.raises(ScenarioFileError, match=r"a vertical <AccelerationCondition> is not supported"):
        load(scene(tmp_path, evs))


def _global_event(name: str, actor: str, action: str, start: str) -> tuple[str, str]:
    return actor, (
        f'<Event name="{name}" priority="parallel" maximumExecutionCount="1"><Action name="{name}Action">'
        f"<GlobalAction>{action}</GlobalAction></Action>{start}</Event>"
    )


def _param_cond(ref: str, value: str, kind: str = "Parameter") -> str:
    attr = "parameterRef" if kind == "Parameter" else "variableRef"
    return (
        f'<Condition name="p" delay="0" conditionEdge="none"><ByValueCondition><{kind}Condition {attr}="{ref}" '
        f'value="{value}" rule="equalTo"/></ByValueCondition></Condition>'
    )


@pytest.mark.sumo
def test_parameter_and_variable_actions_change_what_conditions_see(tmp_path):
    """Count = 0 gets + 2 at 1.0 s and x 3 at 2.0 s: a ParameterCondition Count == 6 holds from the
    next storyboard step (2.1 s); a VariableSetAction at 1.0 s makes Phase == 'b' hold at 1.1 s;
    each global action is done once although its maneuver group has an actor."""
    params = '<ParameterDeclaration name="Count" parameterType="double" value="0"/>'
    evs = [
        _global_event(
            "Add",
            "A",
            '<ParameterAction parameterRef="Count"><ModifyAction><Rule><AddValue value="2"/></Rule>'
            "</ModifyAction></ParameterAction>",
            trigger([sim_time(0.95)]),
        ),
        _global_event(
            "Times",
            "A",
            '<ParameterAction parameterRef="Count"><ModifyAction><Rule><MultiplyByValue value="3"/>'
            "</Rule></ModifyAction></ParameterAction>",
            trigger([sim_time(1.95)]),
        ),
        _global_event(
            "Phase",
            "B",
            '<VariableAction variableRef="Phase"><SetAction value="b"/></VariableAction>',
            trigger([sim_time(0.95)]),
        ),
        event("Six", "C", speed(20), trigger([_param_cond("Count", "6")])),
        event("B", "C", speed(18), trigger([_param_cond("Phase", "b", "Variable")])),
    ]
    path = scene(tmp_path, evs, params=params)
    _edit(
        path,
        "</ParameterDeclarations>",
        "</ParameterDeclarations><VariableDeclarations><VariableDeclaration "
        'name="Phase" variableType="string" value="a"/></VariableDeclarations>',
    )
    sc = run_scene(path, 3.0)
    assert starts(sc, "Six") == [pytest.approx(2.1)]
    assert starts(sc, "B") == [pytest.approx(1.1)]


@pytest.mark.parametrize(
    ("action", "message"),
    [
        (
            '<ParameterAction parameterRef="Nope"><SetAction value="1"/></ParameterAction>',
            r"parameter 'Nope' is not declared",
        ),
        (
            '<ParameterAction parameterRef="Name"><ModifyAction><Rule><AddValue value="1"/></Rule></ModifyAction>'
            "</ParameterAction>",
            r"<AddValue> needs a numeric parameter \('Name' is 'x'\)",
        ),
        ('<VariableAction variableRef="V"><SetAction value="1"/></VariableAction>', r"variable 'V' is not declared"),
    ],
)
def test_bad_parameter_actions_are_refused_in_one_line(tmp_path, action, message):
    params = '<ParameterDeclaration name="Name" parameterType="string" value="x"/>'
    path = scene(tmp_path, [_global_event("G", "A", action, trigger([sim_time(1)]))], params=params)
    with pytest.raises(ScenarioFileError, match=message):
        load(path)


def test_a_parameter_action_in_init_is_refused(tmp_path):
    params = '<ParameterDeclaration name="Count" parameterType="double" value="0"/>'
    path = scene(tmp_path, [], params=params)
    _edit(
        path,
        "<Init><Actions>",
        '<Init><Actions>\n<GlobalAction><ParameterAction parameterRef="Count"><SetAction '
        'value="1"/></ParameterAction></GlobalAction>',
    )
    with pytest.raises(ScenarioFileError, match=r"<ParameterAction> in <Init> is not supported by ego") as exc:
        load(path)
    assert exc.value.line == _line_of(path, "<ParameterAction")


def _sync(master: str, ms: float, s: float, final: str = "") -> str:
    def lane_pos(lane: int, at: float) -> str:
        return f'<LanePosition roadId="0" laneId="{lane}" s="{at}" offset="0"/>'

    return (
        f'<SynchronizeAction masterEntityRef="{master}"><TargetPositionMaster>{lane_pos(-1, ms)}'
        f"</TargetPositionMaster><TargetPosition>{lane_pos(-2, s)}</TargetPosition>{final}</SynchronizeAction>"
    )


@pytest.mark.sumo
@pytest.mark.parametrize(
    ("final", "v_end"),
    [
        ("", None),
        ('<FinalSpeed><AbsoluteSpeed value="10"/></FinalSpeed>', 10.0),
        ('<FinalSpeed><RelativeSpeedToMaster speedTargetValueType="delta" value="-15"/></FinalSpeed>', 10.0),
    ],
)
def test_synchronize_arrives_with_the_master(tmp_path, monkeypatch, final, v_end):
    """A (master, 25 m/s from s = 100) reaches s = 300 at 8 s; B (15 m/s from s = 200) is to
    reach s = 250 then: it arrives within one step's travel of it when A arrives (and with the
    final speed within 0.5 m/s); the action ends there."""
    from ego.openscenario import runtime

    seen: list[tuple[float, float, float, float]] = []
    orig = runtime.Storyboard._kinematics

    def record(self, t):
        orig(self, t)
        a, b = self.states["A"], self.states["B"]
        seen.append((t, a.s, b.s, b.speed))

    monkeypatch.setattr(runtime.Storyboard, "_kinematics", record)
    done = (
        '<Condition name="e" delay="0" conditionEdge="none"><ByValueCondition><StoryboardElementStateCondition '
        'storyboardElementType="action" storyboardElementRef="SyncAction" state="completeState"/></ByValueCondition>'
        "</Condition>"
    )
    evs = [
        event("Sync", "B", _sync("A", 300.0, 250.0, final), trigger([sim_time(0)])),
        event("Done", "C", speed(15), trigger([done])),
    ]
    sc = run_scene(scene(tmp_path, evs), 9.0)
    arrival = next(row for row in seen if row[1] >= 300.0 - 1e-9)
    t, _, s_b, v_b = arrival
    assert t == pytest.approx(8.0, abs=0.11)
    assert abs(s_b - 250.0) <= max(v_b, 1.0) * 0.1 + 1e-6
    if v_end is not None:
        assert v_b == pytest.approx(v_end, abs=0.5)
    assert starts(sc, "Done") and starts(sc, "Done")[0] == pytest.approx(t + 0.1, abs=0.11)


def test_synchronize_on_the_ego_is_refused(tmp_path, capsys):
    from ego.cli import main

    path = scene(tmp_path, [event("Sync", "Ego", _sync("A", 300.0, 250.0), trigger([sim_time(0)]))])
    assert main(["run", str(path), "-c", "pid"]) == 2
    assert "<SynchronizeAction> on the ego (Ego) is not supported" in capsys.readouterr().err


MANEUVERS = """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="0" date="2026-01-01T00:00:00" description="m" author="t"/>
<Catalog name="Moves">
  <Maneuver name="Brake">
    <ParameterDeclarations><ParameterDeclaration name="Target" parameterType="double" value="5"/>
    </ParameterDeclarations>
    <Event name="BrakeEvent" priority="overwrite"><Action name="BrakeAction"><PrivateAction>
      <LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step"/><SpeedActionTarget>
      <AbsoluteTargetSpeed value="$Target"/></SpeedActionTarget></SpeedAction></LongitudinalAction>
    </PrivateAction></Action>{start}</Event>
  </Maneuver>
</Catalog></OpenSCENARIO>
"""


def _catalog_scene(tmp_path, assign: str):
    (tmp_path / "man").mkdir(exist_ok=True)
    (tmp_path / "man" / "Moves.xosc").write_text(MANEUVERS.format(start=trigger([sim_time(0.95)])))
    path = scene(tmp_path, [event("X", "C", speed(15), trigger([sim_time(5)]))])
    _edit(
        path,
        "<RoadNetwork>",
        '<CatalogLocations><ManeuverCatalog><Directory path="man"/></ManeuverCatalog></CatalogLocations><RoadNetwork>',
    )
    ref = (
        '<ManeuverGroup name="GA" maximumExecutionCount="1"><Actors selectTriggeringEntities="false">'
        '<EntityRef entityRef="A"/></Actors><CatalogReference catalogName="Moves" entryName="Brake">'
        f"<ParameterAssignments>{assign}</ParameterAssignments></CatalogReference></ManeuverGroup>"
    )
    _edit(path, '<ManeuverGroup name="GC"', ref + '<ManeuverGroup name="GC"')
    return path


def test_a_maneuver_from_a_maneuver_catalog(tmp_path):
    """A ManeuverGroup's CatalogReference to a ManeuverCatalog entry: its own parameters, the
    reference's assignments (a parameterRef written with a leading $, as the reference player's
    files write it, names the same parameter), its events in the storyboard."""
    path = _catalog_scene(tmp_path, '<ParameterAssignment parameterRef="$Target" value="12"/>')
    sc = load(path)
    group = sc.stories[0].acts[0].groups[0]
    assert group.actors == ("A",) and group.maneuvers[0].name == "Brake"
    ev = group.maneuvers[0].events[0]
    assert ev.name == "BrakeEvent" and ev.actions[0].action.value == 12.0  # type: ignore[union-attr]
    path = _catalog_scene(tmp_path, '<ParameterAssignment parameterRef="Nope" value="12"/>')
    with pytest.raises(ScenarioFileError, match=r"catalog entry 'Brake' declares no parameter 'Nope'"):
        load(path)


def test_boxes_overlap_is_the_oriented_rectangles_test():
    from ego.openscenario.runtime import EntityState, boxes_overlap

    a = EntityState(x=0.0, y=0.0, yaw=0.0, length=4.0, width=2.0)
    assert boxes_overlap(a, EntityState(x=3.9, y=0.0, length=4.0, width=2.0))
    assert not boxes_overlap(a, EntityState(x=4.1, y=0.0, length=4.0, width=2.0))
    assert not boxes_overlap(a, EntityState(x=0.0, y=2.05, length=4.0, width=2.0))
    # turned 45 degrees: its corner reaches (2 + 1) cos 45 = 2.121 m along x, so they touch
    # while its centre is within 2 + 2.121 = 4.121 m
    assert boxes_overlap(a, EntityState(x=4.1, y=0.0, yaw=math.pi / 4, length=4.0, width=2.0))
    assert not boxes_overlap(a, EntityState(x=4.15, y=0.0, yaw=math.pi / 4, length=4.0, width=2.0))


@pytest.mark.sumo
def test_collision_condition_fires_when_the_boxes_touch(tmp_path):
    """C drives beside B (lane -3 and -2, both 15 m/s) and changes into B's lane over 1 s from
    1 s (a scripted move, blind to B): the CollisionCondition of C with B fires once their boxes
    touch (C 1.8 m wide, the lanes 3.5 m apart: half way across, 1.3-1.9 s), ByType vehicle at
    the same step, ByType pedestrian never."""
    coll = (
        '<Condition name="k" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities '
        'triggeringEntitiesRule="any"><EntityRef entityRef="C"/></TriggeringEntities><EntityCondition>'
        "<CollisionCondition>{}</CollisionCondition></EntityCondition></ByEntityCondition></Condition>"
    )
    evs = [
        event("Move", "C", lane_change(-2, "linear", "time", 1.0), trigger([sim_time(0.95)])),
        event("Hit", "A", speed(20), trigger([coll.format('<EntityRef entityRef="B"/>')])),
        event("Any", "A", speed(21), trigger([coll.format('<ByType objectType="vehicle"/>')])),
        event("Walker", "A", speed(22), trigger([coll.format('<ByType objectType="pedestrian"/>')])),
    ]
    sc = run_scene(scene(tmp_path, evs, at={"C": (-3, 200.0, 15.0)}), 2.5)
    hit = starts(sc, "Hit")
    assert len(hit) == 1 and 1.3 <= hit[0] <= 1.9
    assert starts(sc, "Any") == starts(sc, "Hit")
    assert starts(sc, "Walker") == []


def _profile(mode: str, entries: str, limits: str = "") -> str:
    dc = f"<DynamicConstraints {limits}/>" if limits else ""
    return (
        f'<LongitudinalAction><SpeedProfileAction followingMode="{mode}">{dc}{entries}</SpeedProfileAction>'
        "</LongitudinalAction>"
    )


def test_speed_profile_knots():
    from ego.openscenario.runtime import speed_profile_knots

    entries = ((10.0, 4.0), (4.0, 4.0), (8.0, None))
    a = M.SpeedProfileAction(entries, None, "position", max_accel=2.0, max_decel=3.0)
    assert speed_profile_knots(a, 1.0, 0.0, 0.0) == ([1.0, 5.0, 9.0, 11.0], [0.0, 10.0, 4.0, 8.0])
    # follow: no faster than the limits (10 m/s in 4 s is 2.5 m/s^2 > 2: 5 s)
    a = M.SpeedProfileAction(entries, None, "follow", max_accel=2.0, max_decel=3.0)
    assert speed_profile_knots(a, 1.0, 0.0, 0.0) == ([1.0, 6.0, 10.0, 12.0], [0.0, 10.0, 4.0, 8.0])
    # relative to an entity driving 5 m/s; no limits: an entry without time is a step
    a = M.SpeedProfileAction(((1.0, None),), "B", "position")
    assert speed_profile_knots(a, 0.0, 3.0, 5.0) == ([0.0, 0.0], [3.0, 6.0])


@pytest.mark.sumo
def test_speed_profile_is_followed_step_by_step(tmp_path):
    """B (15 m/s) goes to 25 m/s in 2 s, then to 5 m/s in 4 s, from 1 s: its speed is the
    piecewise-linear profile within 1e-6 at every step."""
    entries = '<SpeedProfileEntry speed="25" time="2"/><SpeedProfileEntry speed="5" time="4"/>'
    ev = event("P", "B", _profile("position", entries), trigger([sim_time(0.95)]))
    sc = run_scene(scene(tmp_path, [ev]), 8.0)
    import numpy as np

    for t, v, _ in sc._history["B"]:
        want = float(np.interp(t, [1.0, 3.0, 7.0], [15.0, 25.0, 5.0]))
        assert v == pytest.approx(want, abs=1e-6), t


@pytest.mark.sumo
def test_relative_object_positions(tmp_path, monkeypatch):
    """A starts 30 m behind C and 3.5 m to its left (RelativeObjectPosition in Init: C's lane
    -3 is straight, so lane -2); at 1 s B is teleported 20 m ahead of C in C's own frame."""
    from ego.openscenario import runtime

    seen: dict[float, dict[str, tuple[float, float]]] = {}
    orig = runtime.Storyboard._kinematics

    def record(self, t):
        orig(self, t)
        seen[round(t, 3)] = {n: (e.s, e.d) for n, e in self.states.items()}

    monkeypatch.setattr(runtime.Storyboard, "_kinematics", record)
    to = '<TeleportAction><Position><RelativeObjectPosition entityRef="C" dx="20" dy="0"/></Position></TeleportAction>'
    path = scene(tmp_path, [event("Jump", "B", to, trigger([sim_time(0.95)]))])
    _edit(
        path,
        '<LanePosition roadId="0" laneId="-1" s="100.0" offset="0"/>',
        '<RelativeObjectPosition entityRef="C" dx="-30" dy="3.5"/>',
    )
    run_scene(path, 1.5)
    a, c = seen[0.0]["A"], seen[0.0]["C"]
    assert a[0] == pytest.approx(c[0] - 30.0, abs=1e-3) and a[1] == pytest.approx(c[1] + 3.5, abs=1e-3)
    b, c = seen[1.1]["B"], seen[1.1]["C"]
    assert b[1] == pytest.approx(c[1], abs=1e-3)
    # the teleport (started at 1.0) puts B 20 m ahead of where C was at 1.0, at 1.1 (as every
    # TeleportAction: the position is read from the states at the step it starts), while C
    # drove on 1.5 m in that step
    assert b[0] - c[0] == pytest.approx(20.0 - 1.5, abs=0.05)


def _reach(position: str) -> str:
    return _cond(f'<ReachPositionCondition tolerance="12"><Position>{position}</Position></ReachPositionCondition>')


def test_a_lane_position_on_lane_0_is_the_reference_line(tmp_path):
    """OpenDRIVE's lane 0 is the reference line (esmini's controller_test.xosc reaches a
    LanePosition with laneId 0): its offset is t from the line, so the condition fires when a
    RoadPosition with that t does. C drives lane -3 (its centre 8.75 m right of the line) from
    s = 400 m at 15 m/s: within 12 m of (500, -2) once 6.75 m across and 9.92 m before it."""
    evs = [
        event("Lane0", "A", speed(26), trigger([_reach('<LanePosition roadId="0" laneId="0" s="500" offset="-2"/>')])),
        event("Road", "B", speed(16), trigger([_reach('<RoadPosition roadId="0" s="500" t="-2"/>')])),
    ]
    sc = run_scene(scene(tmp_path, evs), 8.0)
    reach = (100 - math.sqrt(12**2 - 6.75**2)) / 15
    assert starts(sc, "Lane0") == starts(sc, "Road") == [pytest.approx(reach, abs=0.1)]


@pytest.mark.parametrize(
    "position, message",
    [
        ('<LanePosition roadId="7" laneId="-1" s="300"/>', "unknown road '7'"),
        ('<LanePosition roadId="0" laneId="2" s="300"/>', "has no lanes with positive ids"),
    ],
)
def test_a_bad_position_in_a_condition_is_refused_by_list_and_run_alike(tmp_path, position, message):
    """Found before the run, at the position's own line, by ``ego list`` as by ``ego run``
    (it used to be found when the condition was first evaluated, or not at all)."""
    from ego.openscenario.scenario import file_listing

    path = scene(tmp_path, [event("Reach", "A", speed(26), trigger([_reach(position)]))])
    listing = file_listing(str(path))
    assert not listing["supported"] and message in listing["error"], listing["error"]
    run = subprocess.run(
        [sys.executable, "-m", "ego", "run", str(path), "-c", "pid"], capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert message in run.stderr and listing["error"] in run.stderr, run.stderr


def test_a_lane_change_past_the_ego_roads_lanes_is_refused_by_list_and_run_alike(tmp_path):
    """esmini's acc-test/aeb-test/alks-test change lanes to the ego's left on a road with one
    lane each way; ego models the lanes of the ego's direction only. Refused before the run at
    the LaneChangeAction's line (ego list said supported and ego run failed mid-run)."""
    from ego.openscenario.scenario import file_listing

    relative = (
        '<LateralAction><LaneChangeAction><LaneChangeActionDynamics dynamicsShape="sinusoidal" value="2" '
        'dynamicsDimension="time"/><LaneChangeTarget><RelativeTargetLane entityRef="Ego" value="3"/>'
        "</LaneChangeTarget></LaneChangeAction></LateralAction>"
    )
    path = scene(tmp_path, [event("Far", "A", relative, trigger([sim_time(1)]))])
    listing = file_listing(str(path))
    want = f"scene.xosc:{_line_of(path, '<LaneChangeAction>')}: a lane change +3 lanes from Ego's lane"
    assert not listing["supported"] and want in listing["error"], listing["error"]
    run = subprocess.run(
        [sys.executable, "-m", "ego", "run", str(path), "-c", "pid"], capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 2 and want in run.stderr and len(run.stderr.strip().splitlines()) == 1, run.stderr


def test_route_environment_and_trajectory_catalog_locations_are_accepted(tmp_path):
    """The reference player's files declare these catalogs whether they use them or not,
    often as an empty ``<RouteCatalog/>``: a location reads nothing, so the file lists as
    supported and runs; an empty vehicle catalog location is accepted the same way."""
    from ego.openscenario.scenario import file_listing

    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))])
    (tmp_path / "Routes").mkdir()
    _edit(
        path,
        "<RoadNetwork>",
        '<CatalogLocations><RouteCatalog/><VehicleCatalog/><EnvironmentCatalog><Directory path="Routes"/>'
        '</EnvironmentCatalog><TrajectoryCatalog><Directory path="Routes"/></TrajectoryCatalog></CatalogLocations>'
        "<RoadNetwork>",
    )
    listing = file_listing(str(path))
    assert listing["supported"], listing["error"]
    assert starts(run_scene(path, 2.0), "Go") == [pytest.approx(1.0)]


@pytest.mark.parametrize(
    "old, new, ok",
    [
        ('<Maneuver name="MA">', "<Maneuver>", True),  # esmini's alks_decelerate.xosc
        ('revMinor="2"', 'revMinor="1+"', True),  # esmini's speed-profile.xosc
        ('revMinor="2"', 'revMinor="x"', False),
    ],
    ids=["maneuver-without-name", "revMinor-1+", "revMinor-x"],
)
def test_the_reference_players_loose_header_and_maneuver_forms(tmp_path, old, new, ok):
    """A Maneuver without its name (only a reference needs it) and a revision written "1+"
    (read by its leading number) are read as the reference player reads them; a revision
    without a number is still one line."""
    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))])
    _edit(path, old, new)
    if ok:
        assert starts(run_scene(path, 2.0), "Go") == [pytest.approx(1.0)]
    else:
        with pytest.raises(ScenarioFileError, match="needs integer revMajor and revMinor"):
            load(path)


def test_a_start_closer_than_sumos_safe_gap_runs_where_the_file_places_it(tmp_path):
    """esmini's cut-in_simple.xosc starts a faster car 20 m behind the ego: closer than SUMO's
    drivers' safe gap, so SUMO refused to insert the ego (``ego list`` had said supported).
    A file's Init places its entities; SUMO now refuses only an overlap. B starts 8 m behind
    A's tail at 5 m/s more and both are where the file put them."""
    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(0.5)]))], at={"B": (-1, 87.0, 30.0)})
    sc = run_scene(path, 1.0)  # SUMO refused it: SumoError before the first step
    assert sc.status in ("completed", "ended"), sc.status_detail
    assert starts(sc, "Go") == [pytest.approx(0.5)]


def test_entities_starting_in_one_place_collide_at_the_start(tmp_path):
    """Two bodies overlapping at the start (esmini's python_scenario.xosc starts Target1 where
    the ego is): the standard has no rule against it and the reference player places them;
    ``ego list`` accepts the file as ``ego run`` does, and the run reports the collision at
    t = 0 with the overlap's geometry (B's front 2 m into A's back: 2.00 m along, the full
    1.80 m across)."""
    from ego.openscenario.scenario import file_listing

    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))], at={"B": (-1, 102.5, 25.0)})
    listing = file_listing(str(path))
    assert listing["supported"], listing["error"]
    sc = run_scene(path, 2.0)
    traffic = [e for e in sc.events if e.kind == "traffic" and e.t == 0.0]
    assert [e.text for e in traffic] == [
        "collision in the traffic: B hit A, overlapping at the start (2.00 m along, 1.80 m across their lane)"
    ]


def test_an_entity_starting_in_the_egos_place_is_a_collision_at_t_0(tmp_path):
    sc = run_scene(scene(tmp_path, [], at={"A": (-3, 20.0, 20.0)}), 2.0)
    assert sc.status == "collision" and sc.t == 0.0
    assert "A (20.0 m/s) hit ego (20.0 m/s): overlapping at the start (4.50 m along, 1.80 m across" in (
        sc.status_detail
    )


GHOST = (
    '<ObjectController><Controller name="FollowGhostController"><Properties><Property name="ghost" '
    'value="A"/></Properties></Controller></ObjectController>'
)


@pytest.mark.sumo
def test_a_ghost_starting_in_the_egos_place_is_no_body(tmp_path):
    """esmini's basic_ghost.xosc: the ego follows a ghost (its controller's `ghost` property)
    that starts where the ego is. A ghost is no physical body: no collision at the start nor
    later (it drives off ahead through the ego's place), and the surround sensor does not see
    it."""
    path = scene(tmp_path, [event("Go", "A", speed(30), trigger([sim_time(0.5)]))], at={"A": (-3, 20.0, 20.0)})
    text = path.read_text()
    first = text.index("</ScenarioObject>", text.index('<ScenarioObject name="Ego">'))
    path.write_text(text[:first] + GHOST + text[first:])
    assert load(path).ghosts == frozenset({"A"})
    sc = run_scene(path, 3.0)
    assert sc.status != "collision", sc.status_detail
    assert sc.board.states["A"].s > sc.board.states["Ego"].s + 5.0  # it drove off ahead
    assert "A" in sc.view.hidden and sc.view.gap_front == math.inf


def test_an_openscenario_0_8_file_is_refused_for_its_version(tmp_path):
    """A version ego does not read (0.8 here; 0.9 is read as 1.0: test_xosc_v09.py) is refused
    for its version, not for its first element of the other schema (`<ParameterDeclaration>`)."""
    path = scene(tmp_path, [event("Go", "A", speed(26), trigger([sim_time(1)]))])
    _edit(path, 'revMajor="1" revMinor="2"', 'revMajor="0" revMinor="8"')
    _edit(path, "<ParameterDeclarations>", '<ParameterDeclaration><Parameter name="$X" type="double" value="1"/>')
    _edit(path, "</ParameterDeclarations>", "</ParameterDeclaration>")
    with pytest.raises(ScenarioFileError, match=r"OpenSCENARIO 0\.8 is not supported by ego \(0\.9 and 1\.0 to 1\.3"):
        load(path)


@pytest.mark.parametrize("spelling, value", [("freespace", True), ("freeSpace", True), ("freeSpace", False)])
def test_a_distance_conditions_freespace_is_read_in_either_spelling(tmp_path, spelling, value):
    """esmini's two_plus_one_road.xosc writes a RelativeDistanceCondition's freespace as
    freeSpace (the spelling of 1.2's RelativeClearanceCondition): read where freespace is missing."""
    body = (
        f'<RelativeDistanceCondition entityRef="A" {spelling}="{str(value).lower()}" rule="lessThan" '
        'relativeDistanceType="longitudinal" value="20"/>'
    )
    cond = (
        '<Condition name="c" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities '
        'triggeringEntitiesRule="any"><EntityRef entityRef="Ego"/></TriggeringEntities><EntityCondition>'
        f"{body}</EntityCondition></ByEntityCondition></Condition>"
    )
    path = scene(tmp_path, [event("E", "A", speed(20.0), trigger([cond]))])
    model = load(path)
    conds = [c for g in model.stories[0].acts[0].groups[0].maneuvers[0].events[0].start.groups for c in g]
    assert [(c.kind, c.freespace) for c in conds] == [("RelativeDistanceCondition", value)]
