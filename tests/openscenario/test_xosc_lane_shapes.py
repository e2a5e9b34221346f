"""Lanes beside a lane that opens along a road (esmini's two_plus_one.xodr pattern), against the
OpenDRIVE geometry itself.

The road: a straight line along +x, 300 m. From s = 100 m to 150 m the reference line moves
3.5 m left (``laneOffset`` p(s) = 3 (3.5) x^2 / 50^2 - 2 (3.5) x^3 / 50^3, x = s - 100) while a
new lane -1 opens between it and the old lane (width p(s)), so the old lane, lane -2 from
s = 100 m on, stays where it was: its centre y = p - p - 1.75 = -1.75 m all along. netconvert
gives each SUMO lane one width per piece and takes the offset only at a straight line's ends:
it put lane -2 up to 1.4 m off y = -1.75 with 1.5 m steps between its pieces, and the ego
following it left its lane (esmini's two_plus_one_road.xosc: 0.38 m beyond the marking).
"""

from __future__ import annotations

import math
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
from xosc_scenes import drive_alone

from ego.openscenario.lane_shapes import ReferenceLine, exact_lane_shapes
from ego.openscenario.roads import OPTIONS, RoadMap, network_file
from ego.sumo.net import sumo_binary

W, A, B = 3.5, 100.0, 150.0
C, D = 3 * W / (B - A) ** 2, -2 * W / (B - A) ** 3


def opening(s: float) -> float:
    """p(s): the lane offset and the new lane's width (m)."""
    x = min(max(s - A, 0.0), B - A)
    return C * x * x + D * x**3


def _lane(lid: int, width: str, before: int = 0, after: int = 0) -> str:
    link = (f'<predecessor id="{before}"/>' if before else "") + (f'<successor id="{after}"/>' if after else "")
    return f'<lane id="{lid}" type="driving" level="false"><link>{link}</link>{width}</lane>'


def _width(a: float, b: float = 0.0, c: float = 0.0, d: float = 0.0) -> str:
    return f'<width sOffset="0" a="{a!r}" b="{b!r}" c="{c!r}" d="{d!r}"/>'


def two_plus_one() -> str:
    """The OpenDRIVE text (module docstring)."""
    centre = '<center><lane id="0" type="none" level="false"/></center>'
    left = f"<left>{_lane(1, _width(W))}</left>"
    right = [
        _lane(-1, _width(W), after=-2),
        _lane(-1, _width(0.0, 0.0, C, D), after=-1) + _lane(-2, _width(W), before=-1, after=-2),
        _lane(-1, _width(W), before=-1) + _lane(-2, _width(W), before=-2),
    ]
    sections = "".join(
        f'<laneSection s="{s0!r}">{left}{centre}<right>{lanes}</right></laneSection>'
        for s0, lanes in zip((0.0, A, B), right)
    )
    offsets = (
        '<laneOffset s="0" a="0" b="0" c="0" d="0"/>'
        f'<laneOffset s="{A!r}" a="0" b="0" c="{C!r}" d="{D!r}"/>'
        f'<laneOffset s="{B!r}" a="{W!r}" b="0" c="0" d="0"/>'
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenDRIVE><header revMajor="1" revMinor="5" name="2+1"/>'
        '<road name="r" length="300" id="1" junction="-1"><link/><planView>'
        '<geometry s="0" x="0" y="0" hdg="0" length="300"><line/></geometry></planView>'
        f"<lanes>{offsets}{sections}</lanes></road></OpenDRIVE>\n"
    )


def test_the_old_lane_stays_straight_and_the_new_one_opens_beside_it(tmp_path):
    """Every point of the SUMO lanes of OpenDRIVE lane -1 before s = 100 m and lane -2 after,
    and of the internal lanes between them, at y = -1.75 m within 1 mm; the new lane -1's
    centre at y = p(x) - p(x) / 2 within 1 mm."""
    road = tmp_path / "two_plus_one.xodr"
    road.write_text(two_plus_one())
    roads = RoadMap(network_file(road), converted=True)
    lane, _ = roads.lane_position("1", -1, 20.0)
    route = roads.lane_route(lane.edge, lane.index)
    pts = np.array(roads.route_points(route))
    assert pts[:, 0].max() > 290.0
    assert np.abs(pts[:, 1] + W / 2).max() < 1e-3
    new = [ln for e in roads.edges.values() for ln in e.lanes if ln.orig == "1_-1" and ln.shape[0][0] > A + 1.0]
    assert new
    for ln in new:
        for x, y in ln.shape:
            assert abs(y - (opening(x) - 0.5 * (opening(x) if x < B else W))) < 1e-3


