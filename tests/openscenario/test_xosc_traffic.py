"""TrafficAction: sources, sinks, swarms and stops as SUMO traffic (ego/openscenario/traffic.py).
Hand-written files on xosc_scenes' straight road (lanes -1, -2, -3; the ego in lane -3)."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import run_scene, scene, sim_time, trigger

from ego.openscenario.loader import load
from ego.openscenario.traffic import TrafficActions
from ego.openscenario.xmltree import ScenarioFileError

CARS = (
    '<TrafficDefinition name="cars"><VehicleCategoryDistribution>'
    '<VehicleCategoryDistributionEntry category="car" weight="1"/></VehicleCategoryDistribution>'
    "<ControllerDistribution/></TrafficDefinition>"
)


def _watch(monkeypatch) -> list[dict[str, tuple[float, float, float]]]:
    """Every storyboard step: the traffic vehicles in SUMO -> (x, y, speed) (box centres), and
    the ego's (x, y, yaw) under "Ego"."""
    snaps: list[dict[str, tuple[float, float, float]]] = []
    step = TrafficActions.step

    def watching(self):
        step(self)
        ids = [v for v in self.sim.libsumo.vehicle.getIDList() if v.startswith("traffic")]
        snap = {v: (lambda b: (b[0], b[1], b[3]))(self.sim.box(v)) for v in ids}
        snap["Ego"] = self._state("Ego")  # as the storyboard saw it at this step
        snaps.append(snap)

    monkeypatch.setattr(TrafficActions, "step", watching)
    return snaps


def _cars(snap: dict) -> dict:
    return {k: v for k, v in snap.items() if k != "Ego"}


def _at(lane: int, s: float) -> str:
    return f'<Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="0"/></Position>'


def _global(name: str, body: str, start: str, traffic_name: str = "") -> str:
    attr = f' trafficName="{traffic_name}"' if traffic_name else ""
    return (
        f'<Event name="{name}" priority="parallel" maximumExecutionCount="1"><Action name="{name}A"><GlobalAction>'
        f"<TrafficAction{attr}>{body}</TrafficAction></GlobalAction></Action>{start}</Event>"
    )


def _with_globals(tmp_path, events: list[str]):
    """The scene with a maneuver group holding ``events`` (global actions, no actors)."""
    path = scene(tmp_path, [])
    text = path.read_text()
    group = (
        '<ManeuverGroup name="GT" maximumExecutionCount="1"><Actors selectTriggeringEntities="false"/>'
        f'<Maneuver name="MT">{"".join(events)}</Maneuver></ManeuverGroup>'
    )
    path.write_text(text.replace('<Act name="Act">', f'<Act name="Act">{group}', 1))
    return path


def _source(rate: float, lane: int, s: float, speed: float) -> str:
    return f'<TrafficSourceAction rate="{rate}" radius="0" speed="{speed}">{_at(lane, s)}{CARS}</TrafficSourceAction>'


def test_a_source_adds_rate_vehicles_a_second_on_its_lane(tmp_path, monkeypatch):
    """2.5 vehicles a second from t = 0 (the first at once) on lane -1 at s = 60 m, 20 m/s top
    speed: after n storyboard steps 1 + floor(0.25 (n - 1)) vehicles added, on lane -1 (d = 7 m
    left of the ego's lane), none faster than 20 m/s."""
    snaps = _watch(monkeypatch)
    path = _with_globals(tmp_path, [_global("Src", _source(2.5, -1, 60.0, 20.0), trigger([sim_time(0)]))])
    sc = run_scene(path, 4.0)
    p = sc.story._traffic.processes[0]
    assert p.added == 1 + int(0.25 * (len(snaps) - 1))
    # 8 m apart at 20 m/s is closer than SUMO's drivers insert: the later ones queue for a
    # place (SUMO's insertion), the ones inserted slow down behind the first
    assert 3 <= len(_cars(snaps[-1])) <= p.added
    for snap in snaps:
        for x, y, v in _cars(snap).values():
            assert sc.road.project(x, y)[1] == pytest.approx(7.0, abs=0.01)
            assert v <= 20.0 + 1e-9


