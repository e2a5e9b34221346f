"""Entities on lanes netconvert drops (border, shoulder, sidewalk: the reference player's
``full_e6mini.xosc`` puts a car on every lane of ``e6mini.xodr``, border lanes included).

A hand-written road: road 1 (600 m along +x) with lanes -1, -2 driving (3.5 m), -3 border
(0.5 m), -4 shoulder (2.5 m), -5 sidewalk (2 m) on the right and 1 driving (3.5 m), 2 shoulder
(1.5 m), 3 sidewalk (2 m) on the left; road 2 the same lanes 100 m to the left, unconnected.
netconvert keeps the driving lanes; the others are found on the road converted with every
lane (``--opendrive.import-all-lanes``), their centres from the widths above."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from xosc_scenes import event, sim_time, trigger, write_file

from ego.cli import main
from ego.openscenario.loader import load
from ego.openscenario.roads import RoadMap, network_file
from ego.openscenario.runtime import Storyboard
from ego.openscenario.scenario import ego_choice, road_map
from ego.runner import RunSpec, build

WIDTHS = {-1: 3.5, -2: 3.5, -3: 0.5, -4: 2.5, -5: 2.0, 1: 3.5, 2: 1.5, 3: 2.0}
KINDS = {-1: "driving", -2: "driving", -3: "border", -4: "shoulder", -5: "sidewalk"}
KINDS.update({1: "driving", 2: "shoulder", 3: "sidewalk"})


def _lanes(ids) -> str:
    return "".join(
        f'<lane id="{k}" type="{KINDS[k]}" level="false"><link/><width sOffset="0" a="{WIDTHS[k]}" b="0" c="0" d="0"/>'
        "</lane>"
        for k in ids
    )


def _road(rid: int, y: float) -> str:
    return f"""<road name="r{rid}" length="600" id="{rid}" junction="-1"><link/>
    <planView><geometry s="0" x="0" y="{y}" hdg="0" length="600"><line/></geometry></planView>
    <lanes><laneSection s="0"><left>{_lanes((3, 2, 1))}</left>
    <center><lane id="0" type="none" level="false"/></center>
    <right>{_lanes((-1, -2, -3, -4, -5))}</right></laneSection></lanes></road>"""


#: road 3: a sidewalk on the left only (its side has no lane of the network), y = 200
ROAD3 = """<road name="r3" length="600" id="3" junction="-1"><link/>
    <planView><geometry s="0" x="0" y="200" hdg="0" length="600"><line/></geometry></planView>
    <lanes><laneSection s="0"><left><lane id="1" type="sidewalk" level="false"><link/>
    <width sOffset="0" a="2" b="0" c="0" d="0"/></lane></left>
    <center><lane id="0" type="none" level="false"/></center><right>{}</right></laneSection></lanes></road>
    <road name="r4" length="600" id="4" junction="-1"><link/>
    <planView><geometry s="0" x="0" y="300" hdg="0" length="600"><line/></geometry></planView>
    <lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right>
    <lane id="-1" type="sidewalk" level="false"><link/><width sOffset="0" a="2" b="0" c="0" d="0"/></lane>
    </right></laneSection></lanes></road>"""

ROAD = f"""<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE><header revMajor="1" revMinor="6" name="lanes" version="1.0"/>
{_road(1, 0.0)}
{_road(2, 100.0)}
{ROAD3.format(_lanes((-1,)))}
</OpenDRIVE>
"""

CAR = (
    '<Vehicle name="car" vehicleCategory="car"><BoundingBox><Center x="0" y="0" z="0.75"/>'
    '<Dimensions width="1.8" length="4.5" height="1.5"/></BoundingBox>'
    '<Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/></Vehicle>'
)
WALKER = (
    '<Pedestrian name="walker" mass="80" pedestrianCategory="pedestrian" model3d="Adult"><BoundingBox>'
    '<Center x="0" y="0" z="0.9"/><Dimensions width="0.5" length="0.3" height="1.8"/></BoundingBox>'
    "<Properties/></Pedestrian>"
)


def centre(lane: int) -> float:
    """y of ``lane``'s centre on road 1 (the reference line is y = 0): from the widths."""
    side = -1 if lane < 0 else 1
    inner = sum(WIDTHS[side * k] for k in range(1, abs(lane)))
    return side * (inner + 0.5 * WIDTHS[lane])


def write(tmp: Path, starts: list[tuple], name: str = "lanes.xosc", events=()) -> Path:
    """A file with one entity per start (name, body, road, lane, s, speed, offset) and ``events``."""
    (tmp / "lanes.xodr").write_text(ROAD)
    rows = [(n, str(r), lane, s, v, "") for n, _, r, lane, s, v, _ in starts]
    bodies = {n: body for n, body, *_ in starts}
    offsets = {n: off for n, *_, off in starts}
    return write_file(tmp / name, "lanes.xodr", rows, list(events), bodies, offsets)


