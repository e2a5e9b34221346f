"""Storyboard semantics in real SUMO runs: each condition type fires at the storyboard step
where the hand-computed condition first holds; edges, delays, condition groups, priorities
and execution counts; each dynamics shape moves a SUMO car along its closed-form profile.

Kinematics of the scene (tests/openscenario/xosc_scenes.py): at storyboard time t = 0.1 k the box
centres are s_A = 100 + 2.5 k (lane -1, y = 3.5), s_B = 200 + 1.5 k (lane -2); every car is
4.5 m long. Thresholds sit between steps, never on one."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import (
    entity,
    event,
    lane_change,
    lane_offset,
    run_scene,
    scene,
    sim_time,
    speed,
    starts,
    trigger,
)

from ego.openscenario.dynamics import (
    Transition,
    lateral_duration,
    offset_duration,
    speed_duration,
)

pytestmark = pytest.mark.sumo


def _pos(s: float, lane: int = -1) -> str:
    return f'<Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="0"/></Position>'


#: (event, trigger, storyboard time it must fire at, the hand computation)
CONDITIONS = [
    ("SimulationTime", trigger([sim_time(1.05)]), 1.1, "t >= 1.05"),
    ("TraveledDistance", trigger([entity("A", '<TraveledDistanceCondition value="26.25"/>')]), 1.1, "2.5 k >= 26.25"),
    (
        "ReachPosition",
        trigger([entity("A", f'<ReachPositionCondition tolerance="1">{_pos(130)}</ReachPositionCondition>')]),
        1.2,
        "|100 + 2.5 k - 130| <= 1",
    ),
    (
        "Distance",
        trigger(
            [
                entity(
                    "A",
                    '<DistanceCondition value="10" freespace="false" rule="lessThan">'
                    '<Position><WorldPosition x="150" y="3.5"/></Position></DistanceCondition>',
                )
            ]
        ),
        1.7,
        "150 - (100 + 2.5 k) < 10",
    ),
    (
        "DistanceFreespace",
        trigger(
            [
                entity(
                    "A",
                    '<DistanceCondition value="10" freespace="true" rule="lessThan">'
                    '<Position><WorldPosition x="150" y="3.5"/></Position>'
                    "</DistanceCondition>",
                )
            ]
        ),
        1.6,
        "150 - (100 + 2.5 k + 2.25) < 10",
    ),
    (
        "RelativeDistance",
        trigger(
            [
                entity(
                    "A",
                    '<RelativeDistanceCondition entityRef="B" relativeDistanceType='
                    '"longitudinal" value="79.5" freespace="false" rule="lessThan"/>',
                )
            ]
        ),
        2.1,
        "100 - k < 79.5",
    ),
    (
        "RelativeDistanceFreespace",
        trigger(
            [
                entity(
                    "A",
                    '<RelativeDistanceCondition entityRef="B" '
                    'relativeDistanceType="longitudinal" value="79.5" '
                    'freespace="true" rule="lessThan"/>',
                )
            ]
        ),
        1.7,
        "100 - k - 4.5 < 79.5: k > 16",
    ),
    (
        "TimeHeadway",
        trigger([entity("A", '<TimeHeadwayCondition entityRef="B" value="3.5" freespace="false" rule="lessThan"/>')]),
        1.3,
        "(100 - k) / 25 < 3.5",
    ),
    (
        "TimeHeadwayFreespace",
        trigger([entity("A", '<TimeHeadwayCondition entityRef="B" value="3.5" freespace="true" rule="lessThan"/>')]),
        0.9,
        "(95.5 - k) / 25 < 3.5",
    ),
    (
        "TimeToCollision",
        trigger(
            [
                entity(
                    "A",
                    '<TimeToCollisionCondition value="9.45" freespace="false" '
                    'rule="lessThan"><TimeToCollisionConditionTarget><EntityRef '
                    'entityRef="B"/></TimeToCollisionConditionTarget>'
                    "</TimeToCollisionCondition>",
                )
            ]
        ),
        0.6,
        "(100 - k) / 10 < 9.45",
    ),
    (
        "TimeToCollisionPosition",
        trigger(
            [
                entity(
                    "A",
                    '<TimeToCollisionCondition value="3.05" freespace="false" '
                    'rule="lessThan"><TimeToCollisionConditionTarget>'
                    f"{_pos(180)}</TimeToCollisionConditionTarget>"
                    "</TimeToCollisionCondition>",
                )
            ]
        ),
        0.2,
        "(180 - 100 - 2.5 k) / 25 < 3.05: k > 1.5",
    ),
    ("Speed", trigger([entity("B", '<SpeedCondition value="15.5" rule="greaterThan"/>')]), None, "never: 15"),
    (
        "RelativeSpeed",
        trigger([entity("A", '<RelativeSpeedCondition entityRef="B" value="9.5" rule="greaterThan"/>')]),
        0.0,
        "25 - 15 > 9.5 from the start",
    ),
    (
        "Parameter",
        trigger(
            [
                (
                    '<Condition name="p" delay="0" conditionEdge="none"><ByValueCondition>'
                    '<ParameterCondition parameterRef="Flag" value="1" rule="equalTo"/>'
                    "</ByValueCondition></Condition>"
                )
            ]
        ),
        0.0,
        "Flag = 1",
    ),
    (
        "AllOfTwo",
        trigger([entity("A,B", '<SpeedCondition value="14" rule="greaterThan"/>', rule="all")]),
        0.0,
        "25 > 14 and 15 > 14",
    ),
    (
        "AllFails",
        trigger([entity("A,B", '<SpeedCondition value="20" rule="greaterThan"/>', rule="all")]),
        None,
        "15 > 20 never",
    ),
    # edges and delays
    ("Rising", trigger([sim_time(1.05, edge="rising")]), 1.1, "false at 1.0, true at 1.1"),
    ("Falling", trigger([sim_time(1.05, rule="lessThan", edge="falling")]), 1.1, "true at 1.0, false at 1.1"),
    ("RisingOrFalling", trigger([sim_time(1.05, rule="lessThan", edge="risingOrFalling")]), 1.1, "a change"),
    ("RisingFromStart", trigger([sim_time(0.0, edge="rising")]), None, "true from the first step: no edge"),
    ("Delay", trigger([sim_time(1.05, delay=0.5)]), 1.6, "1.1 + 0.5"),
    ("DelayedRising", trigger([sim_time(1.05, edge="rising", delay=1.0)]), 2.1, "1.1 + 1.0"),
    # condition groups: OR of ANDs
    ("AndGroup", trigger([sim_time(1.05), sim_time(2.05)]), 2.1, "both"),
    ("OrOfAnds", trigger([sim_time(3.05), sim_time(1.05, name="c2")], [sim_time(2.55)]), 2.6, "second group"),
]


@pytest.fixture(scope="module")
def condition_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("conditions")
    evs = [event(name, "A", speed(25), trig) for name, trig, _, _ in CONDITIONS]
    params = '<ParameterDeclaration name="Flag" parameterType="integer" value="1"/>'
    return run_scene(scene(tmp, evs, params), 4.0)


@pytest.mark.parametrize("name,expected", [(c[0], c[2]) for c in CONDITIONS], ids=[c[0] for c in CONDITIONS])
def test_condition_fires_at_the_hand_computed_step(condition_run, name, expected):
    got = starts(condition_run, name)
    if expected is None:
        assert got == []
    else:
        assert got == [pytest.approx(expected, abs=1e-9)]


def test_parameter_condition_follows_set(tmp_path):
    params = '<ParameterDeclaration name="Flag" parameterType="integer" value="1"/>'
    cond = trigger(
        [
            (
                '<Condition name="p" delay="0" conditionEdge="none"><ByValueCondition>'
                '<ParameterCondition parameterRef="Flag" value="1" rule="equalTo"/></ByValueCondition>'
                "</Condition>"
            )
        ]
    )
    sc = run_scene(scene(tmp_path, [event("P", "A", speed(25), cond)], params), 1.0, Flag=0)
    assert starts(sc, "P") == []


def test_storyboard_element_states(tmp_path):
    """A step action completes at its first step, its event at the next; a state condition sees
    a transition one step later."""

    def state(ref: str, st: str, kind: str = "event") -> str:
        return trigger(
            [
                f'<Condition name="s" delay="0" conditionEdge="none"><ByValueCondition>'
                f'<StoryboardElementStateCondition storyboardElementType="{kind}" '
                f'storyboardElementRef="{ref}" state="{st}"/></ByValueCondition></Condition>'
            ]
        )

    evs = [
        event("First", "A", speed(25), trigger([sim_time(0.95)])),
        event("AfterStart", "B", speed(15), state("First", "startTransition")),
        event("WhileRunning", "B", speed(15), state("First", "runningState")),
        event("AfterEnd", "C", speed(15), state("First", "endTransition")),
        event("WhenComplete", "C", speed(15), state("First", "completeState")),
        event("ActionDone", "C", speed(15), state("FirstAction", "completeState", "action")),
    ]
    sc = run_scene(scene(tmp_path, evs), 2.0)
    assert starts(sc, "First") == [pytest.approx(1.0)]
    assert starts(sc, "AfterStart") == [pytest.approx(1.1)]
    assert starts(sc, "WhileRunning") == [pytest.approx(1.1)]
    assert starts(sc, "AfterEnd") == [pytest.approx(1.2)]
    assert starts(sc, "WhenComplete") == [pytest.approx(1.2)]
    assert starts(sc, "ActionDone") == [pytest.approx(1.2)]


def test_priorities_and_execution_counts(tmp_path):
    evs = [
        # three runs: each completes a step after it starts and is triggered again a step later
        event("Thrice", "A", speed(25), trigger([sim_time(0.95)]), count=3),
        # a long action, overwritten by Later; Skipped does not start while Long runs
        event("Long", "C", speed(25, "linear", "time", 5.0), trigger([sim_time(0.95)])),
        event("Skipped", "C", speed(15), trigger([sim_time(1.95)]), priority="skip"),
        event("Later", "C", speed(20), trigger([sim_time(2.95)]), priority="overwrite"),
    ]
    sc = run_scene(scene(tmp_path, evs), 4.0)
    assert starts(sc, "Thrice") == [pytest.approx(1.0), pytest.approx(1.2), pytest.approx(1.4)]
    assert starts(sc, "Long") == [pytest.approx(1.0)]
    assert starts(sc, "Later") == [pytest.approx(3.0)]
    assert any("event 'Long' overwritten by 'Later'" in e.text for e in sc.events)
    # Skipped's trigger holds from 2.0 on; Long runs until Later stops it at 3.0 (Later is
    # running then, until its step action completes): Skipped starts once neither runs
    assert starts(sc, "Skipped") == [pytest.approx(3.2)]


def test_storyboard_stop_trigger(tmp_path):
    stop = f"<StopTrigger><ConditionGroup>{sim_time(1.55)}</ConditionGroup></StopTrigger>"
    sc = run_scene(scene(tmp_path, [event("E", "A", speed(25), trigger([sim_time(0.0)]))], stop=stop), 5.0)
    assert sc.status == "completed" and "StopTrigger" in sc.status_detail
    assert sc.t == pytest.approx(1.6)  # the storyboard's step at 1.6 ends it, at 1.6 on the run's clock


# -- dynamics: SUMO follows the closed-form profile ------------------------------------------------
SPEED_CASES = [  # shape, dimension, value, target: C from 15 m/s starting at t = 1.0
    ("step", "time", 0.0, 22.0),
    ("linear", "time", 2.0, 25.0),
    ("linear", "rate", 3.0, 21.0),
    ("linear", "rate", 4.0, 7.0),
    ("cubic", "time", 2.5, 25.0),
    ("cubic", "rate", 2.0, 9.0),
    ("sinusoidal", "time", 3.0, 20.0),
    ("sinusoidal", "distance", 40.0, 25.0),
    ("linear", "distance", 30.0, 10.0),
]


@pytest.mark.parametrize("shape,dim,value,target", SPEED_CASES, ids=[f"{c[0]}-{c[1]}-{c[3]:g}" for c in SPEED_CASES])
def test_speed_follows_closed_form(tmp_path, shape, dim, value, target):
    sc = run_scene(scene(tmp_path, [event("S", "C", speed(target, shape, dim, value), trigger([sim_time(0.95)]))]), 6.0)
    t0, v0 = 1.0, 15.0
    profile = Transition(t0, v0, target, speed_duration(shape, dim, value, v0, target), shape)
    hist = sc._history["C"]
    assert len(hist) > 50
    for t, v, _ in hist:
        assert v == pytest.approx(profile.value(t), abs=1e-6), t


LATERAL_CASES = [  # A from lane -1 (left) to lane -2 (middle): 3.5 m to the right
    ("lane-change", "sinusoidal", "time", 3.0),
    ("lane-change", "cubic", "time", 2.0),
    ("lane-change", "linear", "time", 2.5),
    ("lane-change", "linear", "distance", 50.0),
    ("lane-change", "step", "time", 0.0),
    ("lane-offset", "cubic", "", 1.0),
    ("lane-offset", "sinusoidal", "", 1.0),
]


@pytest.mark.parametrize("kind,shape,dim,value", LATERAL_CASES, ids=[f"{c[0]}-{c[1]}-{c[2]}" for c in LATERAL_CASES])
def test_lateral_follows_closed_form(tmp_path, kind, shape, dim, value):
    """The car's offset from the ego's road frame follows the profile within the sublane
    model's resolution: SUMO moves a car sideways by exactly the commanded change each step."""
    action = lane_change(-2, shape, dim, value) if kind == "lane-change" else lane_offset(-0.8, shape, value)
    sc = run_scene(scene(tmp_path, [event("L", "A", action, trigger([sim_time(0.95)]))]), 5.0)
    hist = sc._history["A"]
    d0 = hist[0][2]
    t0 = 1.0
    if kind == "lane-change":
        end = d0 - 3.5
        T = lateral_duration(shape, dim, value, 25.0)
    else:
        end = d0 - 0.8
        T = offset_duration(shape, value, -0.8)
    profile = Transition(t0, d0, end, T, shape)
    worst = max(abs(d - profile.value(t)) for t, _, d in hist)
    assert worst < 1e-6, worst
    assert hist[-1][2] == pytest.approx(end, abs=1e-6)


