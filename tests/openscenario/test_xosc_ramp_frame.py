"""The ego's lane frame on a curved on-ramp that merges through a direct junction, the pattern
of esmini's highway_merge.xosc on soderleden.xodr: a hand-written OpenDRIVE network of a
one-lane ramp (road 1: 20 m straight, then an arc of radius 40 m turning right), its plain
successor road 5 (straight) and direct junction 9 joining road 5's lane into the right lane of
a three-lane road 3, beside a two-lane motorway (road 2) running on into road 3's left lanes.
netconvert turns the direct junction into a common one (1 cm connecting roads); the ego's frame
joins the ramp's lanes, the junction's internal lane and road 3's right lane into one centre
line, which has to lie on the OpenDRIVE lane centre (the arc's radius 40 - 1.75 m) and which
SUMO and the ego drive along.

highway_merge.xosc's ego leaves its lane there because the file asks 25 m/s on a ramp whose
tightest bend has a radius of 36 m (17 m/s² against the tyres' 0.7 g), not because of the
frame: the frame is exact (this test), and at a speed the bend allows the ego keeps its lane."""

from __future__ import annotations

import math

import numpy as np
from xosc_scenes import drive_alone

from ego.openscenario.roads import RoadMap, network_file

W, L1, R, LA, L5, L2, L3 = 3.5, 20.0, 40.0, 30.0, 40.0, 150.0, 200.0
K = -1.0 / R  # the ramp's arc turns right


def _lanes(n: int) -> str:
    lanes = "".join(
        f'<lane id="-{k}" type="driving" level="false"><width sOffset="0" a="{W}" b="0" c="0" d="0"/></lane>'
        for k in range(1, n + 1)
    )
    return (
        '<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center>'
        f"<right>{lanes}</right></laneSection></lanes>"
    )


def _geometry(s: float, x: float, y: float, h: float, length: float, shape: str) -> str:
    return f'<geometry s="{s!r}" x="{x!r}" y="{y!r}" hdg="{h!r}" length="{length!r}">{shape}</geometry>'


def _road(rid: int, length: float, link: str, geometries: str, n: int) -> str:
    return (
        f'<road name="r{rid}" length="{length!r}" id="{rid}" junction="-1"><link>{link}</link>'
        f"<planView>{geometries}</planView>{_lanes(n)}</road>"
    )


def _ramp_end() -> tuple[float, float, float]:
    """Road 5's start: the end of road 1's arc (x, y, heading)."""
    return L1 + math.sin(K * LA) / K, (1.0 - math.cos(K * LA)) / K, K * LA


def network() -> str:
    """The OpenDRIVE text (module docstring)."""
    x5, y5, h = _ramp_end()
    c, s = math.cos(h), math.sin(h)
    # road 3's reference line 7 m left of road 5's: its lane -3 centre continues road 5's lane -1
    x3, y3 = x5 + L5 * c - 2 * W * s, y5 + L5 * s + 2 * W * c
    roads = [
        _road(
            1,
            L1 + LA,
            '<successor elementType="road" elementId="5" contactPoint="start"/>',
            _geometry(0.0, 0.0, 0.0, 0.0, L1, "<line/>") + _geometry(L1, L1, 0.0, 0.0, LA, f'<arc curvature="{K!r}"/>'),
            1,
        ),
        _road(
            5,
            L5,
            '<predecessor elementType="road" elementId="1" contactPoint="end"/>'
            '<successor elementType="junction" elementId="9"/>',
            _geometry(0.0, x5, y5, h, L5, "<line/>"),
            1,
        ),
        _road(
            2,
            L2,
            '<successor elementType="junction" elementId="9"/>',
            _geometry(0.0, x3 - L2 * c, y3 - L2 * s, h, L2, "<line/>"),
            2,
        ),
        _road(
            3, L3, '<predecessor elementType="junction" elementId="9"/>', _geometry(0.0, x3, y3, h, L3, "<line/>"), 3
        ),
    ]
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenDRIVE><header revMajor="1" revMinor="7" name="ramp"/>\n'
        + "\n".join(roads)
        + '\n<junction name="" id="9" type="direct">'
        '<connection id="0" incomingRoad="2" linkedRoad="3" contactPoint="start">'
        '<laneLink from="-1" to="-1"/><laneLink from="-2" to="-2"/></connection>'
        '<connection id="1" incomingRoad="5" linkedRoad="3" contactPoint="start">'
        '<laneLink from="-1" to="-3"/></connection></junction>\n</OpenDRIVE>\n'
    )


