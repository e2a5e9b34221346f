"""RelativeWorldPosition: ``dx``, ``dy`` along the world's axes from an entity's reference
point, against hand-computed points on north3.xodr: straight3.xodr (three 3.5 m lanes right
of the reference line) turned a quarter turn, its reference line on x = -5.25 m heading +y,
so road s is y, lane -1's centre is x = -3.5, lane -2's x = 0, lane -3's x = 3.5, and the
world's axes are not the road's."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import SHIPPED, event, run_scene, starts, trigger, write_file

from ego.openscenario.loader import load
from ego.openscenario.roads import RoadMap, network_file
from ego.openscenario.scenario import placements

STRAIGHT = '<geometry s="0" x="0" y="5.25" hdg="0" length="3000">'
NORTH = f'<geometry s="0" x="-5.25" y="0" hdg="{math.pi / 2!r}" length="3000">'


def _scene(tmp_path, starts_, events, replace: tuple[str, str] | None = None, road: str = "north3.xodr"):
    """The scene on ``road`` (north3.xodr: straight3.xodr turned; or straight3.xodr itself), one
    ``replace`` made in its text."""
    text = (SHIPPED / "straight3.xodr").read_text()
    assert text.count(STRAIGHT) == 1
    (tmp_path / road).write_text(text.replace(STRAIGHT, NORTH) if road == "north3.xodr" else text)
    path = write_file(tmp_path / "scene.xosc", road, starts_, events)
    if replace is not None:
        text = path.read_text()
        assert text.count(replace[0]) == 1, replace[0]
        path.write_text(text.replace(*replace))
    return path


def test_an_init_start_relative_to_an_entity_in_world_axes(tmp_path):
    """B starts 3.5 m in -x and 20 m in +y from A (lane -2 at s = 240: x = 0, y = 240): at
    lane -1's centre (x = -3.5), s = y = 260."""
    lane_b = '<LanePosition roadId="0" laneId="-1" s="999.0" offset="0"></LanePosition>'
    world = '<RelativeWorldPosition entityRef="A" dx="-3.5" dy="20"/>'
    path = _scene(
        tmp_path,
        [("Ego", "0", -3, 20.0, 10.0, ""), ("A", "0", -2, 240.0, 10.0, ""), ("B", "0", -1, 999.0, 10.0, "")],
        [],
        (lane_b, world),
    )
    roads = RoadMap(network_file(tmp_path / "north3.xodr"), converted=True)
    b = placements(load(path), roads)["B"]
    lane_b, _ = roads.lane_position("0", -1, 260.0)
    assert (b.edge, b.index) == (lane_b.edge, lane_b.index)
    (x0, y0), (x1, y1) = lane_b.shape[0], lane_b.shape[-1]
    assert (x0, x1, y1 - y0) == (pytest.approx(-3.5, abs=1e-3), pytest.approx(-3.5, abs=1e-3), pytest.approx(3000.0))
    assert b.front == pytest.approx(260.0 + 2.25, abs=1e-3)  # its centre at y = 260, the front 2.25 m ahead
    assert b.offset == pytest.approx(0.0, abs=1e-3)


def test_a_position_relative_to_a_moving_entity_in_world_axes(tmp_path):
    """A (lane -2 at y = 250, 10 m/s) and B (lane -3 at y = 220, 20 m/s): the
    point 3.5 m in +x and 10 m in -y from A is in B's lane 10 m behind A, 20 m ahead of B at
    the start, closing at 10 m/s: B is within 1.5 m of it from t = 1.9 s (20 - 10 t <= 1.5
    first at the storyboard step t = 1.9). The same point as A's RelativeObjectPosition is dx
    -10 (A heads +y), dy -3.5 (right of A is +x); dx 3.5, dy -10 in A's own frame is 10 m off
    the road and never reached."""

    def reach(position: str) -> str:
        return (
            '<Condition name="r" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities '
            'triggeringEntitiesRule="any"><EntityRef entityRef="B"/></TriggeringEntities><EntityCondition>'
            f'<ReachPositionCondition tolerance="1.5"><Position>{position}</Position></ReachPositionCondition>'
            "</EntityCondition></ByEntityCondition></Condition>"
        )

    noop = (
        '<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>'
        '<SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget></SpeedAction></LongitudinalAction>'
    )
    events = [
        event("World", "Ego", noop, trigger([reach('<RelativeWorldPosition entityRef="A" dx="3.5" dy="-10"/>')])),
        event("Object", "Ego", noop, trigger([reach('<RelativeObjectPosition entityRef="A" dx="-10" dy="-3.5"/>')])),
        event("Off", "Ego", noop, trigger([reach('<RelativeObjectPosition entityRef="A" dx="3.5" dy="-10"/>')])),
    ]
    path = _scene(
        tmp_path,
        [
            ("Ego", "0", -1, 20.0, 10.0, ""),
            ("A", "0", -2, 250.0, 10.0, ""),
            ("B", "0", -3, 220.0, 20.0, ""),
        ],
        events,
    )
    sc = run_scene(path, 3.0)
    assert starts(sc, "World") == [pytest.approx(1.9, abs=1e-9)]
    assert starts(sc, "Object") == [pytest.approx(1.9, abs=1e-9)]
    assert starts(sc, "Off") == []


