"""Cars driving against their lane's direction, which SUMO cannot drive and ego drives itself
(ego/openscenario/kinematic.py): a car started in the oncoming lane turned round (the
reference player's ALKS cut-in form), a wrong-way driver in the ego's lane, and a car changing
lanes across the centre line into the oncoming lane and back (an overtaking form). Hand-written
files on a hand-written two-way road: lane +1 (the other direction) beside lanes -1 and -2."""

from __future__ import annotations

import pytest
from xosc_scenes import event, run_scene, sim_time, speed, trigger, write_file

from ego.openscenario.runtime import Storyboard
from ego.openscenario.xmltree import ScenarioFileError

ROAD = """<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="twoway" version="1.0"/>
  <road name="twoway" length="1000" id="1" junction="-1">
    <link/>
    <planView><geometry s="0" x="0" y="0" hdg="0" length="1000"><line/></geometry></planView>
    <lanes>
      <laneSection s="0">
        <left>
        <lane id="1" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        </left>
        <center><lane id="0" type="none" level="false"/></center>
        <right>
        <lane id="-1" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        <lane id="-2" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
        </right>
      </laneSection>
    </lanes>
  </road>
</OpenDRIVE>
"""


def _scene(tmp, starts: dict, events: list[tuple[str, str]] = ()) -> object:
    """``starts``: name -> (lane, s, speed, turned: True for a relative turn round, or the
    Orientation element itself)."""
    (tmp / "twoway.xodr").write_text(ROAD)
    turned = '<Orientation type="relative" h="3.141593"/>'
    rows = [
        (n, "1", lane, s, v, t if isinstance(t, str) else turned if t else "") for n, (lane, s, v, t) in starts.items()
    ]
    return write_file(tmp / "against.xosc", "twoway.xodr", rows, list(events))


def _record(monkeypatch, name: str) -> dict[float, tuple[float, float, float, float]]:
    """Storyboard time -> (s, d, speed, yaw) of ``name`` as the storyboard sees it."""
    rows: dict[float, tuple[float, float, float, float]] = {}
    step = Storyboard.step

    def recording(self, t):
        e = self.states[name]
        rows[round(t, 6)] = (e.s, e.d, e.speed, e.yaw)
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    return rows


def _lane_change(lanes: int, ref: str = "Ego", duration: float = 2.0) -> str:
    return (
        '<LateralAction><LaneChangeAction><LaneChangeActionDynamics dynamicsShape="sinusoidal" '
        f'value="{duration}" dynamicsDimension="time"/><LaneChangeTarget><RelativeTargetLane entityRef="{ref}" '
        f'value="{lanes}"/></LaneChangeTarget></LaneChangeAction></LateralAction>'
    )


def test_a_car_turned_round_in_the_oncoming_lane_drives_the_egos_way(tmp_path, monkeypatch):
    """T starts in lane +1 at s = 80 turned round (h = pi from its lane), 15 m/s: it drives
    the ego's way, 1.5 m a step, 3.5 m left of the ego's lane (d measured from lane -1)."""
    rows = _record(monkeypatch, "T")
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "T": (1, 80.0, 15.0, True)})
    sc = run_scene(path, 3.0)
    assert sc.status == "completed"
    s0 = rows[0.1][0]
    for k in range(1, 25):
        s, d, v, _ = rows[round(0.1 * k, 6)]
        assert s - s0 == pytest.approx(1.5 * (k - 1), abs=1e-6)
        assert d == pytest.approx(3.5, abs=1e-6)
        assert v == pytest.approx(15.0, abs=1e-9)


