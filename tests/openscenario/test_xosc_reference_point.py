"""A scripted lateral move puts the entity's reference point (its bounding box centre less the
file's ``center.x`` along its heading, as OpenSCENARIO places an entity) on the action's closed
form, measured from SUMO's own state every step: its front bumper (``getPosition``), its angle
and its length give the box, the box and ``center.x`` the reference point, projected onto the
ego's lane frame. Straight road and a 200 m arc; shapes over time, distance and a step."""

from __future__ import annotations

import math
import shutil

import pytest
from xosc_scenes import SHIPPED, event, lane_change, lane_offset, run_scene, scene, sim_time, speed, trigger

from ego.openscenario.dynamics import Transition, lateral_duration, offset_duration
from ego.openscenario.scenario import StoryDriver

CX = 1.4  #: the cars' bounding box centre ahead of their reference point (the ALKS files' 1.4 m)


def _with_center(path, road: str = ""):
    text = path.read_text().replace('<Center x="0"', f'<Center x="{CX}"')
    if road:
        shutil.copy(SHIPPED / road, path.parent / road)
        text = text.replace('filepath="straight3.xodr"', f'filepath="{road}"')
    path.write_text(text)
    return path


def _record(monkeypatch, name: str) -> list:
    """(storyboard time, d of ``name``'s reference point, its speed) from SUMO at every step."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        veh = self.sc.bridge.libsumo.vehicle
        if name in veh.getIDList():
            xf, yf = veh.getPosition(name)
            yaw = math.radians(90.0 - veh.getAngle(name))
            back = 0.5 * veh.getLength(name) + CX  # the front bumper to the reference point
            _, d, _ = self.sc.road.project(xf - back * math.cos(yaw), yf - back * math.sin(yaw))
            rows.append((self.sc.t, d, veh.getSpeed(name)))
        inner(self)

    monkeypatch.setattr(StoryDriver, "step", spy)
    return rows


CASES = [  # A (lane -1, 25 m/s) to lane -2: 3.5 m to the right, from t = 1.0
    ("linear", "time", 2.5),
    ("cubic", "time", 2.0),
    ("sinusoidal", "time", 3.0),
    ("linear", "distance", 50.0),
    ("sinusoidal", "distance", 60.0),
    ("step", "time", 0.0),
]


@pytest.mark.sumo
@pytest.mark.parametrize("shape,dim,value", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_a_lane_change_moves_the_reference_point_on_the_closed_form(tmp_path, monkeypatch, shape, dim, value):
    rows = _record(monkeypatch, "A")
    evs = [event("L", "A", lane_change(-2, shape, dim, value), trigger([sim_time(0.95)]))]
    at = {"B": (-2, 600.0, 15.0)}  # far ahead: A drives on at its speed in B's lane
    sc = run_scene(_with_center(scene(tmp_path, evs, at=at)), 5.0)
    d0 = rows[0][1]
    assert d0 == pytest.approx(sc.lane_offset[2], abs=1e-6)  # lane -1: the left one
    end = sc.lane_offset[1]
    profile = Transition(1.0, d0, end, lateral_duration(shape, dim, value, 25.0), shape)
    worst = max(abs(d - profile.value(t)) for t, d, _ in rows)
    assert worst < 1e-6, worst
    assert rows[-1][1] == pytest.approx(end, abs=1e-6)  # on the target, and held there after the end
    assert all(v == pytest.approx(25.0, abs=1e-6) for _, _, v in rows)  # its speed untouched


@pytest.mark.sumo
def test_a_lane_offset_and_a_speed_change_together(tmp_path, monkeypatch):
    """B (lane -2, 15 m/s) moves 0.8 m right (cubic, maxLateralAcc 1) while it speeds up to 20
    m/s linearly in 2 s: the reference point on the offset's closed form, SUMO's speed on the
    speed's."""
    rows = _record(monkeypatch, "B")
    evs = [
        event("O", "B", lane_offset(-0.8, "cubic", 1.0), trigger([sim_time(0.95)])),
        event("V", "B", speed(20.0, "linear", "time", 2.0), trigger([sim_time(0.95)])),
    ]
    sc = run_scene(_with_center(scene(tmp_path, evs)), 5.0)
    d0 = sc.lane_offset[1]
    lateral = Transition(1.0, d0, d0 - 0.8, offset_duration("cubic", 1.0, -0.8), "cubic")
    ramp = Transition(1.0, 15.0, 20.0, 2.0, "linear")
    assert max(abs(d - lateral.value(t)) for t, d, _ in rows) < 1e-6
    assert max(abs(v - ramp.value(t)) for t, _, v in rows) < 1e-6
    assert rows[-1][1] == pytest.approx(d0 - 0.8, abs=1e-6)


ARC_CASES = [("sinusoidal", "time", 3.0), ("cubic", "distance", 45.0), ("linear", "time", 2.0)]