# -- TrajectoryPosition (1.1), on straight3.xodr: lane -2's centre is y = 0, road s is x ----------
POLYLINE = (
    "<Polyline>"
    '<Vertex><Position><WorldPosition x="0" y="-10"/></Position></Vertex>'
    '<Vertex><Position><WorldPosition x="60" y="70"/></Position></Vertex>'
    "</Polyline>"
)
#: a quarter circle of radius 100 m from the origin heading +x, turning left
CLOTHOID = (
    f'<Clothoid curvature="0.01" curvatureDot="0" length="{50 * math.pi!r}">'
    '<Position><WorldPosition x="0" y="0" h="0"/></Position></Clothoid>'
)


def trajectory_position(shape: str, s: float, t: float) -> str:
    return (
        f'<TrajectoryPosition s="{s!r}" t="{t!r}"><TrajectoryRef><Trajectory name="T" closed="false">'
        f"<Shape>{shape}</Shape></Trajectory></TrajectoryRef></TrajectoryPosition>"
    )


@pytest.mark.parametrize(
    ("shape", "s", "t"),
    [
        # the polyline heads (0.6, 0.8): 50 m along it is (30, 30); t = -50 (right of it) adds (40, -30)
        (POLYLINE, 50.0, -50.0),
        # 45 degrees round the circle (s = 25 pi) is (100 sin 45, 100 (1 - cos 45)); its left normal is
        # (-sin 45, cos 45), so t = -100 (sqrt 2 - 1) is y = 0, x = 100 sin 45 + 100 (sqrt 2 - 1) sin 45 = 100
        (CLOTHOID, 25 * math.pi, -100 * (math.sqrt(2) - 1)),
    ],
    ids=["polyline", "clothoid"],
)
def test_an_init_start_on_a_trajectory(tmp_path, shape, s, t):
    """B starts at a TrajectoryPosition: on lane -2 at the hand-computed x (70 m on the polyline,
    100 m on the arc)."""
    lane_b = '<LanePosition roadId="0" laneId="-1" s="999.0" offset="0"></LanePosition>'
    path = _scene(
        tmp_path,
        [("Ego", "0", -3, 20.0, 10.0, ""), ("B", "0", -1, 999.0, 10.0, "")],
        [],
        (lane_b, trajectory_position(shape, s, t)),
        road="straight3.xodr",
    )
    roads = RoadMap(network_file(tmp_path / "straight3.xodr"), converted=True)
    b = placements(load(path), roads)["B"]
    lane2, _ = roads.lane_position("0", -2, 10.0)
    assert (b.edge, b.index) == (lane2.edge, lane2.index)
    expected = 70.0 if shape == POLYLINE else 100.0
    assert b.front - 2.25 == pytest.approx(expected, abs=1e-3)
    assert b.offset == pytest.approx(0.0, abs=1e-3)


def test_a_position_on_a_trajectory_during_the_run(tmp_path):
    """B (lane -2, s = 20, 10 m/s) reaches the polyline's point (70, 0) (within 0.5 m) once
    20 + 10 t >= 69.5: first at the storyboard step t = 5.0."""
    reach = (
        '<Condition name="r" delay="0" conditionEdge="none"><ByEntityCondition><TriggeringEntities '
        'triggeringEntitiesRule="any"><EntityRef entityRef="B"/></TriggeringEntities><EntityCondition>'
        f'<ReachPositionCondition tolerance="0.5"><Position>{trajectory_position(POLYLINE, 50.0, -50.0)}</Position>'
        "</ReachPositionCondition></EntityCondition></ByEntityCondition></Condition>"
    )
    noop = (
        '<LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" dynamicsDimension="time"/>'
        '<SpeedActionTarget><AbsoluteTargetSpeed value="10"/></SpeedActionTarget></SpeedAction></LongitudinalAction>'
    )
    path = _scene(
        tmp_path,
        [("Ego", "0", -3, 20.0, 10.0, ""), ("B", "0", -2, 20.0, 10.0, "")],
        [event("Reach", "Ego", noop, trigger([reach]))],
        road="straight3.xodr",
    )
    sc = run_scene(path, 6.0)
    assert starts(sc, "Reach") == [pytest.approx(5.0, abs=1e-9)]