@pytest.mark.parametrize("form", ["absolute", "world"])
def test_a_car_given_a_world_heading_against_its_lane_is_driven_as_one_turned_round(tmp_path, monkeypatch, form):
    """T in lane +1 (whose lane heads -x) given the world heading 0 (facing +x, the road's
    way), by an absolute Orientation or a WorldPosition's h: the same run, step for step, as
    the relative turn round (h = pi from its lane) of the test above."""
    relative = _record(monkeypatch, "T")
    (tmp_path / "r").mkdir()
    run_scene(_scene(tmp_path / "r", {"Ego": (-1, 30.0, 20.0, False), "T": (1, 80.0, 15.0, True)}), 3.0)
    relative = dict(relative)  # (its recorder records the next run too)
    rows = _record(monkeypatch, "T")
    absolute = '<Orientation type="absolute" h="0"/>'
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "T": (1, 80.0, 15.0, absolute)})
    if form == "world":  # lane +1's centre at s = 80: (80, 1.75)
        text = path.read_text()
        i = text.index('<Private entityRef="T">')
        j = text.index("</Position>", i)
        path.write_text(
            text[:i] + text[i:j].split("<Position>")[0] + '<Position><WorldPosition x="80" y="1.75" h="0"/>' + text[j:]
        )
    sc = run_scene(path, 3.0)
    assert sc.status == "completed"
    assert len(rows) == len(relative) > 20
    for t, row in relative.items():
        assert rows[t] == pytest.approx(row, abs=1e-9)


def test_a_car_given_a_world_heading_along_its_lane_is_driven_by_sumo(tmp_path, monkeypatch):
    """T in lane +1 with the absolute heading pi (its lane's way): SUMO drives it, away from
    the ego's way (its s falls)."""
    rows = _record(monkeypatch, "T")
    path = _scene(
        tmp_path, {"Ego": (-1, 30.0, 20.0, False), "T": (1, 300.0, 15.0, '<Orientation type="absolute" h="3.141593"/>')}
    )
    run_scene(path, 2.0)
    assert rows[1.0][0] < rows[0.1][0] - 10.0


def test_a_car_offset_across_the_centre_line_beside_the_ego_drives_its_own_way(tmp_path, monkeypatch):
    """T starts in the ego's lane -1 at the ego's s with offset 3.5 (the reference player's
    speed-profile.xosc form: its centre in the oncoming lane, heading its own lane's way), 15 m/s:
    SUMO inserts it elsewhere on the lane (both on the lane's centre would overlap), ego drives
    it from its start, 1.5 m a step, 3.5 m left of the ego's lane."""
    rows = _record(monkeypatch, "T")
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 15.0, False), "T": (-1, 30.0, 15.0, False)})
    text = path.read_text()
    i = text.index('<Private entityRef="T">')
    path.write_text(text[:i] + text[i:].replace('offset="0"', 'offset="3.5"', 1))
    sc = run_scene(path, 3.0)
    assert sc.status == "completed"
    s0 = rows[0.1][0]
    assert s0 == pytest.approx(30.0 + 1.5, abs=1e-6)  # from its start, level with the ego
    for k in range(1, 25):
        s, d, v, _ = rows[round(0.1 * k, 6)]
        assert s - s0 == pytest.approx(1.5 * (k - 1), abs=1e-6)
        assert d == pytest.approx(3.5, abs=1e-6)


def test_a_wrong_way_driver_in_the_egos_lane_comes_towards_it(tmp_path, monkeypatch):
    """W in the ego's lane at s = 400 turned round, 10 m/s: s falls 1 m a step; a speed
    change on it is followed exactly (step to 5 m/s at t = 1 s)."""
    rows = _record(monkeypatch, "W")
    evs = [event("Slow", "W", speed(5.0), trigger([sim_time(0.95)]))]
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "W": (-1, 400.0, 10.0, True)}, evs)
    run_scene(path, 3.0)
    s1 = rows[1.0][0]
    assert rows[0.5][0] - rows[0.6][0] == pytest.approx(1.0, abs=1e-6)
    assert rows[2.0][0] == pytest.approx(s1 - 0.5 * 10, abs=1e-6)
    assert rows[2.0][1] == pytest.approx(0.0, abs=1e-6)
    assert rows[2.0][2] == pytest.approx(5.0, abs=1e-9)