def centre_line(step: float = 0.5) -> np.ndarray:
    """The ego's lane centre from the OpenDRIVE geometry itself: 1.75 m right of road 1's
    reference line (straight, then the arc), on along road 5 and road 3's lane -3."""
    pts = [(x, -W / 2) for x in np.arange(0.0, L1, step)]
    for a in np.arange(0.0, LA, step):
        h = K * a  # the arc's point at a, moved W/2 along its right normal (sin h, -cos h)
        pts.append((L1 + math.sin(h) / K + (W / 2) * math.sin(h), (1.0 - math.cos(h)) / K - (W / 2) * math.cos(h)))
    x5, y5, h = _ramp_end()
    c, s = math.cos(h), math.sin(h)
    for a in np.linspace(0.0, L5 + L3, round((L5 + L3) / step) + 1):
        pts.append((x5 + a * c + (W / 2) * s, y5 + a * s - (W / 2) * c))
    return np.array(pts)


def _distance(p: np.ndarray, line: np.ndarray) -> float:
    a, b = line[:-1], line[1:]
    ab = b - a
    t = np.clip(((p - a) * ab).sum(1) / (ab * ab).sum(1), 0.0, 1.0)
    return float(np.hypot(*(a + t[:, None] * ab - p).T).min())


def test_the_frame_lies_on_the_lane_centre_across_the_direct_junction(tmp_path):
    """The ego's route from the ramp is road 1, road 5 and road 3's right lane, and its frame
    lies on the OpenDRIVE lane centre within 1 cm (netconvert's chords on the arc) all along."""
    road = tmp_path / "ramp.xodr"
    road.write_text(network())
    roads = RoadMap(network_file(road), converted=True)
    lane, _ = roads.lane_position("1", -1, 5.0)
    route = roads.lane_route(lane.edge, lane.index)
    assert [(e, i) for e, i, _ in route] == [("-1", 0), ("-5", 0), ("-3", 0)]
    frame = np.array(roads.route_points(roads.beside(route, 0)))
    truth = centre_line()
    assert max(_distance(p, truth) for p in frame) < 0.01
    assert max(_distance(p, frame) for p in truth) < 0.01


def test_the_ego_keeps_its_lane_round_the_ramp_into_the_merge(tmp_path):
    """At 12 m/s (3.8 m/s² on the arc's 38.25 m lane centre, well inside 0.7 g) the pid keeps
    the ego within 0.5 m of its lane centre from the ramp through the direct junction onto
    road 3; the run goes to its StopTrigger, the ego 120 m on, on road 3."""
    (tmp_path / "ramp.xodr").write_text(network())
    sc = drive_alone(tmp_path / "ramp.xosc", "ramp.xodr", ("1", -1, 5.0, 12.0), 10.0, 15.0)
    assert "StopTrigger" in sc.events[-1].text, sc.events[-1].text
    a = sc.trace.array(0)
    x, y, s, d = (a[:, sc.trace.names.index(n)] for n in ("x", "y", "s", "d"))
    assert np.abs(d).max() < 0.5
    assert s.max() > L1 + LA + L5
    truth = centre_line()
    assert _distance(np.array([x[-1], y[-1]]), truth) < 0.5  # on road 3's right lane, as the frame says