def test_a_sink_removes_the_traffic_that_reaches_it(tmp_path, monkeypatch):
    """A source on lane -1 at s = 60 m and a sink 40 m further (radius 4 m): no traffic vehicle
    gets past the sink, and every one that reached it was removed."""
    sink = f'<TrafficSinkAction radius="4">{_at(-1, 100.0)}</TrafficSinkAction>'
    events = [
        _global("Src", _source(1.0, -1, 60.0, 15.0), trigger([sim_time(0)])),
        _global("Snk", sink, trigger([sim_time(0)])),
    ]
    snaps = _watch(monkeypatch)
    sc = run_scene(_with_globals(tmp_path, events), 8.0)
    src = sc.story._traffic.processes[0]
    assert src.added >= 7
    for snap in snaps:
        for x, y, _ in _cars(snap).values():
            assert sc.road.project(x, y)[0] < 100.0 + 4.0
    assert len(_cars(snaps[-1])) < src.added  # the sink took the first ones


def test_a_stop_ends_the_named_source(tmp_path, monkeypatch):
    events = [
        _global("Src", _source(5.0, -1, 60.0, 15.0), trigger([sim_time(0)]), traffic_name="S"),
        _global("Stop", "<TrafficStopAction/>", trigger([sim_time(1.0)]), traffic_name="S"),
    ]
    snaps = _watch(monkeypatch)
    sc = run_scene(_with_globals(tmp_path, events), 3.0)
    assert sc.story._traffic.processes == []
    ids = sorted(int(v.split("_")[1]) for v in _cars(snaps[-1]))
    assert ids and max(ids) <= 5  # 1 at t = 0, then 0.5 a step up to t = 1 s


def test_a_swarm_keeps_its_vehicles_in_the_ellipse_around_the_ego(tmp_path, monkeypatch):
    """12 cars in the ellipse 150 m x 20 m around the ego, outside 30 m (a swarm in Init)."""
    path = scene(tmp_path, [])
    swarm = (
        '<GlobalAction><TrafficAction><TrafficSwarmAction innerRadius="30" semiMajorAxis="150" '
        f'semiMinorAxis="20" numberOfVehicles="12" velocity="20"><CentralObject entityRef="Ego"/>{CARS}'
        "</TrafficSwarmAction></TrafficAction></GlobalAction>"
    )
    text = path.read_text()
    path.write_text(text.replace("<Init><Actions>", f"<Init><Actions>{swarm}", 1))
    snaps = _watch(monkeypatch)
    sc = run_scene(path, 3.0)
    p = sc.story._traffic.processes[0]
    assert len(p.live) == 12
    assert len(_cars(snaps[-1])) == 12
    # each one appears (one SUMO step after it was added) outside the inner 30 m, less the
    # step's 2 m of travel, and every one stays in the ellipse (the road runs along x)
    seen: set[str] = set()
    for snap in snaps:
        ex, ey, _ = snap["Ego"]
        for vid, (x, y, _) in snap.items():
            if vid == "Ego":
                continue
            if vid not in seen:
                assert math.hypot(x - ex, y - ey) >= 30.0 - 2.0 - 2.0
                seen.add(vid)
            assert ((x - ex) / 152.0) ** 2 + ((y - ey) / 20.0) ** 2 <= 1.0
    assert len(seen) >= 12


def test_a_source_without_its_vehicles_is_one_line(tmp_path):
    body = f'<TrafficSourceAction rate="1" radius="0">{_at(-1, 60.0)}</TrafficSourceAction>'
    path = _with_globals(tmp_path, [_global("Src", body, trigger([sim_time(0)]))])
    with pytest.raises(ScenarioFileError, match=r"<TrafficSourceAction> needs a <TrafficDefinition>") as e:
        load(path)
    assert e.value.line == next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if "TrafficSource" in ln)