def test_a_lane_change_into_the_oncoming_lane_and_back(tmp_path, monkeypatch):
    """A (ahead in the ego's lane, 25 m/s) changes to the ego's lane +1 (the oncoming lane, 3.5 m
    left) over 2 s from t = 1 s and back at t = 4 s: it follows the sinusoidal profile across the
    centre line (ego drives it once it crosses) and ends on the lanes' centres."""
    rows = _record(monkeypatch, "A")
    evs = [
        event("Out", "A", _lane_change(1), trigger([sim_time(0.95)])),
        event("Back", "A", _lane_change(0), trigger([sim_time(3.95)])),
    ]
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "A": (-1, 120.0, 25.0, False)}, evs)
    sc = run_scene(path, 6.5)
    assert sc.status == "completed"
    assert rows[3.5][1] == pytest.approx(3.5, abs=1e-6)
    assert rows[6.3][1] == pytest.approx(0.0, abs=1e-6)
    # across the centre line it drives on at its speed
    assert all(rows[round(0.1 * k, 6)][2] == pytest.approx(25.0, abs=1e-6) for k in range(25, 60))


@pytest.mark.parametrize(
    "lanes,line", [(-2, None), (-3, "a lane change -3 lanes from A's lane")], ids=["fits", "too-far"]
)
def test_a_change_right_relative_to_a_car_in_the_oncoming_lane_spans_the_whole_road(tmp_path, monkeypatch, lanes, line):
    """A changes into lane +1 (the oncoming lane) and then 2 lanes right of its own lane:
    across both of the ego's direction's lanes to lane -2 (3.5 m right of lane -1), which the
    check before the run refused (it counted only the ego's direction's lanes right of a
    reference: the reference player's light_state.xosc changes back so). 3 lanes right of any
    lane of the road's 3 is still refused before the run with the action's line."""
    rows = _record(monkeypatch, "A")
    evs = [
        event("Out", "A", _lane_change(1), trigger([sim_time(0.95)])),
        event("Back", "A", _lane_change(lanes, "A"), trigger([sim_time(3.95)])),
    ]
    path = _scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "A": (-1, 120.0, 25.0, False)}, evs)
    if line is not None:
        text = path.read_text()
        with pytest.raises(ScenarioFileError, match=line) as err:
            run_scene(path, 1.0)
        action = text.rindex("<LaneChangeAction", 0, text.index(f'value="{lanes}"'))
        assert err.value.line == text.count("\n", 0, action) + 1
        return
    sc = run_scene(path, 6.5)
    assert sc.status == "completed"
    assert rows[3.5][1] == pytest.approx(3.5, abs=1e-6)
    assert rows[6.3][1] == pytest.approx(-3.5, abs=1e-6)


def test_the_ego_turned_against_its_lane_reads_its_road_left_hand(tmp_path, monkeypatch):
    """The ego turned round in lane +1 (the reference player's left-hand traffic by heading):
    the road is read as left-hand traffic (tests/openscenario/test_xosc_left_hand.py), so the
    ego drives lane +1 along +x, and A in lane -1 (no Orientation: its right-hand lane's way,
    +x, now against SUMO's lane) is driven by ego along +x at its speed."""
    rows = _record(monkeypatch, "A")
    path = _scene(tmp_path, {"Ego": (1, 30.0, 20.0, True), "A": (-1, 120.0, 25.0, False)})
    sc = run_scene(path, 3.0)
    assert sc.status == "completed" and sc.roads.by_heading == frozenset({"1"})
    a = sc.trace.array(0)
    x, y = (a[:, sc.trace.names.index(n)] for n in ("x", "y"))
    assert x[-1] - x[0] > 55.0 and abs(y - 1.75).max() < 0.02
    assert "A" in sc.story._kin.cars
    assert rows[2.1][0] - rows[0.1][0] == pytest.approx(50.0, abs=1e-6)


