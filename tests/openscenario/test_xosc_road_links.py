"""The ego drives on across road links: a hand-written OpenDRIVE network of a straight road 1,
a junction 100 whose connecting road 4 (an arc) leads to road 2 (straight), road 2's plain
successor link (no junction) to road 3 (an arc the other way) and, in the fork variant, a
second connecting road 5 turning right off road 1's right lane onto road 6. Converted by
netconvert and run in SUMO: the ego's lane frame follows its lane's successors (the straightest
at the fork) and the run ends at the file's StopTrigger, or at the dead end of road 3."""

from __future__ import annotations

import math

import numpy as np
import pytest
from xosc_scenes import run_scene, sim_time, write_file

K4, L4, L2, K3, L3, K5, L5 = 0.002, 50.0, 150.0, -0.003, 150.0, -0.02, 40.0


def _lanes(n: int, links: list[str] | None = None) -> str:
    links = links or [""] * n
    lanes = "".join(
        f'<lane id="-{k + 1}" type="driving" level="false">{links[k]}'
        '<width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>'
        for k in range(n)
    )
    return (
        '<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center>'
        f"<right>{lanes}</right></laneSection></lanes>"
    )


def _link(pred: int | None = None, succ: int | None = None) -> str:
    p = f'<predecessor id="{pred}"/>' if pred is not None else ""
    s = f'<successor id="{succ}"/>' if succ is not None else ""
    return f"<link>{p}{s}</link>"


def _road(rid: int, length: float, junction: int, link: str, x: float, y: float, h: float, shape: str) -> str:
    return (
        f'<road name="r{rid}" length="{length!r}" id="{rid}" junction="{junction}"><link>{link}</link><planView>'
        f'<geometry s="0" x="{x!r}" y="{y!r}" hdg="{h!r}" length="{length!r}">{shape}</geometry></planView>'
        f"{_lanes(2) if rid != 5 and rid != 6 else ''}"
    )


def network(fork: bool) -> str:
    """The OpenDRIVE text (module docstring)."""
    x2, y2, h2 = 200.0 + math.sin(K4 * L4) / K4, (1.0 - math.cos(K4 * L4)) / K4, K4 * L4
    x3, y3 = x2 + L2 * math.cos(h2), y2 + L2 * math.sin(h2)
    x6, y6, h6 = 200.0 + math.sin(K5 * L5) / K5, (1.0 - math.cos(K5 * L5)) / K5, K5 * L5
    roads = [
        _road(1, 200.0, -1, '<successor elementType="junction" elementId="100"/>', 0.0, 0.0, 0.0, "<line/>")
        + "</road>",
        _road(
            4,
            L4,
            100,
            '<predecessor elementType="road" elementId="1" contactPoint="end"/>'
            '<successor elementType="road" elementId="2" contactPoint="start"/>',
            200.0,
            0.0,
            0.0,
            f'<arc curvature="{K4}"/>',
        ).replace(_lanes(2), _lanes(2, [_link(-1, -1), _link(-2, -2)]))
        + "</road>",
        _road(
            2,
            L2,
            -1,
            '<predecessor elementType="junction" elementId="100"/>'
            '<successor elementType="road" elementId="3" contactPoint="start"/>',
            x2,
            y2,
            h2,
            "<line/>",
        ).replace(_lanes(2), _lanes(2, [_link(None, -1), _link(None, -2)]))
        + "</road>",
        _road(
            3,
            L3,
            -1,
            '<predecessor elementType="road" elementId="2" contactPoint="end"/>',
            x3,
            y3,
            h2,
            f'<arc curvature="{K3}"/>',
        ).replace(_lanes(2), _lanes(2, [_link(-1), _link(-2)]))
        + "</road>",
    ]
    conns = (
        '<connection id="0" incomingRoad="1" connectingRoad="4" contactPoint="start">'
        '<laneLink from="-1" to="-1"/><laneLink from="-2" to="-2"/></connection>'
    )
    if fork:
        roads.append(
            _road(
                5,
                L5,
                100,
                '<predecessor elementType="road" elementId="1" contactPoint="end"/>'
                '<successor elementType="road" elementId="6" contactPoint="start"/>',
                200.0,
                0.0,
                0.0,
                f'<arc curvature="{K5}"/>',
            )
            + _lanes(1, [_link(-2, -1)])
            + "</road>"
        )
        roads.append(
            _road(6, 100.0, -1, '<predecessor elementType="junction" elementId="100"/>', x6, y6, h6, "<line/>")
            + _lanes(1)
            + "</road>"
        )
        conns += (
            '<connection id="1" incomingRoad="1" connectingRoad="5" contactPoint="start">'
            '<laneLink from="-2" to="-1"/></connection>'
        )
    body = "\n".join(roads)
    return (
        '<?xml version="1.0" standalone="yes"?>\n<OpenDRIVE><header revMajor="1" revMinor="4" name="links" '
        f'version="1"/>\n{body}\n<junction name="j" id="100">{conns}</junction>\n</OpenDRIVE>\n'
    )


