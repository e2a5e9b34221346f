"""Left-hand traffic: a road with ``rule="LHT"`` (its lanes +k driven along the reference
line), and a right-hand road whose ego is headed against its lane (the reference player's
"left-hand traffic by heading"). netconvert converts every road right-hand; ego turns the
road's edges round (``roads.left_hand``) and runs the file on them with the real netconvert
and SUMO. A hand-written straight road along +x: lanes +2, +1 left of the reference line
(centres y = 5.25, 1.75), -1, -2 right of it (y = -1.75, -5.25), every lane 3.5 m wide.

The scene is the reference player's left-hand cut-in (``left-hand-traffic_*.xosc``): the ego
in the kerb lane +2, the overtaker passing it on the right in lane +1 and cutting in to the
left in front of it, a third car in lane -1 driving the other way."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from test_xosc_against_lane import ROAD as TWOWAY
from xosc_scenes import event, run_scene, sim_time, trigger, write_file

from ego.openscenario.roads import RoadMap, network_file
from ego.openscenario.runtime import Storyboard
from ego.openscenario.xmltree import ScenarioFileError

#: test_xosc_against_lane.py's two-way road with a second left lane and a ``{rule}`` slot
ROAD = TWOWAY.replace(
    '<road name="twoway" length="1000" id="1" junction="-1">',
    '<road name="lht" length="1000" id="1" junction="-1"{rule}>',
).replace(
    "<left>\n",
    '<left>\n        <lane id="2" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>\n',
)
CENTRE = {2: 5.25, 1: 1.75, -1: -1.75, -2: -5.25}
LHT = ' rule="LHT"'
TURNED = '<Orientation type="relative" h="3.141593"/>'


def _road(tmp: Path, rule: str = LHT) -> Path:
    path = tmp / "lht.xodr"
    path.write_text(ROAD.format(rule=rule))
    return path


def _cut_in(value: int = 1, absolute: int | None = None) -> str:
    target = (
        f'<AbsoluteTargetLane value="{absolute}"/>'
        if absolute is not None
        else f'<RelativeTargetLane entityRef="O" value="{value}"/>'
    )
    return (
        '<LateralAction><LaneChangeAction><LaneChangeActionDynamics dynamicsShape="sinusoidal" value="2" '
        f'dynamicsDimension="time"/><LaneChangeTarget>{target}</LaneChangeTarget></LaneChangeAction></LateralAction>'
    )


def _scene(tmp: Path, rule: str = LHT, orient: str = "", cut_in: str | None = None) -> Path:
    """The ego in lane +2 at s = 50, 20 m/s; O in lane +1 at s = 20, 30 m/s, changing lanes at
    t = 4 s (``cut_in``, default one lane to its left in 2 s); C in lane -1 at s = 600, 15 m/s.
    ``orient`` is the Orientation of the ego's and O's starts."""
    _road(tmp, rule)
    starts = [("Ego", "1", 2, 50.0, 20.0, orient), ("O", "1", 1, 20.0, 30.0, orient), ("C", "1", -1, 600.0, 15.0, "")]
    events = [event("CutIn", "O", cut_in or _cut_in(), trigger([sim_time(4.0)]))]
    return write_file(tmp / "lht.xosc", "lht.xodr", starts, events)


def _record(monkeypatch) -> dict[str, list[tuple[float, float, float, float]]]:
    """Entity -> (t, x, y, yaw) of its box centre at every storyboard step."""
    rows: dict[str, list[tuple[float, float, float, float]]] = {}
    step = Storyboard.step

    def recording(self, t):
        for name, e in self.states.items():
            rows.setdefault(name, []).append((t, e.x, e.y, e.yaw))
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    return rows


def test_a_left_hand_road_is_converted_with_its_edges_turned_round(tmp_path):
    """Edge ``1`` (lanes +k) runs along +x and edge ``-1`` against it; each edge's lane 0 is the
    lane next to the centre line (the rightmost in its driving direction, as SUMO's right-hand
    index order has it), and every lane lies where OpenDRIVE puts it. Lane positions and road
    s map to the same points as on the right-hand road, driven the other way."""
    roads = RoadMap(network_file(_road(tmp_path)), converted=True)
    along, against = roads.edges["1"], roads.edges["-1"]
    assert along.left_hand and against.left_hand
    assert [roads.lane_id_of(ln) for ln in along.lanes] == [1, 2]
    assert [roads.lane_id_of(ln) for ln in against.lanes] == [-1, -2]
    for ln in along.lanes:
        assert ln.shape[0] == pytest.approx((0.0, CENTRE[roads.lane_id_of(ln)]), abs=1e-6)
        assert ln.shape[-1] == pytest.approx((1000.0, CENTRE[roads.lane_id_of(ln)]), abs=1e-6)
    for ln in against.lanes:
        assert ln.shape[0] == pytest.approx((1000.0, CENTRE[roads.lane_id_of(ln)]), abs=1e-6)
    for lane, y in CENTRE.items():
        sumo_lane, g = roads.lane_s("1", lane, 100.0)
        x = g if lane > 0 else 1000.0 - g
        assert (x, sumo_lane.shape[0][1]) == pytest.approx((100.0, y), abs=1e-6)
        assert roads.road_s(sumo_lane, g) == pytest.approx(100.0, abs=1e-6)
    # a RoadPosition's t (+ left of the reference line) on lane -1, driven against s here
    lane, g, d = roads.t_position("1", 100.0, 2.0)
    assert (lane.id, g, d) == ("-1_0", pytest.approx(900.0), pytest.approx(-3.75))
    (tmp_path / "rht").mkdir()
    rht = RoadMap(network_file(_road(tmp_path / "rht", "")), converted=True)
    assert not rht.edges["1"].left_hand and rht.edges["-1"].lanes[0].shape[0] == pytest.approx((0.0, -5.25))


def _check_cut_in(sc, rows) -> None:
    """The ego holds its lane +2 along +x; O passes it on its right in lane +1 and changes one
    lane to its left (y 1.75 -> 5.25) from t = 4 s to 6 s; C drives lane -1 towards -x; every
    car at its speed, driven by SUMO (none by ego's own kinematic driver); the ego's front gap
    afterwards is O's distance along the lane less the half lengths."""
    assert sc.status == "completed", sc.events[-1].text
    assert not sc.story._kin.cars
    a = sc.trace.array(0)
    col = {n: a[:, sc.trace.names.index(n)] for n in ("t", "x", "y", "d", "gap_front")}
    assert np.all(np.diff(col["x"]) > 0.0)
    assert np.abs(col["y"] - CENTRE[2]).max() < 0.02
    assert np.abs(col["d"]).max() < 0.02
    o = {round(t, 6): (x, y, yaw) for t, x, y, yaw in rows["O"]}
    c = {round(t, 6): (x, y, yaw) for t, x, y, yaw in rows["C"]}
    for t in (1.0, 3.0):
        assert o[t][1] == pytest.approx(CENTRE[1], abs=1e-3) and math.cos(o[t][2]) > 0.999
    assert o[3.0][0] - o[1.0][0] == pytest.approx(60.0, abs=0.1)  # 30 m/s along +x
    for t in (6.5, 7.5):
        assert o[t][1] == pytest.approx(CENTRE[2], abs=1e-3)
    ys = [o[round(4.0 + 0.1 * k, 6)][1] for k in range(0, 26)]
    assert all(b >= a - 1e-9 for a, b in zip(ys, ys[1:]))  # to the left, never back
    assert c[1.0][1] == pytest.approx(CENTRE[-1], abs=1e-3) and math.cos(c[1.0][2]) < -0.999
    assert c[1.0][0] - c[3.0][0] == pytest.approx(30.0, abs=0.1)  # 15 m/s along -x
    # after the cut-in: the ego's front gap is O's rear less the ego's front along the lane
    # (both 4.5 m long; the boxes' centres as the storyboard sees them)
    e = {round(t, 6): x for t, x, _, _ in rows["Ego"]}
    for t in (6.5, 7.0, 7.5):
        i = int(np.argmin(np.abs(col["t"] - t)))
        assert col["gap_front"][i] == pytest.approx(o[t][0] - e[t] - 4.5, abs=1e-3)
    assert col["gap_front"][int(np.argmin(np.abs(col["t"] - 3.0)))] == math.inf  # O beside, not ahead


def test_the_left_hand_cut_in_runs_on_a_left_hand_road(tmp_path, monkeypatch):
    rows = _record(monkeypatch)
    sc = run_scene(_scene(tmp_path), 8.0)
    _check_cut_in(sc, rows)


def test_an_absolute_target_lane_on_a_left_hand_road_is_the_lane_of_that_id(tmp_path, monkeypatch):
    rows = _record(monkeypatch)
    sc = run_scene(_scene(tmp_path, cut_in=_cut_in(absolute=2)), 8.0)
    _check_cut_in(sc, rows)


@pytest.mark.parametrize("orient", ["relative", "absolute"])
def test_an_ego_headed_against_its_right_hand_lane_reads_its_road_left_hand(tmp_path, monkeypatch, orient):
    """The same scene on the right-hand road, the ego and O turned round in lanes +2 and +1
    (a relative h = pi, or the absolute world heading 0): the road is read as left-hand
    traffic, and the run is the one on the rule="LHT" road, step for step. C (no Orientation)
    drives its right-hand lane's way, as on the left-hand road it drives its own."""
    lht_rows = _record(monkeypatch)
    (tmp_path / "lht").mkdir()
    lht = run_scene(_scene(tmp_path / "lht"), 8.0)
    lht_rows = {k: list(v) for k, v in lht_rows.items()}
    rows = _record(monkeypatch)
    heading = TURNED if orient == "relative" else '<Orientation type="absolute" h="0"/>'
    path = _scene(tmp_path, rule="", orient=heading)
    text = path.read_text()
    i = text.index('<Private entityRef="C">')  # C: lane -1 driven against +x, as on the LHT road
    path.write_text(text[:i] + text[i:].replace('offset="0">', f'offset="0">{TURNED}', 1))
    sc = run_scene(path, 8.0)
    _check_cut_in(sc, rows)
    assert sc.roads.by_heading == frozenset({"1"})
    assert np.array_equal(sc.trace.array(0), lht.trace.array(0))
    for name in ("O", "C"):
        assert np.abs(np.array(rows[name]) - np.array(lht_rows[name])).max() < 1e-9


def test_a_left_hand_road_joined_at_a_junction_is_refused(tmp_path):
    """Turning a road round would turn its junction's connections too, which ego does not:
    one line naming the road."""
    from test_xosc_road_links import network

    road = tmp_path / "links.xodr"
    road.write_text(network(False).replace('<road name="r1"', '<road rule="LHT" name="r1"'))
    with pytest.raises(ScenarioFileError) as exc:
        network_file(road)
    assert str(exc.value) == (
        f"{road}: road '1' is left-hand traffic (rule=\"LHT\" or turned by its ego's heading) and joined to another "
        "road at a junction: not supported by ego (left-hand roads without junctions only)"
    )


def test_a_rule_neither_rht_nor_lht_is_refused(tmp_path, capsys):
    """One line naming the road's line and the allowed rules, exit 2, by ``ego run`` and
    ``ego list`` alike."""
    from ego.cli import main

    path = _scene(tmp_path, rule=' rule="XHT"')
    want = f'ego: error: {tmp_path / "lht.xodr"}:4: <road rule="XHT"> is not a traffic rule (allowed: RHT, LHT)\n'
    assert main(["run", str(path), "-c", "pid"]) == 2
    assert capsys.readouterr().err == want
    assert main(["list", str(path), "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert listing["supported"] is False and "ego: error: " + listing["error"] + "\n" == want


def test_list_and_run_agree_on_a_left_hand_road(tmp_path, capsys):
    """``ego list`` says every element supported and ``ego run`` runs the file (exit 0), on the
    left-hand road as on the right-hand one."""
    from ego.cli import main

    path = _scene(tmp_path)
    assert main(["list", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["supported"] is True
    assert main(["run", str(path), "-c", "pid", "--set", "duration=2"]) == 0
    assert "completed" in capsys.readouterr().out


def test_an_absolute_target_lane_past_a_border_lane_is_the_lane_of_that_id(tmp_path, monkeypatch):
    """A right-hand road whose lane -1 is a 0.5 m border lane (netconvert leaves it out, as
    e6mini.xodr's): A in lane -3 changes to AbsoluteTargetLane -2 and ends on lane -2's centre,
    y = -(0.5 + 1.75) m (counted from the centre line, lane -2 would be SUMO's outer lane)."""
    border = '<lane id="-1" type="border" level="false"><link/><width sOffset="0" a="0.5" b="0" c="0" d="0"/></lane>\n'
    road = ROAD.format(rule="").replace('<lane id="-2"', '<lane id="-3"').replace('<lane id="-1"', '<lane id="-2"')
    road = road.replace("<right>\n", "<right>\n        " + border)
    (tmp_path / "lht.xodr").write_text(road)
    starts = [("Ego", "1", -3, 50.0, 20.0, ""), ("A", "1", -3, 120.0, 20.0, "")]
    change = _cut_in(absolute=-2).replace('value="2" dynamicsDimension', 'value="1" dynamicsDimension')
    path = write_file(
        tmp_path / "border.xosc", "lht.xodr", starts, [event("Left", "A", change, trigger([sim_time(0.5)]))]
    )
    rows = _record(monkeypatch)
    assert run_scene(path, 3.0).status == "completed"
    a = {round(t, 6): y for t, _, y, _ in rows["A"]}
    assert a[0.3] == pytest.approx(-(0.5 + 3.5 + 1.75), abs=1e-3)
    assert a[2.5] == pytest.approx(-(0.5 + 1.75), abs=1e-3)


def test_lane_positions_on_a_curved_left_hand_road_are_opendrives(tmp_path):
    """An arc of curvature 1/200 m (left) as the reference line: each lane's point at road s
    (the reference line's point moved along its normal to the lane's centre, t = +5.25, +1.75,
    -1.75) on the turned edges is the arc's, within 1 cm (netconvert samples the arc every
    0.5 m), and its road s maps back within 1 cm."""
    from ego.lane_frame import LanePolyline

    k = 1.0 / 200.0
    road = tmp_path / "arc.xodr"
    road.write_text(ROAD.format(rule=LHT).replace("<line/>", f'<arc curvature="{k}"/>'))
    roads = RoadMap(network_file(road), converted=True)
    for lane, t in CENTRE.items():
        for s in (50.0, 300.0, 600.0):
            sumo_lane, g = roads.lane_s("1", lane, s)
            x, y = LanePolyline(sumo_lane.shape).offset_point(g, 0.0)
            want = (math.sin(k * s) / k - t * math.sin(k * s), (1 - math.cos(k * s)) / k + t * math.cos(k * s))
            assert (x, y) == pytest.approx(want, abs=0.01), (lane, s)
            assert roads.road_s(sumo_lane, g) == pytest.approx(s, abs=0.01)


def test_the_left_hand_cut_in_on_a_curved_left_hand_road(tmp_path):
    """The scene on the arc of 1/200 m from s = 0: the ego follows its lane +2 as on a
    right-hand road (its largest offset, 0.17 m at 1 s, is the start on the arc with the wheels
    straight; the ego alone in lane -1 of the right-hand arc: 0.166 m at 1 s, then within
    0.02 m as here), SUMO drives the other cars, and the cut-in ends with O ahead of the ego in
    its lane (a finite front gap)."""
    path = _scene(tmp_path)
    road = tmp_path / "lht.xodr"
    road.write_text(road.read_text().replace("<line/>", '<arc curvature="0.005"/>'))
    sc = run_scene(path, 8.0)
    assert sc.status == "completed" and not sc.story._kin.cars
    a = sc.trace.array(0)
    d, gap, t = (a[:, sc.trace.names.index(n)] for n in ("d", "gap_front", "t"))
    assert np.abs(d).max() < 0.18 and np.abs(d[t > 4.0]).max() < 0.025
    assert np.isfinite(gap[t > 6.5]).all() and np.isinf(gap[t < 3.0]).all()