def test_relative_lane_change_and_speed(tmp_path):
    """Relative targets: B moves to A's lane (one left of its own) and to A's speed - 5."""
    evs = [
        event(
            "R",
            "B",
            lane_change(-1, "cubic", "time", 2.0).replace(
                '<AbsoluteTargetLane value="-1"/>', '<RelativeTargetLane entityRef="A" value="0"/>'
            ),
            trigger([sim_time(0.45)]),
        ),
        event("V", "B", speed(-5, "linear", "time", 1.0, relative="A"), trigger([sim_time(0.45)])),
    ]
    sc = run_scene(scene(tmp_path, evs), 3.0)
    t, v, d = sc._history["B"][-1]
    a = sc._history["A"][-1]
    assert d == pytest.approx(a[2], abs=1e-6)
    assert v == pytest.approx(20.0, abs=1e-6)


def test_teleport_and_trajectory(tmp_path):
    """TeleportAction places A's centre; FollowTrajectoryAction with timing moves C along a
    polyline at the vertices' times."""
    teleport = f"<TeleportAction>{_pos(300, -2)}</TeleportAction>"
    verts = "".join(
        f'<Vertex time="{tt}"><Position><WorldPosition x="{x}" y="{y}"/></Position></Vertex>'
        for tt, x, y in ((0.0, 420.0, -3.5), (2.0, 460.0, -3.5), (4.0, 500.0, 0.0))
    )
    traj = (
        '<RoutingAction><FollowTrajectoryAction><TrajectoryRef><Trajectory name="t" closed="false"><Shape>'
        f"<Polyline>{verts}</Polyline></Shape></Trajectory></TrajectoryRef><TimeReference>"
        '<Timing domainAbsoluteRelative="relative" scale="1" offset="0"/></TimeReference>'
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction>'
    )
    evs = [event("Tp", "A", teleport, trigger([sim_time(0.95)])), event("Tr", "C", traj, trigger([sim_time(0.95)]))]
    sc = run_scene(scene(tmp_path, evs), 6.0)
    hist_a = dict((round(t, 6), d) for t, _, d in sc._history["A"])
    # d is measured from the ego's lane (the right one): the middle lane is 3.5 m to its left
    assert hist_a[1.0] == pytest.approx(7.0, abs=1e-6)
    assert hist_a[1.1] == pytest.approx(3.5, abs=1e-6)  # in the middle lane from the next step
    st = sc.board.states["A"]
    assert st.s > 300.0
    # on the first leg C drives 40 m in 2 s along its lane's centre (d = 0 from the ego's
    # lane), on the second sqrt(40^2 + 3.5^2) m in 2 s
    hist_c = {round(t, 6): (v, d) for t, v, d in sc._history["C"]}
    for t in (1.5, 2.0, 2.5, 2.8):
        assert hist_c[t][0] == pytest.approx(20.0, abs=1e-6)
        assert hist_c[t][1] == pytest.approx(0.0, abs=1e-6)
    assert hist_c[4.0][0] == pytest.approx(math.hypot(40.0, 3.5) / 2.0, abs=1e-6)


