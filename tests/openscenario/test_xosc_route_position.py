"""RoutePosition: a point ``pathS`` m along a route's path (the shortest way through its
waypoints' roads, the one an AssignRouteAction drives) from its first waypoint, on the
hand-written network of test_xosc_road_links.py: road 1 (straight, 200 m) into junction 100,
its connecting road 4 (an arc, L4 = 50 m) onto road 2 (straight, 150 m). Converted by netconvert;
the point against the closed form of road s along the path."""

from __future__ import annotations

import math

import pytest
from test_xosc_road_links import L4, network
from xosc_scenes import write_file

from ego.openscenario import model as M
from ego.openscenario.loader import load
from ego.openscenario.roads import RoadMap, network_file
from ego.openscenario.scenario import _absolute_xy, concrete, placements

ROUTE = (
    '<Route name="R" closed="false">'
    '<Waypoint routeStrategy="shortest"><Position><LanePosition roadId="1" laneId="-1" s="20" offset="0"/>'
    "</Position></Waypoint>"
    '<Waypoint routeStrategy="shortest"><Position><LanePosition roadId="2" laneId="-1" s="100" offset="0"/>'
    "</Position></Waypoint></Route>"
)
B_START = '<LanePosition roadId="1" laneId="-2" s="150.0" offset="0"></LanePosition>'


def route_position(form: str, route: str = ROUTE) -> str:
    return f"<RoutePosition><RouteRef>{route}</RouteRef><InRoutePosition>{form}</InRoutePosition></RoutePosition>"


def _scene(tmp, b_position: str):
    """Ego on road 1 (lane -1, s = 50), B at ``b_position`` (its Init TeleportAction)."""
    (tmp / "links.xodr").write_text(network(False))
    path = write_file(
        tmp / "rp.xosc", "links.xodr", [("Ego", "1", -1, 50.0, 10.0, ""), ("B", "1", -2, 150.0, 10.0, "")], []
    )
    text = path.read_text()
    assert text.count(B_START) == 1
    path.write_text(text.replace(B_START, b_position))
    return path


def _roads(tmp) -> RoadMap:
    return RoadMap(network_file(tmp / "links.xodr"), converted=True, source=tmp / "links.xodr")


def _b(path) -> M.RoutePosition:
    tp = next(a for a in load(path).init["B"] if isinstance(a, M.TeleportAction))
    assert isinstance(tp.position, M.RoutePosition)
    return tp.position


def test_path_s_across_the_junction_lands_on_road_2(tmp_path):
    """pathS 260: 180 m of road 1 (s 20 to 200), 50 m through connecting road 4, then 30 m
    of road 2: road 2, lane -1, s = 30 (road 2 straight from its start, heading K4 * L4)."""
    path = _scene(tmp_path, route_position('<FromLaneCoordinates pathS="260" laneId="-1" laneOffset="0.5"/>'))
    roads = _roads(tmp_path)
    pos = concrete(_b(path), roads)
    assert isinstance(pos, M.LanePosition)
    assert (pos.road, pos.lane, pos.offset) == ("2", -1, 0.5)
    assert pos.s == pytest.approx(260.0 - 180.0 - L4, abs=1e-6)
    # the point: road 2's start (the arc's end) + 30 m along heading h2, 1.75 + 0.5 m right of... left
    k4 = 0.002
    x2, y2, h2 = 200.0 + math.sin(k4 * L4) / k4, (1.0 - math.cos(k4 * L4)) / k4, k4 * L4
    x, y, h = _absolute_xy(pos, roads)
    d = -1.75 + 0.5  # lane -1's centre 1.75 m right of the reference line, offset 0.5 m left
    assert (x, y) == (
        pytest.approx(x2 + 30.0 * math.cos(h2) - d * math.sin(h2), abs=0.02),  # SUMO's shapes: 0.01 m
        pytest.approx(y2 + 30.0 * math.sin(h2) + d * math.cos(h2), abs=0.02),
    )
    assert h == pytest.approx(h2, abs=1e-3)
    b = placements(load(path), roads)["B"]
    lane, _ = roads.lane_position("2", -1, 30.0)
    assert (b.edge, b.index) == (lane.edge, lane.index)


