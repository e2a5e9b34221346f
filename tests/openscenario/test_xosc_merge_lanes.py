"""The ego's lanes after an on-ramp has merged (esmini's highway_merge_advanced.xosc on
soderleden.xodr: the ego on a one-lane ramp joins a motorway's right lane, which ends 100 m on,
and the file then changes it to lane -2).

The road: a one-lane ramp (road 1, lane -1 centre y = -8.75 m) and a two-lane motorway (road 2,
reference line y = 0) along +x for 150 m, joined by direct junction 9 into road 3 (three lanes
from x = 150 m: -1, -2 from the motorway, -3 from the ramp), whose lane -3 ends 100 m on (its
second lane section has lanes -1 and -2). Lane -2's centre: y = -5.25 m.

Before, the ego's lane frame held its start road's lanes only: the lane change to lane -2 was
skipped ("lane -2 does not exist on the ego's road (1 lanes)") and the run ended where lane -3
ends ("the end of its route")."""

from __future__ import annotations

import numpy as np
from xosc_scenes import event, lane_change, run_scene, sim_time, trigger, write_file

W = 3.5


def _lanes(sections: list[tuple[float, list[tuple[int, int, int]]]]) -> str:
    """Lane sections: (s, [(lane id, predecessor id or 0, successor id or 0)])."""
    out = []
    for s0, lanes in sections:
        right = "".join(
            f'<lane id="{lid}" type="driving" level="false"><link>'
            + (f'<predecessor id="{p}"/>' if p else "")
            + (f'<successor id="{q}"/>' if q else "")
            + f'</link><width sOffset="0" a="{W}" b="0" c="0" d="0"/></lane>'
            for lid, p, q in lanes
        )
        out.append(
            f'<laneSection s="{s0!r}"><center><lane id="0" type="none" level="false"/></center>'
            f"<right>{right}</right></laneSection>"
        )
    return "<lanes>" + "".join(out) + "</lanes>"


def _road(rid: int, length: float, x: float, y: float, link: str, lanes: str) -> str:
    return (
        f'<road name="r{rid}" length="{length!r}" id="{rid}" junction="-1"><link>{link}</link><planView>'
        f'<geometry s="0" x="{x!r}" y="{y!r}" hdg="0" length="{length!r}"><line/></geometry></planView>{lanes}</road>'
    )


def merge() -> str:
    """The OpenDRIVE text (module docstring)."""
    to_junction = '<successor elementType="junction" elementId="9"/>'
    roads = [
        _road(1, 150.0, 0.0, -7.0, to_junction, _lanes([(0.0, [(-1, 0, 0)])])),
        _road(2, 150.0, 0.0, 0.0, to_junction, _lanes([(0.0, [(-1, 0, 0), (-2, 0, 0)])])),
        _road(
            3,
            400.0,
            150.0,
            0.0,
            '<predecessor elementType="junction" elementId="9"/>',
            _lanes([(0.0, [(-1, 0, -1), (-2, 0, -2), (-3, 0, 0)]), (100.0, [(-1, -1, 0), (-2, -2, 0)])]),
        ),
    ]
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n<OpenDRIVE><header revMajor="1" revMinor="7" name="merge"/>\n'
        + "\n".join(roads)
        + '\n<junction name="" id="9" type="direct">'
        '<connection id="0" incomingRoad="2" linkedRoad="3" contactPoint="start">'
        '<laneLink from="-1" to="-1"/><laneLink from="-2" to="-2"/></connection>'
        '<connection id="1" incomingRoad="1" linkedRoad="3" contactPoint="start">'
        '<laneLink from="-1" to="-3"/></connection></junction>\n</OpenDRIVE>\n'
    )


def test_the_ego_changes_into_a_lane_that_begins_after_the_merge(tmp_path):
    """From the ramp at s = 20 m and 20 m/s, at t = 8 s (x = 180 m, on road 3's lane -3, which
    ends at x = 250 m) the file changes the ego to lane -2 (3 s, cubic): it is done, the ego
    drives on in lane -2 (y = -5.25 m within 0.6 m from t = 13 s, 0.57 m as the pid closes in
    slowly, within 0.1 m at the end) past the end of lane -3 to the StopTrigger at 16 s
    (x = 340 m), no lane departure."""
    (tmp_path / "merge.xodr").write_text(merge())
    change = event("ToLeft", "Ego", lane_change(-2, "cubic", "time", 3.0), trigger([sim_time(8.0)]))
    path = write_file(tmp_path / "merge.xosc", "merge.xodr", [("Ego", "1", -1, 20.0, 20.0, "")], [change])
    stop = f"<StopTrigger><ConditionGroup>{sim_time(16.0)}</ConditionGroup></StopTrigger>"
    path.write_text(path.read_text().replace("</Story></Storyboard>", f"</Story>{stop}</Storyboard>"))
    sc = run_scene(path, 20.0)
    texts = [e.text for e in sc.events]
    assert not any("skipped" in t for t in texts), texts
    assert "StopTrigger" in sc.events[-1].text, sc.events[-1].text
    a = sc.trace.array(0)
    t, x, y = (a[:, sc.trace.names.index(n)] for n in ("t", "x", "y"))
    assert x.max() > 300.0
    assert np.abs(y[t >= 13.0] + 5.25).max() < 0.6  # in lane -2 (the pid converges slowly after a change)
    assert abs(y[-1] + 5.25) < 0.1
    assert sc.result().metrics["max_lane_departure"] == 0.0


def test_the_frame_numbers_the_lanes_across_the_merge(tmp_path):
    """The route goes on past lane -3's end in lane -2; the ego's lanes: its ramp lane (0),
    and road 3's lanes -2 (1) and -1 (2) beside it from the merge, 3.5 and 7 m to its left."""
    from ego.openscenario.roads import RoadMap, network_file
    from ego.openscenario.scenario import later_lanes

    (tmp_path / "merge.xodr").write_text(merge())
    roads = RoadMap(network_file(tmp_path / "merge.xodr"), converted=True)
    lane, _ = roads.lane_position("1", -1, 20.0)
    route = roads.lane_route(lane.edge, lane.index)
    keys = roads.route_keys(route, 0)
    assert [roads.lane_id_of(roads.edges[e].lanes[i]) for e, i, _ in route][-1] == -2
    assert keys[-1] == 1 and keys[0] == 0
    assert list(later_lanes(roads, route, keys, 1)) == [1, 2]
    for key, y in ((1, -5.25), (2, -1.75)):
        pts = np.array(roads.route_points(roads.beside_from(route, keys, key)))
        assert pts[0, 0] < 155.0 and pts[-1, 0] > 500.0
        assert np.abs(pts[:, 1] - y).max() < 1e-3