def test_traveled_distance_matches_constant_speed(tmp_path):
    sc = run_scene(scene(tmp_path, [event("E", "B", speed(15), trigger([sim_time(0.0)]))]), 2.0)
    st = sc.board.states["B"]
    k = round(sc.board.t / 0.1)
    assert st.traveled == pytest.approx(1.5 * k, abs=1e-6)
    assert math.isclose(st.speed, 15.0)


def test_actions_on_the_ego_move_its_references(tmp_path):
    """A LaneChangeAction and a SpeedAction addressed to the ego: its controller tracks them
    (the lateral reference moves to the middle lane along the shape, the speed reference
    follows the linear profile)."""
    evs = [
        event("Left", "Ego", lane_change(-2, "cubic", "time", 3.0), trigger([sim_time(0.95)])),
        event("Faster", "Ego", speed(24.0, "linear", "time", 2.0), trigger([sim_time(0.95)])),
    ]
    sc = run_scene(scene(tmp_path, evs), 8.0)
    assert sc.status == "completed"
    assert sc.target_lane == 1
    assert sc.d_road == pytest.approx(sc.lane_offset[1], abs=0.3)  # report 000's PID settles slowly
    assert sc.ego.state[1] == pytest.approx(24.0, abs=0.2)
    t = sc.trace.array(0)
    cols = sc.trace.names
    times = t[:, cols.index("t")]
    # a row at time t holds the references of storyboard time t (the actions start at 1.0 on
    # the storyboard's clock, as the scripted cars' do, not a SUMO step later)
    i = round(2.0 / 0.01)  # halfway along the speed ramp: 22 m/s
    assert times[i] == pytest.approx(2.0)
    assert t[i, cols.index("speed_ref")] == pytest.approx(22.0, abs=1e-9)
    i = round(2.5 / 0.01)  # halfway across: 1.75 m short of the lane
    assert t[i, cols.index("d_ref")] == pytest.approx(-1.75, abs=1e-9)
    # on the linear profile at every row from the storyboard's step that starts it (1.0 s) on,
    # the first SUMO step's rows included, and at 20 m/s before it
    for k in range(round(0.9 / 0.01), round(3.0 / 0.01)):
        assert t[k, cols.index("speed_ref")] == pytest.approx(20.0 + 2.0 * max(times[k] - 1.0, 0.0), abs=1e-9)
    lateral = Transition(1.0, -3.5, 0.0, 3.0, "cubic")  # from the middle lane (its target) as the ego's lane's
    for k in range(round(1.0 / 0.01), round(1.3 / 0.01)):
        assert t[k, cols.index("d_ref")] == pytest.approx(lateral.value(times[k]), abs=1e-9)


