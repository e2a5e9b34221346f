"""OpenDRIVE's s is measured along the road's reference line: a lane position (road, lane, s)
is the lane's centre on the reference line's normal at s, whatever the lane's length in SUMO
(netconvert gives every lane of an edge the mean length of their shapes, and SUMO scales its
lane positions by it). Checked against the closed form of a hand-written road: 200 m
straight along +x, then a left 90-degree arc of radius 100 m (the reference line), three
3.5 m lanes each side."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import event, sim_time, speed, trigger, write_file

from ego.lane_frame import LanePolyline
from ego.openscenario.roads import RoadMap, network_file

R = 100.0
STRAIGHT = 200.0
BEND = f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="bend" version="1.0"/>
  <road name="bend" length="{STRAIGHT + R * math.pi / 2:.9f}" id="7" junction="-1">
    <link/>
    <planView>
      <geometry s="0" x="0" y="0" hdg="0" length="{STRAIGHT}"><line/></geometry>
      <geometry s="{STRAIGHT}" x="{STRAIGHT}" y="0" hdg="0" length="{R * math.pi / 2:.9f}"><arc curvature="{1 / R}"/></geometry>
    </planView>
    <lanes><laneSection s="0">
      <left>{"".join(f'<lane id="{k}" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>' for k in (3, 2, 1))}</left>
      <center><lane id="0" type="none" level="false"/></center>
      <right>{"".join(f'<lane id="{-k}" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>' for k in (1, 2, 3))}</right>
    </laneSection></lanes>
  </road>
</OpenDRIVE>
"""


def centre(s: float, lane: int) -> tuple[float, float]:
    """The closed form: lane ``lane``'s centre (t = -/+ 1.75, 5.25, 8.75 m) at road s."""
    t = math.copysign(3.5 * (abs(lane) - 0.5), lane)
    if s <= STRAIGHT:
        return s, t
    a = (s - STRAIGHT) / R  # the arc's centre is (200, 100); a point at angle a, radius R - t
    return STRAIGHT + (R - t) * math.sin(a), R - (R - t) * math.cos(a)