def _scene(tmp, fork: bool, lane: int, stop: float):
    (tmp / "links.xodr").write_text(network(fork))
    path = write_file(tmp / "links.xosc", "links.xodr", [("Ego", "1", lane, 50.0, 20.0, "")], [])
    text = path.read_text()
    stop_trigger = f"<StopTrigger><ConditionGroup>{sim_time(stop)}</ConditionGroup></StopTrigger>"
    path.write_text(text.replace("</Story></Storyboard>", f"</Story>{stop_trigger}</Storyboard>"))
    return path


def _trace(sc, *names: str) -> list[np.ndarray]:
    a = sc.trace.array(0)
    return [a[:, sc.trace.names.index(n)] for n in names]


def _jump(s: np.ndarray, d: np.ndarray, at: float) -> float:
    """The largest change of the lateral offset from one control step to the next within 5 m
    of the arc length ``at`` along the ego's lanes."""
    near = np.flatnonzero(np.abs(s[1:] - at) < 5.0) + 1
    return float(np.abs(d[near] - d[near - 1]).max())


def test_the_ego_drives_through_a_junction_and_a_plain_link(tmp_path):
    """From road 1 (s = 50 m, 20 m/s) through junction 100 (road 1 ends at 200 m along its
    lane, the connecting road at 250 m) and road 2's plain link to road 3 (at 400 m): the run
    goes to its StopTrigger at 20 s, 400 m on, with the lateral offset smooth across the links."""
    sc = run_scene(_scene(tmp_path, False, -1, 20.0), 30.0)
    assert "StopTrigger" in sc.events[-1].text, sc.events[-1].text
    assert [e for e, _, _ in sc.ego_route] == ["-1", "-2", "-3"]
    s, d = _trace(sc, "s", "d")
    assert s.max() > 440.0
    for at in (200.0, 250.0, 400.0):
        assert _jump(s, d, at) < 0.05
    assert np.abs(d).max() < 0.1  # the pid's error through the arcs, no jump at a joint


def test_at_a_fork_the_ego_goes_straight_on(tmp_path):
    """Road 1's right lane leads straight on (road 4) or right (road 5): the ego's route is
    the straightest, and the ego ends on road 3 (y > 10 m; road 6 lies at y < 0)."""
    sc = run_scene(_scene(tmp_path, True, -2, 20.0), 30.0)
    assert "StopTrigger" in sc.events[-1].text, sc.events[-1].text
    assert [e for e, _, _ in sc.ego_route] == ["-1", "-2", "-3"]
    (y,) = _trace(sc, "y")
    assert y[-1] > 10.0


def test_a_dead_end_still_ends_the_run(tmp_path):
    """Road 3 leads nowhere: the run ends when the ego's front reaches its end, 549 m along
    its lanes from road 1's start (about 25 s at 20 m/s from s = 50 m), before the StopTrigger."""
    sc = run_scene(_scene(tmp_path, False, -1, 40.0), 45.0)
    end = sc.events[-1].text
    assert "the end of its route" in end and "a dead end" in end, end
    assert 24.0 < sc.t < 25.5


def test_an_ego_headed_against_its_lane_by_an_absolute_orientation_is_refused(tmp_path):
    """Road 1 runs along +x: an absolute heading of pi on its right lane would have the ego
    drive its lane backwards (a run ending at once at the road's start): refused, naming the
    Orientation's line, as a relative turn is."""
    from ego.openscenario.xmltree import ScenarioFileError

    (tmp_path / "links.xodr").write_text(network(False))
    turned = '<Orientation type="absolute" h="3.14159"/>'
    path = write_file(tmp_path / "turned.xosc", "links.xodr", [("Ego", "1", -1, 50.0, 20.0, turned)], [])
    line = next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if "Orientation" in ln)
    with pytest.raises(ScenarioFileError, match=rf":{line}: a start heading turning the ego against its lane"):
        run_scene(path, 1.0)
    along = '<Orientation type="absolute" h="0.1"/>'
    path = write_file(tmp_path / "along.xosc", "links.xodr", [("Ego", "1", -1, 50.0, 20.0, along)], [])
    assert run_scene(path, 1.0).status in ("completed", "timeout")