@pytest.mark.parametrize("who", ["Ego", "C"])
def test_a_start_beyond_the_road_is_refused_at_load(tmp_path, who):
    from ego.openscenario.xmltree import ScenarioFileError

    with pytest.raises(ScenarioFileError, match=rf"scene.xosc:\d+: {who} starts beyond its road: its front at 3\d\d\d"):
        run_scene(scene(tmp_path, [], at={who: (-3, 3100.0, 15.0)}), 1.0)


def test_a_lane_on_a_side_without_lanes_is_named(tmp_path):
    from ego.openscenario.xmltree import ScenarioFileError

    with pytest.raises(ScenarioFileError, match=r"road '0' has no lanes with positive ids \(lane ids -1, -2, -3\)"):
        run_scene(scene(tmp_path, [], at={"C": (1, 400.0, 15.0)}), 1.0)


def test_a_car_leaving_the_road_network_ends_the_run_as_its_time_would(tmp_path):
    """straight3 is 3000 m long: C, 40 m before its end at 20 m/s, leaves SUMO at the end of
    its route after about 2 s; the run ends there (no TraCI error), the metrics complete."""
    sc = run_scene(scene(tmp_path, [], at={"C": (-1, 2960.0, 20.0)}), 8.0)
    assert sc.status == "completed" and 1.5 < sc.t < 3.0
    assert sc.status_detail.startswith("C left the road network (the end of its route) at t = ")
    assert sc.result().metrics["status"] == "completed"