@pytest.mark.sumo
@pytest.mark.parametrize("shape,dim,value", ARC_CASES, ids=[f"{c[0]}-{c[1]}" for c in ARC_CASES])
def test_a_lane_change_on_an_arc_moves_the_reference_point_on_the_closed_form(tmp_path, monkeypatch, shape, dim, value):
    """arc200.xodr: A (lane -1) starts 20 m into the 200 m arc at 15 m/s and changes into lane
    -2 inside it from t = 0.5 s: the ego lane frame's d of its reference point is the closed
    form while the action runs; after its end SUMO drives it on at its lateral place on the
    lane (its front and back on one offset of netconvert's polyline lane, which strays from
    the frame's arcs by a fraction of a millimetre, as SUMO's own cars do there)."""
    rows = _record(monkeypatch, "A")
    at = {"Ego": (-3, 20.0, 10.0), "A": (-1, 320.0, 15.0), "B": (-2, 700.0, 15.0), "C": (-3, 100.0, 10.0)}
    evs = [event("L", "A", lane_change(-2, shape, dim, value), trigger([sim_time(0.45)]))]
    sc = run_scene(_with_center(scene(tmp_path, evs, at=at), "arc200.xodr"), 4.5)
    d0 = next(d for t, d, _ in rows if t == pytest.approx(0.5))
    # SUMO's car on the arc's lane -1 (its front and back on the lane's centre), in the frame:
    # its reference point 8 mm inside the lane's centre, (L^2 / 4 - cx^2) / (2 R)
    assert d0 - sc.lane_offset[2] == pytest.approx((4.5**2 / 4 - CX**2) / (2 * 200.0), abs=1e-3)
    end = sc.lane_offset[1]
    profile = Transition(0.5, d0, end, lateral_duration(shape, dim, value, 15.0), shape)
    during = [(t, d) for t, d, _ in rows if profile.t0 - 1e-9 <= t <= profile.t0 + profile.duration + 1e-9]
    assert max(abs(d - profile.value(t)) for t, d in during) < 1e-6
    assert during[-1][1] == pytest.approx(end, abs=1e-6)  # on the target at the end
    assert max(abs(d - end) for t, d, _ in rows if t > profile.t0 + profile.duration) < 1e-3
    assert all(v == pytest.approx(15.0, abs=1e-6) for _, _, v in rows)


@pytest.mark.sumo
def test_a_lane_change_across_the_centre_line_and_back_keeps_the_reference_point_on_it(tmp_path, monkeypatch):
    """test_xosc_against_lane.py's overtaking form with cars of center.x 1.4 m: A changes into
    the oncoming lane (SUMO's car placed up to the centre line, then driven by ego as a car of
    the other direction's lanes) and back: its reference point on both sinusoidal profiles."""
    from test_xosc_against_lane import _lane_change, _scene

    rows = _record(monkeypatch, "A")
    evs = [
        event("Out", "A", _lane_change(1), trigger([sim_time(0.95)])),
        event("Back", "A", _lane_change(0), trigger([sim_time(3.95)])),
    ]
    path = _with_center(_scene(tmp_path, {"Ego": (-1, 30.0, 20.0, False), "A": (-1, 120.0, 25.0, False)}, evs))
    sc = run_scene(path, 6.5)
    assert sc.status == "completed"
    out, back = Transition(1.0, 0.0, 3.5, 2.0, "sinusoidal"), Transition(4.0, 3.5, 0.0, 2.0, "sinusoidal")
    worst = max(abs(d - (out.value(t) if t <= 4.0 else back.value(t))) for t, d, _ in rows)
    assert worst < 1e-6, worst
    assert all(v == pytest.approx(25.0, abs=1e-6) for t, _, v in rows)


@pytest.mark.sumo
def test_a_story_teleport_puts_the_reference_point_at_the_position(tmp_path, monkeypatch):
    """A TeleportAction during the run (and an AddEntityAction, which places the same way) puts
    A's reference point, not its box centre, at the LanePosition: read back from SUMO's pose the
    step it lands there, road s = 300 m and lane -2's centre within 1e-6 m."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        veh = self.sc.bridge.libsumo.vehicle
        xf, yf = veh.getPosition("A")
        yaw = math.radians(90.0 - veh.getAngle("A"))
        back = 0.5 * veh.getLength("A") + CX
        rows.append(self.sc.road.project(xf - back * math.cos(yaw), yf - back * math.sin(yaw))[:2])
        inner(self)

    monkeypatch.setattr(StoryDriver, "step", spy)
    tp = '<TeleportAction><Position><LanePosition roadId="0" laneId="-2" s="300" offset="0"/></Position></TeleportAction>'
    sc = run_scene(_with_center(scene(tmp_path, [event("Tp", "A", tp, trigger([sim_time(0.95)]))])), 2.0)
    s, d = min(rows, key=lambda r: abs(r[0] - 300.0))
    assert s == pytest.approx(300.0, abs=1e-6)
    assert d == pytest.approx(sc.lane_offset[1], abs=1e-6)
