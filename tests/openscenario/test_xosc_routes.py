"""AssignRouteAction and AcquirePositionAction: a scripted car routed through waypoints by
SUMO's driver, on a hand-built network with a fork (A -> B, then B -> C straight on or B -> D
turning left)."""

from __future__ import annotations

import subprocess

import pytest
from xosc_scenes import event, run_scene, trigger, write_file

from ego.openscenario.runtime import Storyboard
from ego.openscenario.xmltree import ScenarioFileError
from ego.sumo.net import sumo_binary

NODES = """<nodes>
  <node id="A" x="0" y="0"/><node id="B" x="600" y="0"/><node id="C" x="1200" y="0"/>
  <node id="D" x="900" y="400"/><node id="E" x="0" y="400"/>
</nodes>"""
EDGES = """<edges>
  <edge id="AB" from="A" to="B" numLanes="2" speed="36"/>
  <edge id="BC" from="B" to="C" numLanes="2" speed="36"/>
  <edge id="BD" from="B" to="D" numLanes="1" speed="36"/>
  <edge id="DE" from="D" to="E" numLanes="1" speed="36"/>
</edges>"""


def _net(tmp) -> None:
    (tmp / "fork.nod.xml").write_text(NODES)
    (tmp / "fork.edg.xml").write_text(EDGES)
    subprocess.run(
        [
            str(sumo_binary("netconvert")),
            "-n",
            "fork.nod.xml",
            "-e",
            "fork.edg.xml",
            "-o",
            "fork.net.xml",
            "--no-turnarounds",
            "true",
        ],
        cwd=tmp,
        check=True,
        capture_output=True,
    )


def _scene(tmp, action: str, start: str = '<SimulationTimeCondition value="1" rule="greaterOrEqual"/>'):
    _net(tmp)
    starts = [("Ego", "AB", -2, 20.0, 20.0, ""), ("R", "AB", -1, 300.0, 25.0, "")]
    cond = (
        f'<Condition name="c" delay="0" conditionEdge="none"><ByValueCondition>{start}</ByValueCondition></Condition>'
    )
    events = [event("Go", "R", f"<RoutingAction>{action}</RoutingAction>", trigger([cond]))]
    return write_file(tmp / "route.xosc", "fork.net.xml", starts, events)


def _route(*points: tuple[str, float]) -> str:
    wps = "".join(
        f'<Waypoint routeStrategy="shortest"><Position><LanePosition roadId="{r}" laneId="-1" s="{s}" offset="0"/>'
        "</Position></Waypoint>"
        for r, s in points
    )
    return f'<AssignRouteAction><Route name="r" closed="false">{wps}</Route></AssignRouteAction>'


def _ys(monkeypatch) -> list[float]:
    ys: list[float] = []
    step = Storyboard.step

    def recording(self, t):
        ys.append(self.states["R"].y)
        step(self, t)

    monkeypatch.setattr(Storyboard, "step", recording)
    return ys


@pytest.mark.parametrize(
    "action",
    [
        _route(("AB", 310.0), ("BD", 100.0)),
        '<AcquirePositionAction><Position><LanePosition roadId="BD" laneId="-1" s="100" offset="0"/>'
        "</Position></AcquirePositionAction>",
    ],
    ids=["route", "acquire"],
)
def test_a_routed_car_turns_off_at_the_fork(tmp_path, monkeypatch, action):
    """R (AB, 300 m, 25 m/s) is routed onto BD: at the fork (12 s later) it turns left and
    climbs towards D (y grows), where without a route it would go straight on to C (y = 0)."""
    ys = _ys(monkeypatch)
    sc = run_scene(_scene(tmp_path, action), 18.0)
    assert sc.status in ("completed", "timeout")
    assert max(ys) > 20.0


def test_routed_straight_on_the_car_stays_on_the_main_road(tmp_path, monkeypatch):
    ys = _ys(monkeypatch)
    path = _scene(tmp_path, _route(("AB", 310.0), ("BC", 100.0)))
    run_scene(path, 18.0)
    assert max(abs(y) for y in ys) < 10.0


def test_an_unreachable_waypoint_is_refused_before_the_run(tmp_path):
    """From BD (leading away to D and E) AB is not reachable: refused with the waypoint's line."""
    path = _scene(tmp_path, _route(("BD", 10.0), ("AB", 100.0)))
    with pytest.raises(
        ScenarioFileError, match=r"this waypoint's road 'AB' cannot be reached from the one before \('BD'\)"
    ):
        run_scene(path, 1.0)