def test_the_ego_reaching_the_end_of_its_road_ends_the_run(tmp_path):
    sc = run_scene(scene(tmp_path, [], at={"Ego": (-3, 2960.0, 20.0), "C": (-1, 400.0, 15.0)}), 8.0)
    assert sc.status == "completed" and 1.5 < sc.t < 2.5
    assert "the ego reached the end of its route" in sc.status_detail and "a dead end" in sc.status_detail
    x_end = sc.view.road.length
    assert sc.view.s + sc.geometry.cg_to_front == pytest.approx(x_end, abs=0.1 * 20.0 + 0.5)


def test_a_start_off_the_lane_centre_is_taken_in_the_first_step(tmp_path):
    """An Init LanePosition offset: SUMO inserts on the lane's centre and its sublane model
    moves the car across in the first step (0.1 s), where it then stays."""
    path = scene(tmp_path, [])
    text = path.read_text().replace('laneId="-2" s="200.0" offset="0"', 'laneId="-2" s="200.0" offset="1.2"')
    path.write_text(text)
    sc = run_scene(path, 3.0)
    hist = [(t, d) for t, _, d in sc._history["B"] if t >= 0.1 - 1e-9]
    assert len(hist) > 20
    for t, d in hist:
        assert d == pytest.approx(3.5 + 1.2, abs=1e-6), t