def test_from_road_coordinates_on_the_first_road(tmp_path):
    """pathS 100 from road 1's s = 20: road 1, s = 120, t as given."""
    path = _scene(tmp_path, route_position('<FromRoadCoordinates pathS="100" t="-5.25"/>'))
    pos = concrete(_b(path), _roads(tmp_path))
    assert isinstance(pos, M.RoadPosition)
    assert (pos.road, pos.s, pos.t) == ("1", pytest.approx(120.0, abs=1e-6), -5.25)
    b = placements(load(path), _roads(tmp_path))["B"]
    lane, _ = _roads(tmp_path).lane_position("1", -2, 120.0)  # t = -5.25: lane -2's centre
    assert (b.edge, b.index) == (lane.edge, lane.index)


def test_from_current_entity_is_the_entity_s_own_place(tmp_path):
    """FromCurrentEntity of the ego: B starts where the ego does (its reference point)."""
    path = _scene(tmp_path, route_position('<FromCurrentEntity entityRef="Ego"/>'))
    starts = placements(load(path), _roads(tmp_path))
    assert (starts["B"].edge, starts["B"].index) == (starts["Ego"].edge, starts["Ego"].index)
    assert starts["B"].front == pytest.approx(starts["Ego"].front, abs=1e-9)


@pytest.mark.parametrize(
    ("form", "message"),
    [
        ('<FromLaneCoordinates pathS="400" laneId="-1"/>', "pathS 400 is beyond the route's end"),
        ('<FromLaneCoordinates pathS="200" laneId="-1"/>', "pathS 200 lies 20.00 m into the junction"),
        ('<FromLaneCoordinates pathS="10" laneId="-4"/>', "road '1' has no lane -4"),
    ],
)
def test_bad_route_positions_are_refused_with_their_line(tmp_path, form, message):
    from ego.openscenario.xmltree import ScenarioFileError

    path = _scene(tmp_path, route_position(form))
    with pytest.raises(ScenarioFileError) as err:
        placements(load(path), _roads(tmp_path))
    assert message in str(err.value)


def test_a_story_teleport_and_a_reach_condition_at_route_positions(tmp_path):
    """At t = 1 s B (10 m/s) is teleported to pathS 260 (road 2, s = 30, beyond the junction);
    a ReachPositionCondition at pathS 270 (tolerance 1 m) holds 10 m on: at t = 1.9 s, within a
    control step or two."""
    from xosc_scenes import entity, event, run_scene, sim_time, speed, starts, trigger

    (tmp_path / "links.xodr").write_text(network(False))
    jump = route_position('<FromLaneCoordinates pathS="260" laneId="-1"/>')
    goal = route_position('<FromLaneCoordinates pathS="270" laneId="-1"/>')
    events = [
        event("Jump", "B", f"<TeleportAction><Position>{jump}</Position></TeleportAction>", trigger([sim_time(1.0)])),
        event(
            "Reached",
            "B",
            speed(10.0),
            trigger(
                [
                    entity(
                        "B",
                        f'<ReachPositionCondition tolerance="1"><Position>{goal}</Position></ReachPositionCondition>',
                    )
                ]
            ),
        ),
    ]
    path = write_file(
        tmp_path / "rp.xosc", "links.xodr", [("Ego", "1", -1, 50.0, 10.0, ""), ("B", "1", -2, 150.0, 10.0, "")], events
    )
    sc = run_scene(path, 4.0)
    assert starts(sc, "Jump") == [pytest.approx(1.0, abs=0.05)]
    assert starts(sc, "Reached") == [pytest.approx(1.9, abs=0.15)]