def test_a_routed_car_watched_at_its_road_end_stops_at_the_dead_end(tmp_path):
    """R (AB at 500 m, 30 m/s) is routed straight on onto BC, a dead end at C: an
    EndOfRoadCondition on R holds it there (it stands with its front at C), and the event
    waiting 1 s at the end starts 1 s after it stands; the route assigned after the start moves
    the stop to the new route's end."""
    from xosc_scenes import entity, speed, starts

    _net(tmp_path)
    starts_ = [("Ego", "AB", -1, 20.0, 10.0, ""), ("R", "AB", -2, 500.0, 30.0, "")]
    cond = (
        '<Condition name="c" delay="0" conditionEdge="none"><ByValueCondition>'
        '<SimulationTimeCondition value="0.5" rule="greaterOrEqual"/></ByValueCondition></Condition>'
    )
    events = [
        event("Go", "R", f"<RoutingAction>{_route(('AB', 510.0), ('BC', 100.0))}</RoutingAction>", trigger([cond])),
        event("End", "Ego", speed(11), trigger([entity("R", '<EndOfRoadCondition duration="1"/>')])),
    ]
    path = write_file(tmp_path / "route.xosc", "fork.net.xml", starts_, events)
    rows: list = []
    step = Storyboard.step

    def recording(self, t):
        step(self, t)
        rows.append((t, self.states["R"].at_end, self.states["R"].speed, self.states["R"].x))

    import pytest as _pytest

    mp = _pytest.MonkeyPatch()
    mp.setattr(Storyboard, "step", recording)
    try:
        sc = run_scene(path, 40.0)
    finally:
        mp.undo()
    first = next(t for t, at_end, *_ in rows if at_end)
    x_end = next(x for t, _, _, x in rows if t == first)
    assert starts(sc, "End") == [pytest.approx(first + 1.0)]
    assert 1200.0 - 2.25 - 0.15 <= x_end <= 1200.0 - 2.25 + 1e-6  # its box centre half a car before C


ROUTES = """<?xml version="1.0"?>
<OpenSCENARIO><FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="r" author="t"/>
<Catalog name="RoutesAtTheFork">
<Route name="Left" closed="false"><ParameterDeclarations><ParameterDeclaration name="Far" parameterType="double"
 value="100"/></ParameterDeclarations>
<Waypoint routeStrategy="shortest"><Position><LanePosition roadId="AB" laneId="-1" s="310" offset="0"/></Position>
</Waypoint><Waypoint routeStrategy="shortest"><Position><LanePosition roadId="$Road" laneId="-1" s="$Far" offset="0"/>
</Position></Waypoint></Route>
</Catalog></OpenSCENARIO>
"""


def _catalog_scene(tmp, road: str):
    (tmp / "routes").mkdir(exist_ok=True)
    (tmp / "routes" / "RoutesAtTheFork.xosc").write_text(ROUTES.replace("$Road", road))
    ref = '<AssignRouteAction><CatalogReference catalogName="RoutesAtTheFork" entryName="Left"/></AssignRouteAction>'
    path = _scene(tmp, ref)
    text = path.read_text().replace(
        "<RoadNetwork>",
        '<CatalogLocations><RouteCatalog><Directory path="routes"/></RouteCatalog></CatalogLocations><RoadNetwork>',
    )
    path.write_text(text)
    return path


def test_a_route_from_a_route_catalog_turns_the_car_off_at_the_fork(tmp_path, monkeypatch):
    """The route of the first test, from a RouteCatalog entry (its parameter's default)."""
    ys = _ys(monkeypatch)
    sc = run_scene(_catalog_scene(tmp_path, "BD"), 18.0)
    assert sc.status in ("completed", "timeout")
    assert max(ys) > 20.0


def test_a_bad_road_of_a_catalog_route_is_refused_at_the_reference(tmp_path):
    """A catalog route's waypoint on a road the network lacks: found before the run (as any
    road position of the storyboard) and named at the CatalogReference's line of the scenario
    (the waypoint's own line is in the catalog file)."""
    from ego.openscenario.scenario import file_listing

    path = _catalog_scene(tmp_path, "XX")
    listing = file_listing(str(path))
    line = next(n for n, ln in enumerate(path.read_text().splitlines(), 1) if "<CatalogReference" in ln)
    assert listing["error"] == f"{path}:{line}: unknown road 'XX' (roads: AB, BC, BD, DE)"