def test_the_ego_keeps_its_lane_past_the_opening(tmp_path):
    """The ego at 20 m/s from s = 60 m drives past the opening (s = 100-150 m) on y = -1.75 m
    within 1 cm; no lane departure (before: its frame followed netconvert's steps)."""
    (tmp_path / "two_plus_one.xodr").write_text(two_plus_one())
    sc = drive_alone(tmp_path / "t.xosc", "two_plus_one.xodr", ("1", -1, 60.0, 20.0), 7.0, 8.0)
    assert "StopTrigger" in sc.events[-1].text, sc.events[-1].text
    a = sc.trace.array(0)
    x, y, d = (a[:, sc.trace.names.index(n)] for n in ("x", "y", "d"))
    assert x.max() > B + 20.0
    assert np.abs(y + W / 2).max() < 0.01
    assert np.abs(d).max() < 0.01
    assert sc.result().metrics["max_lane_departure"] == 0.0


def curved() -> str:
    """A road of line (30 m), spiral (curvature 0 to 1/80 m over 40 m), arc (40 m) and
    paramPoly3 (40 m) with a constant lane -1 and a lane -2 that widens from 3 m to 4 m over the
    road (each geometry starts where the one before ends)."""
    k = 1.0 / 80.0
    geoms = []
    ref = ReferenceLine(
        ET.fromstring(
            "<planView>"
            '<geometry s="0" x="0" y="0" hdg="0" length="30"><line/></geometry>'
            '<geometry s="30" x="30" y="0" hdg="0" length="40">'
            f'<spiral curvStart="0" curvEnd="{k!r}"/></geometry></planView>'
        )
    )
    x, y, h = ref.pose(70.0)
    geoms.append('<geometry s="0" x="0" y="0" hdg="0" length="30"><line/></geometry>')
    geoms.append(
        f'<geometry s="30" x="30" y="0" hdg="0" length="40"><spiral curvStart="0" curvEnd="{k!r}"/></geometry>'
    )
    geoms.append(f'<geometry s="70" x="{x!r}" y="{y!r}" hdg="{h!r}" length="40"><arc curvature="{k!r}"/></geometry>')
    h2 = h + 40.0 * k
    x2, y2 = x + (math.sin(h2) - math.sin(h)) / k, y - (math.cos(h2) - math.cos(h)) / k
    geoms.append(
        f'<geometry s="110" x="{x2!r}" y="{y2!r}" hdg="{h2!r}" length="40"><paramPoly3 pRange="arcLength" '
        'aU="0" bU="1" cU="0" dU="0" aV="0" bV="0" cV="0.002" dV="-0.00003"/></geometry>'
    )
    lanes = (
        '<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right>'
        f"{_lane(-1, _width(W))}{_lane(-2, _width(3.0, 1.0 / 150.0))}</right></laneSection></lanes>"
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenDRIVE><header revMajor="1" revMinor="5" name="c"/>'
        f'<road name="c" length="150" id="1" junction="-1"><link/><planView>{"".join(geoms)}</planView>'
        f"{lanes}</road></OpenDRIVE>\n"
    )


def test_the_reference_line_agrees_with_netconvert_where_its_lanes_are_right(tmp_path):
    """On a road of line, spiral, arc and paramPoly3 whose lane -2 widens, lane -1 (constant,
    next to the reference line) is where netconvert puts it: the rewritten lane's points lie
    within 5 mm of netconvert's own polyline (its 0.5 m chords of the curves), and lane -2's
    centre 3.5 + w(s) / 2 m right of the reference line."""
    road = tmp_path / "c.xodr"
    road.write_text(curved())
    exe = sumo_binary("netconvert")
    raw = tmp_path / "raw.net.xml"
    subprocess.run(
        [str(exe), "--opendrive-files", str(road), "-o", str(raw), *OPTIONS],
        check=True,
        capture_output=True,
        env={"SUMO_HOME": str(exe.parent.parent)},
    )
    before = RoadMap(raw, converted=True)
    netconvert = next(ln for e in before.edges.values() for ln in e.lanes if ln.orig == "1_-1")
    fixed = tmp_path / "fixed.net.xml"
    fixed.write_bytes(raw.read_bytes())
    assert exact_lane_shapes(road.read_bytes(), fixed)
    after = RoadMap(fixed, converted=True)
    mine = next(ln for e in after.edges.values() for ln in e.lanes if ln.orig == "1_-1")
    from ego.lane_frame import LanePolyline

    line = LanePolyline(netconvert.shape)
    assert max(abs(line.project(x, y)[1]) for x, y in mine.shape) < 0.005
    ref = ReferenceLine(ET.fromstring(road.read_text()).find("road/planView"))
    outer = next(ln for e in after.edges.values() for ln in e.lanes if ln.orig == "1_-2")
    for x, y in outer.shape:
        s = ref.s_of(x, y)
        px, py, h = ref.pose(s)
        t = (x - px) * -math.sin(h) + (y - py) * math.cos(h)
        assert abs(t + W + 0.5 * (3.0 + s / 150.0)) < 1e-3