@pytest.fixture
def bend(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    path = tmp_path / "bend.xodr"
    path.write_text(BEND)
    return path


def test_lane_positions_are_on_the_reference_lines_normal(bend):
    """Every lane, every 2.5 m of road s (1 m from the joint of line and arc aside, where
    netconvert's polyline has no point: within 2.3 cm there): within 1 mm of the closed form;
    road s back from the point within 1e-9 m; SUMO's lane position is the shape's arc length
    times the lane's SUMO length over its shape's length, the SUMO length being the mean of
    the edge's lanes' shapes (so the outer lane of a curve runs 1.5 % longer than SUMO says)."""
    roads = RoadMap(network_file(bend), converted=True)
    for lane_id in (-3, -2, -1, 1, 2, 3):
        worst = 0.0
        for k in range(1, 142):
            s = 2.5 * k
            if abs(s - STRAIGHT) < 1.0:
                continue
            lane, g = roads.lane_s("7", lane_id, s)
            x, y = LanePolyline(lane.shape).offset_point(g, 0.0)
            worst = max(worst, math.dist((x, y), centre(s, lane_id)))
            assert roads.road_s(lane, g) == pytest.approx(s, abs=1e-9)
            pos = roads.lane_position("7", lane_id, s)[1]
            assert pos == pytest.approx(g * lane.length / roads.shape_length(lane), abs=1e-6)
            assert roads.from_sumo(lane, pos) == pytest.approx(g, abs=1e-6)
        assert worst < 1e-3, (lane_id, worst)
    for edge in roads.edges.values():
        shapes = [roads.shape_length(ln) for ln in edge.lanes]
        mean = sum(shapes) / 3
        assert all(ln.length == pytest.approx(mean, abs=1e-5) for ln in edge.lanes)
        outer = edge.lanes[0]  # the right lane of either direction: the outer one on -7
        if edge.id == "-7":
            assert roads.shape_length(outer) / outer.length == pytest.approx(
                (STRAIGHT + (R + 8.75) * math.pi / 2) / (STRAIGHT + (R + 5.25) * math.pi / 2), abs=1e-4
            )


def test_a_file_places_cars_at_road_s_on_inner_and_outer_lanes(bend):
    """A file run: cars at LanePosition s = 260 m (in the arc) on the inner (-1) and outer (-3)
    lane stand where the closed form puts them (SUMO's front bumper 2.25 m ahead along the lane
    within 1 mm), and the storyboard (its distance and position conditions) sees them at road
    s 260 m (within 2 mm), measured along the reference line, not along the ego's lane (263.16 m
    there: the arc is 5 % longer in the middle lane)."""
    path = write_file(
        bend.parent / "bend.xosc",
        "bend.xodr",
        [("Ego", "7", -2, 150.0, 0.0, ""), ("A", "7", -1, 260.0, 0.0, ""), ("B", "7", -3, 260.0, 0.0, "")],
        [event("Hold", "A", speed(0.0), trigger([sim_time(0.0)]))],
    )
    from ego.runner import RunSpec, build

    sc = build(RunSpec(str(path), "pid", overrides={"duration": 1.0}))
    fronts: dict[str, tuple[float, float]] = {}
    after = sc.after_sim_step

    def spy() -> None:  # SUMO's front bumpers after its first step
        after()
        if not fronts:
            fronts.update({n: sc.bridge.libsumo.vehicle.getPosition(n) for n in ("A", "B")})

    sc.after_sim_step = spy
    sc.run()
    states = sc.board.states
    for name, lane in (("A", -1), ("B", -3)):
        # the front 2.25 m ahead along the lane, on its circle of radius R - t
        ahead = 2.25 * R / (R - math.copysign(3.5 * (abs(lane) - 0.5), lane))
        assert math.dist(fronts[name], centre(260.0 + ahead, lane)) < 1e-3, (name, fronts[name])
        # the box centre: SUMO's front less half the length along SUMO's heading (a chord to
        # its back, 4.5 m of SUMO's lane position behind): within 2 mm of the arc's point
        assert states[name].s == pytest.approx(260.0, abs=2e-3)
        # the ego's lane (-2, radius 105.25 m) measures the same point 263.16 m along it
        lane_s = sc.road.project(states[name].x, states[name].y)[0]
        assert lane_s == pytest.approx(STRAIGHT + 60.0 * (R + 5.25) / R, abs=2e-3)
    ego = states["Ego"]  # on the straight: road s and the lane's s are one
    assert ego.s == sc.road.project(ego.x, ego.y)[0]


def test_road_and_relative_positions_in_init_are_at_road_s(bend):
    """Init's road position (s, t) and a relative lane position (ds along the reference line,
    another lane) start where the closed form puts them: on their lane's centre line within
    1 mm."""
    from ego.openscenario import model as M
    from ego.openscenario.scenario import _place

    roads = RoadMap(network_file(bend), converted=True)

    def world(placed) -> tuple[float, float]:
        lane, g, off = placed
        return LanePolyline(lane.shape).offset_point(g, off)

    # t = -6.5 m: lane -2 (its centre t = -5.25 m), 1.25 m to the right of it
    lane, g, off = placed = _place(M.RoadPosition("7", 260.0, -6.5, 1), roads, {})
    assert roads.lane_id_of(lane) == -2 and off == pytest.approx(-1.25, abs=1e-9)
    t = -6.5
    a = (260.0 - STRAIGHT) / R
    # off the centre line ego's lane frame moves across a chord's normal, not the arc's (its
    # 0.5 m chords here turn 2.4 mrad: up to 3 mm at 1.25 m)
    assert math.dist(world(placed), (STRAIGHT + (R - t) * math.sin(a), R - (R - t) * math.cos(a))) < 4e-3
    assert math.dist(world((lane, g, 0.0)), centre(260.0, -2)) < 1e-3
    # 30 m of road s on from A (lane -1 at s = 250), one lane to the right: lane -2 at s = 280
    start = _place(M.LanePosition("7", -1, 250.0, 0.0, 1), roads, {})
    rel = _place(M.RelativeLanePosition("A", -1, 30.0, 0.0, 1), roads, {"A": start})
    assert roads.lane_id_of(rel[0]) == -2
    assert math.dist(world(rel), centre(280.0, -2)) < 1e-3