@pytest.mark.parametrize("form", ["absolute", "world"])
def test_the_ego_given_a_world_heading_against_its_lane_reads_its_road_left_hand(tmp_path, form):
    """The ego in lane -1 (heading +x) given the world heading pi, by an absolute Orientation
    (the reference player's left-hand-traffic_internal.xosc form) or a WorldPosition's h: the
    road is read as left-hand traffic and the ego drives lane -1 towards -x (A, in lane +1
    without an Orientation, its right-hand lane's way: -x too)."""
    o = '<Orientation type="absolute" h="3.141593"/>'
    path = _scene(tmp_path, {"Ego": (-1, 300.0, 20.0, o), "A": (1, 120.0, 25.0, False)})
    if form == "world":
        text = path.read_text()
        i = text.index('<LanePosition roadId="1" laneId="-1" s="300.0"')
        j = text.index("</LanePosition>", i) + len("</LanePosition>")
        path.write_text(text[:i] + '<WorldPosition x="300" y="-1.75" h="3.141593"/>' + text[j:])
    sc = run_scene(path, 3.0)
    assert sc.status == "completed" and sc.roads.by_heading == frozenset({"1"})
    a = sc.trace.array(0)
    x, y = (a[:, sc.trace.names.index(n)] for n in ("x", "y"))
    assert x[0] - x[-1] > 55.0 and abs(y + 1.75).max() < 0.02


@pytest.mark.parametrize("kind", ["relative", "absolute"])
def test_a_car_turned_against_its_lane_outside_init_is_refused(tmp_path, kind):
    """Only an Init start may be turned: a TeleportAction of the story turned round on lane -1
    (a relative h = pi, or the absolute heading pi against the lane's +x, checked before the
    run) is refused with its Orientation's line; along its lane it is accepted."""
    teleport = (
        '<TeleportAction><Position><LanePosition roadId="1" laneId="-1" s="200" offset="0">\n'
        f'<Orientation type="{kind}" h="3.141593"/></LanePosition></Position></TeleportAction>'
    )
    path = _scene(
        tmp_path,
        {"Ego": (-1, 30.0, 20.0, False), "A": (-1, 120.0, 25.0, False)},
        [event("Tp", "A", teleport, trigger([sim_time(1.0)]))],
    )
    with pytest.raises(ScenarioFileError, match=r"against its lane's direction \(outside <Init>\)") as exc:
        run_scene(path, 1.0)
    assert exc.value.line == next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if "Orientation" in ln)
    path.write_text(path.read_text().replace('h="3.141593"', 'h="0.2"'))
    assert run_scene(path, 1.5).status == "completed"


@pytest.mark.parametrize("h, way", [("0", 1), ("3.141593", -1)])
def test_a_relative_start_across_the_centre_line_drives_the_way_its_world_heading_faces(tmp_path, monkeypatch, h, way):
    """esmini's cut-in_simple.xosc form: T starts 3.5 m left of the ego (in the oncoming lane),
    20 m behind, by a RelativeRoadPosition with an absolute Orientation, 15 m/s: facing +x (the
    ego's way) it drives the ego's way, facing -x (its lane's way) against it, 1.5 m a step."""
    rows = _record(monkeypatch, "T")
    path = _scene(tmp_path, {"Ego": (-1, 100.0, 15.0, False), "T": (-1, 300.0, 15.0, False)})
    text = path.read_text()
    i = text.index('<Private entityRef="T">')
    j = text.index("<LanePosition", i)
    k = text.index("</Position>", j)
    path.write_text(
        text[:j]
        + f'<RelativeRoadPosition entityRef="Ego" ds="-20" dt="3.5"><Orientation type="absolute" h="{h}"/>'
        + "</RelativeRoadPosition>"
        + text[k:]
    )
    sc = run_scene(path, 2.5)
    assert sc.status == "completed"
    s0 = rows[0.1][0]
    for k in range(1, 20):
        s, d, v, _ = rows[round(0.1 * k, 6)]
        assert s - s0 == pytest.approx(way * 1.5 * (k - 1), abs=1e-6)
        assert d == pytest.approx(3.5, abs=1e-6)