def refusal(path: Path, capsys, marker: str) -> tuple[str, int]:
    """``ego run``'s one error line for ``path`` (exit 2) and the line of ``marker`` in it."""
    assert main(["run", str(path), "-c", "pid"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err, next(i for i, t in enumerate(path.read_text().splitlines(), 1) if marker in t)


def test_a_dropped_lane_is_the_nearest_lane_of_the_network_with_the_offset_of_its_centre(tmp_path):
    (tmp_path / "lanes.xodr").write_text(ROAD)
    road = tmp_path / "lanes.xodr"
    roads = RoadMap(network_file(road), True, road)
    kept = {roads.lane_id_of(ln) for e in roads.edges.values() for ln in e.lanes}
    assert kept == {-1, -2, 1}  # netconvert's network: the driving lanes only
    assert roads.lane_s_offset("1", -2, 100.0)[2] == 0.0
    assert roads._every is None  # a lane of the network: the road is not converted again
    for lane, near in ((-3, -2), (-4, -2), (-5, -2), (2, 1), (3, 1)):
        sumo_lane, g, d = roads.lane_s_offset("1", lane, 100.0)
        assert roads.lane_id_of(sumo_lane) == near
        # + left of the lane's driving direction: the right lanes drive +x (left is +y), the left -x
        expected = centre(lane) - centre(near)
        assert d == pytest.approx(expected if lane < 0 else -expected, abs=1e-5)
        x, y = roads.lane_position("1", lane, 100.0)[0].shape[0]
        assert y == pytest.approx(centre(near), abs=1e-5)  # the lane of the network itself
        assert g == pytest.approx(100.0 if lane < 0 else 500.0, abs=1e-6)
    every = roads.every_lane_map()
    assert every is not None
    assert {every.lane_id_of(ln) for e in every.edges.values() for ln in e.lanes} == set(WIDTHS)
    assert {every.lane_id_of(ln): ln.kind for ln in every.edges["-1"].lanes} == {k: KINDS[k] for k in KINDS if k < 0}
    # the lanes of the network are the same on both conversions
    for e in roads.edges:
        for ln in roads.edges[e].lanes:
            twin = next(t for t in every.edges[e].lanes if t.orig == ln.orig)
            assert max(math.dist(p, q) for p, q in zip(ln.shape, twin.shape, strict=True)) < 1e-5
    with pytest.raises(ValueError, match=r"has no lane -6 on that side at s = 100 \(lane ids -1, -2, -3, -4, -5, of"):
        roads.lane_s_offset("1", -6, 100.0)
    # a side with no lane of the network: the other side's nearest (road 3's sidewalk 1 is
    # 1 + 1.75 m left of its lane -1's centre); a road with none at all is refused
    sumo_lane, _, d = roads.lane_s_offset("3", 1, 100.0)
    assert roads.lane_id_of(sumo_lane) == -1 and d == pytest.approx(2.75, abs=1e-5)
    with pytest.raises(ValueError, match=r"road '4' has no lane netconvert makes \(lane -1 is a sidewalk lane\)"):
        roads.lane_s_offset("4", -1, 100.0)


def test_the_ego_is_not_a_vehicle_on_a_dropped_lane(tmp_path):
    path = write(
        tmp_path,
        [("OnShoulder", CAR, 1, -4, 50.0, 10.0, 0), ("Driver", CAR, 1, -1, 30.0, 20.0, 0)],
    )
    model = load(str(path))
    name, why = ego_choice(model, "", road_map(model))
    assert name == "Driver"
    assert "OnShoulder starts on a lane netconvert does not make" in why
    # named, it is refused in one line at its position's line
    rc = main(["run", str(path), "-c", "pid", "--ego", "OnShoulder"])
    assert rc == 2


def test_the_ego_on_a_dropped_lane_and_an_entity_on_one_away_from_its_road_are_refused(tmp_path, capsys):
    path = write(tmp_path, [("Ego", CAR, 1, -4, 50.0, 10.0, 0)])
    err, line = refusal(path, capsys, 'laneId="-4"')
    assert err == (
        f"ego: error: {path}:{line}: the ego 'Ego' starts on lane -4 of road '1', a shoulder lane netconvert does not "
        "make: the ego drives the lanes of the road network (driving and stop lanes; choose another with --ego, see "
        "docs/openscenario.md)\n"
    )
    path = write(tmp_path, [("Ego", CAR, 1, -1, 50.0, 10.0, 0), ("Far", CAR, 2, -5, 50.0, 0.0, 0)])
    err, _ = refusal(path, capsys, "Far")
    assert "Far starts on lane -5 of road '2', a sidewalk lane netconvert does not make away from the ego's road" in err


def _record(monkeypatch, names) -> dict[str, list[tuple[float, float, float, float]]]:
    """Storyboard time -> (t, x, y, speed) of each of ``names`` as the storyboard sees it."""
    rows: dict[str, list[tuple[float, float, float, float]]] = {n: [] for n in names}
    step = Storyboard.step

    def recording(self, t):
        for n in names:
            e = self.states[n]
            rows[n].append((round(t, 6), e.x, e.y, e.speed))
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    return rows


def test_entities_on_dropped_lanes_keep_their_lane_and_are_seen(tmp_path, monkeypatch):
    """A car on the shoulder at 10 m/s, a walker on the sidewalk at 1.5 m/s, a car parked on
    the left sidewalk: each at its lane's centre (the widths) and its s moving at its speed
    exactly; the sensor's rows have them; the ego's lane frame is the two driving lanes."""
    rows = _record(monkeypatch, ("S", "W", "K"))
    path = write(
        tmp_path,
        [
            ("Ego", CAR, 1, -1, 30.0, 20.0, 0),
            ("S", CAR, 1, -4, 100.0, 10.0, 0),
            ("W", WALKER, 1, -5, 150.0, 1.5, 0),
            ("K", CAR, 1, 3, 160.0, 0.0, 0.5),
        ],
    )
    sc = build(RunSpec(str(path), "pid", overrides={"duration": 3.0}))
    sc.run()
    assert sc.status == "completed", sc.events[-1].text
    for name, lane, s0, v, off in (("S", -4, 100.0, 10.0, 0.0), ("W", -5, 150.0, 1.5, 0.0), ("K", 3, 160.0, 0.0, 0.5)):
        # road s is x (the reference line runs along +x); K's offset 0.5 m left of its lane's
        # direction (a left lane drives -x) is towards -y
        y0 = centre(lane) - off if lane > 0 else centre(lane) + off
        assert rows[name][0][1] == pytest.approx(s0, abs=1e-6)
        for t, x, y, speed in rows[name][1:]:
            assert y == pytest.approx(y0, abs=1e-6), (name, t)
            assert x == pytest.approx(s0 + v * t, abs=1e-6), (name, t)
            assert speed == pytest.approx(v, abs=1e-9)
    ids, _ = sc.view.around
    assert {"S", "W", "K"} <= set(ids)
    assert sorted(sc.lane_offset) == [0, 1] and sc.view.lane_offset == sc.lane_offset


def test_a_car_parked_on_the_border_reaching_into_the_egos_lane_is_hit(tmp_path):
    """The border lane -3 (0.5 m) beside the ego's lane -2: a 1.8 m car parked there 0.5 m
    towards the ego (its outline from 0.1 m to 1.9 m right of the ego's lane centre... into
    the ego's 1.8 m): the sensor sees it in the ego's path (the trigger and AEB name it, and the
    ego stops short); with AEB and evasion off the coasting ego (controller none) runs into it."""
    path = write(tmp_path, [("Ego", CAR, 1, -2, 30.0, 10.0, 0), ("P", CAR, 1, -3, 80.0, 0.0, 0.5)])
    sc = build(RunSpec(str(path), "none", overrides={"duration": 10.0}))
    sc.run()
    assert sc.status == "completed"
    assert any(e.kind == "aeb" and "front P" in e.text for e in sc.events)
    sc = build(RunSpec(str(path), "none", overrides={"duration": 10.0, "aeb": False, "evade": False}))
    sc.run()
    assert sc.status == "collision", sc.events[-1].text
    hit = next(e.text for e in sc.events if e.kind == "collision")
    assert "P" in hit and "outlines overlap" in hit


def test_a_teleport_onto_a_dropped_lane_outside_init_is_refused(tmp_path, capsys):
    teleport = (
        '<TeleportAction><Position><LanePosition roadId="1" laneId="-4" s="200" offset="0"/></Position>'
        "</TeleportAction>"
    )
    starts = [("A", CAR, 1, -2, 50.0, 10.0, 0), ("Ego", CAR, 1, -1, 50.0, 10.0, 0)]
    path = write(tmp_path, starts, events=[event("T", "A", teleport, trigger([sim_time(1.0)]))])
    err, line = refusal(path, capsys, 's="200"')
    assert err == (
        f"ego: error: {path}:{line}: a TeleportAction onto lane -4 of road '1', a lane netconvert does not make, "
        "outside <Init> is not supported by ego: an entity is on such a lane from its Init start only (see "
        "docs/openscenario.md)\n"
    )