def test_the_storyboard_sees_the_ego_at_its_own_time_as_it_sees_sumos_cars(tmp_path):
    """At storyboard time t every entity is as of t: the ego's state there is the trace's row
    at t (the storyboard steps right after SUMO's step to t, when the ego's model is at t too;
    a state a step off would be 2 m at 20 m/s for a distance condition)."""
    from ego.runner import RunSpec, build

    sc = build(RunSpec(str(scene(tmp_path, [])), "pid", overrides={"duration": 3.0}))
    seen = []
    sc.reset()
    step = sc.board.step

    def spy(t):
        e = sc.board.states["Ego"]
        seen.append((t, e.s, e.speed))
        step(t)

    sc.board.step = spy
    controller = sc.controller
    obs = sc.obs
    while not sc.done:
        obs = sc.step(controller.step(obs))
    trace = sc.trace.array()
    names = sc.trace.names
    g = sc.geometry
    off = g.cg_to_front - 0.5 * g.length
    sc.close()
    assert len(seen) > 20
    assert seen[-1][0] == pytest.approx(3.0)  # its last step at the run's end, past the trace's last row
    for t, s, u in seen[:-1]:
        row = trace[round(t / sc.config.dt)]
        assert row[names.index("t")] == pytest.approx(t)
        assert s - off == pytest.approx(row[names.index("s")], abs=1e-9)
        assert u == pytest.approx(row[names.index("speed")], abs=1e-12)
