"""Conditions and actions of the standard the reference player's motorway examples use beside
the storyboard's core: EndOfRoadCondition and OffroadCondition (esmini's acc-toggle.xosc,
lane_change_simple.xosc, lane_change.xosc). Each file here is hand-written for the test."""

from __future__ import annotations

import math

import pytest
from xosc_scenes import entity, event, lane_offset, run_scene, scene, sim_time, speed, starts, trigger

from ego.openscenario.loader import load
from ego.openscenario.scenario import StoryDriver
from ego.openscenario.xmltree import ScenarioFileError


def _record(monkeypatch, name: str) -> list:
    """(storyboard time, state of ``name``: s, d, speed, at_end, offroad) every step."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        inner(self)
        e = self.board.states[name]
        rows.append((self.board.t, e.s, e.d, e.speed, e.at_end, e.offroad))

    monkeypatch.setattr(StoryDriver, "step", spy)
    return rows


@pytest.mark.sumo
def test_an_entity_watched_at_its_road_end_stops_there_and_the_condition_counts(tmp_path, monkeypatch):
    """C starts 50 m before the end of the 3000 m road at 15 m/s: an EndOfRoadCondition on C
    makes it stop at the road's end (SUMO's stop: it brakes at its maxDeceleration, 4.5 m/s^2)
    instead of leaving the network; the event waiting for 1 s at the end starts 1.0 s after
    the first step C stands at the end, its front at the road's end."""
    rows = _record(monkeypatch, "C")
    evs = [event("End", "A", speed(10), trigger([entity("C", '<EndOfRoadCondition duration="1"/>')]))]
    sc = run_scene(scene(tmp_path, evs, at={"C": (-3, 2950.0, 15.0)}), 9.0)
    assert sc.status != "ended" or "left the road network" not in sc.status_detail, sc.status_detail
    first = next(t for t, *_, at_end, _ in rows if at_end)
    s_end, v_end = next((s, v) for t, s, _, v, *_ in rows if t == first)
    assert v_end < 0.01  # standing (SUMO reports the last mm/s of its braking step)
    assert 3000.0 - 0.15 <= s_end + 2.25 <= 3000.0 + 1e-6  # its front at the end (SUMO stops 0.1 m short at most)
    assert starts(sc, "End") == [pytest.approx(first + 1.0)]


@pytest.mark.sumo
def test_the_egos_road_end_is_seen_by_the_storyboard_before_the_run_ends(tmp_path):
    """The ego reaches the end of its road: its run ends there (ego drives its start road only),
    after the storyboard's step that sees it there, so an EndOfRoadCondition of duration 0 on
    the ego starts its event first, at the run's last time."""
    evs = [event("EgoEnd", "B", speed(10), trigger([entity("Ego", '<EndOfRoadCondition duration="0"/>')]))]
    sc = run_scene(scene(tmp_path, evs, at={"Ego": (-3, 2900.0, 20.0)}), 12.0)
    assert "the ego reached the end of its route" in sc.status_detail
    (t_event,) = starts(sc, "EgoEnd")
    t_end = float(sc.status_detail.split("at t = ")[1].split(" s")[0])
    assert t_end == pytest.approx(t_event)
    texts = [e.text for e in sc.events]
    started = next(i for i, x in enumerate(texts) if "event 'EgoEnd' starts" in x)
    assert started < next(i for i, x in enumerate(texts) if x.startswith("run ends"))


@pytest.mark.sumo
def test_offroad_condition_counts_from_the_step_the_centre_leaves_the_lanes(tmp_path, monkeypatch):
    """The ego moves 4 m right of its lane, the rightmost (3.5 m wide lanes, so off the road
    once its centre is more than 1.75 m right of that lane's centre): an OffroadCondition of
    0.5 s starts its event 0.5 s after the first step its centre is past the road's edge."""
    rows = _record(monkeypatch, "Ego")
    evs = [
        event("Off", "Ego", lane_offset(-4.0, "sinusoidal", 2.0), trigger([sim_time(0.5)])),
        event("Offroad", "A", speed(10), trigger([entity("Ego", '<OffroadCondition duration="0.5"/>')])),
    ]
    sc = run_scene(scene(tmp_path, evs), 8.0)
    d0 = rows[0][2]
    first = next(t for t, _, d, *_ in rows if d < d0 - 1.75)
    assert next(off for t, *_, off in rows if t == first)
    assert all(not off for t, *_, off in rows if t < first)
    assert starts(sc, "Offroad") == [pytest.approx(first + 0.5)]


def test_end_of_road_conditions_read_the_reference_players_rule(tmp_path):
    evs = [
        event("E", "A", speed(10), trigger([entity("C", '<EndOfRoadCondition duration="2.5" rule="greaterThan"/>')]))
    ]
    sc = load(scene(tmp_path, evs))
    c = sc.stories[0].acts[0].groups[0].maneuvers[0].events[0].start.groups[0][0]
    assert (c.kind, c.rule, c.value) == ("EndOfRoadCondition", "greaterThan", 2.5)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('<EndOfRoadCondition duration="-1"/>', r"bad value for duration in <EndOfRoadCondition>: -1"),
        ("<OffroadCondition/>", r"<OffroadCondition> needs attribute duration"),
        ('<OffroadCondition duration="1" rule="sometimes"/>', r"bad value for rule in <OffroadCondition>"),
    ],
)
def test_bad_end_of_road_and_offroad_conditions(tmp_path, body, message):
    with pytest.raises(ScenarioFileError, match=message):
        load(scene(tmp_path, [event("E", "A", speed(10), trigger([entity("C", body)]))]))


def _visibility(attrs: str) -> str:
    return f"<VisibilityAction {attrs}/>"


@pytest.mark.sumo
def test_a_car_hidden_from_sensors_is_not_the_egos_front_object_until_shown(tmp_path, monkeypatch):
    """C drives 60 m ahead of the ego in its lane: the surround sensor's front object. Hidden
    from sensors at storyboard time 1 s (graphics and traffic left out: true, as the reference
    player reads them) the ego has no front object from the next SUMO step on; shown again at
    2 s it is the front object again from the step after."""
    rows: list = []
    inner = StoryDriver.step

    def spy(self):
        inner(self)
        rows.append((self.board.t, self.sc.view.gap_front))

    monkeypatch.setattr(StoryDriver, "step", spy)
    evs = [
        event("Hide", "C", _visibility('sensors="false"'), trigger([sim_time(1)])),
        event("Show", "C", _visibility('graphics="true" sensors="true" traffic="true"'), trigger([sim_time(2)])),
    ]
    run_scene(scene(tmp_path, evs, at={"C": (-3, 84.5, 20.0)}), 3.0)
    seen = {round(t, 6): gap for t, gap in rows}
    assert all(math.isfinite(gap) and 50.0 < gap < 70.0 for t, gap in seen.items() if t <= 1.0)
    assert all(math.isinf(gap) for t, gap in seen.items() if 1.1 <= t <= 2.0)
    assert all(math.isfinite(gap) for t, gap in seen.items() if t >= 2.1)


def test_a_visibility_for_traffic_false_is_refused_in_one_line(tmp_path):
    path = scene(
        tmp_path,
        [event("Hide", "C", _visibility('graphics="true" traffic="false" sensors="true"'), trigger([sim_time(1)]))],
    )
    with pytest.raises(
        ScenarioFileError, match=r'a <VisibilityAction> with traffic="false" is not supported by ego'
    ) as exc:
        load(path)
    assert exc.value.line == next(
        i for i, ln in enumerate(path.read_text().splitlines(), 1) if "<VisibilityAction" in ln
    )


# -- LateralDistanceAction -----------------------------------------------------------------------
def lateral_distance(ref: str, attrs: str, limits: str = "") -> str:
    dc = f"<DynamicConstraints {limits}/>" if limits else ""
    return (
        f'<LateralAction><LateralDistanceAction entityRef="{ref}" {attrs}>{dc}</LateralDistanceAction></LateralAction>'
    )


@pytest.mark.parametrize(("freespace", "side"), [(False, "rightToReferencedEntity"), (True, "any")])
def test_lateral_distance_is_held_beside_the_entity(tmp_path, freespace, side):
    """B (lane -2, 3.5 m right of A in lane -1) holds 1.0 m right of A (freespace: between the
    1.8 m wide boxes): reached in one step, then exact every step (within 1e-6)."""
    attrs = f'distance="1.0" freespace="{str(freespace).lower()}" continuous="true" displacement="{side}"'
    ev = event("L", "B", lateral_distance("A", attrs), trigger([sim_time(0.5)]))
    sc = run_scene(scene(tmp_path, [ev]), 2.0)
    a_d = sc.board.states["A"].d
    want = a_d - 1.0 - (1.8 if freespace else 0.0)
    after = [d for t, _, d in sc._history["B"] if t >= 0.7 - 1e-9]
    assert after and all(d == pytest.approx(want, abs=1e-6) for d in after)


def test_lateral_distance_within_its_constraints_ends_once_held(tmp_path):
    """maxSpeed 1 m/s, maxAcceleration 2 m/s^2, maxDeceleration 2 m/s^2: B's lateral speed grows
    by at most 0.2 m/s a step, never exceeds 1 m/s, and B closes the 2.5 m to 1.0 m right of A
    without passing it; the action (not continuous) ends once held within 1 cm, and its state
    condition starts the next event."""
    attrs = 'distance="1.0" freespace="false" continuous="false" displacement="rightToReferencedEntity"'
    limits = 'maxSpeed="1" maxAcceleration="2" maxDeceleration="2"'
    ended = (
        '<Condition name="e" delay="0" conditionEdge="none"><ByValueCondition><StoryboardElementStateCondition '
        'storyboardElementType="action" storyboardElementRef="LAction" state="completeState"/></ByValueCondition>'
        "</Condition>"
    )
    evs = [
        event("L", "B", lateral_distance("A", attrs, limits), trigger([sim_time(0.5)])),
        event("E", "C", speed(10.0), trigger([ended])),
    ]
    sc = run_scene(scene(tmp_path, evs), 6.0)
    a_d = sc.board.states["A"].d
    hist = [(t, d) for t, _, d in sc._history["B"] if t >= 0.5 - 1e-9]
    vs = [(d1 - d0) / (t1 - t0) for (t0, d0), (t1, d1) in zip(hist, hist[1:])]
    assert max(abs(v) for v in vs) <= 1.0 + 1e-6
    assert all(abs(v1 - v0) <= 0.2 + 1e-6 for v0, v1 in zip(vs, vs[1:]))
    assert all(d <= a_d - 1.0 + 1e-6 for _, d in hist)
    (t_end,) = starts(sc, "E")
    d_end = next(d for t, d in hist if abs(t - t_end) < 1e-9)
    assert abs(a_d - 1.0 - d_end) < 0.01
    # 2.5 m at most 1 m/s after 0.5 s of speeding up: at least 2.5 s
    assert t_end >= 0.5 + 2.5


@pytest.mark.parametrize(
    ("attrs", "message"),
    [
        ('distance="-1" freespace="false" continuous="true"', r"bad value for distance in <LateralDistanceAction>: -1"),
        ('distance="1" freespace="false" continuous="true" displacement="above"', r"bad value for displacement"),
        ('distance="1" continuous="true"', r"<LateralDistanceAction> needs attribute freespace"),
    ],
)
def test_bad_lateral_distance_actions(tmp_path, attrs, message):
    with pytest.raises(ScenarioFileError, match=message):
        load(scene(tmp_path, [event("L", "B", lateral_distance("A", attrs), trigger([sim_time(0.5)]))]))


# -- entities without a start position ----------------------------------------------------------
def _without_start(path, name: str) -> None:
    text = path.read_text()
    i = text.index(f'<Private entityRef="{name}">')
    j = text.index("</Private>", i) + len("</Private>")
    path.write_text(text[:i] + text[j:])


def _teleport(s: float, lane: int = -3) -> str:
    return (
        f'<TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="{s}" offset="0"/></Position>'
        "</TeleportAction>"
    )


@pytest.mark.sumo
def test_an_entity_without_a_start_enters_when_a_teleport_places_it(tmp_path):
    """C has no TeleportAction in Init (esmini's full_e6mini.xosc vehicle7, cut-in_sumo.xosc's
    SumoVehicles): it is not in the simulation (the standard: an entity is placed by its Init or
    later) - a SpeedAction on it at 0.5 s does nothing, a condition on it does not hold - until a
    TeleportAction at 1 s places it (speed 0: it has no Init speed), and from then on it is a
    car as any."""
    evs = [
        event("Early", "C", speed(20), trigger([sim_time(0.5)])),
        event("Place", "C", _teleport(300.0), trigger([sim_time(1.0)])),
        event("Seen", "A", speed(20), trigger([entity("C", '<SpeedCondition value="-1" rule="greaterThan"/>')])),
        event("Go", "C", speed(10), trigger([sim_time(1.5)])),
    ]
    path = scene(tmp_path, evs)
    _without_start(path, "C")
    sc = run_scene(path, 3.0)
    texts = [e.text for e in sc.events if e.kind == "storyboard"]
    assert "t = 0.50 s: SpeedAction 'EarlyAction' on C: not in the simulation" in texts
    assert "t = 1.00 s: C enters the simulation" in texts
    assert starts(sc, "Seen") == [pytest.approx(1.1)]
    hist = sc._history["C"]
    assert hist[0][0] == pytest.approx(1.1)  # in SUMO from the step after the teleport
    assert all(v == pytest.approx(0.0, abs=1e-9) for t, v, _ in hist if t <= 1.5 + 1e-9)
    assert all(v == pytest.approx(10.0, abs=1e-6) for t, v, _ in hist if t >= 1.6 - 1e-9)
    # its box centre placed at s = 300 m, then 10 m/s from 1.6 s: at the last state (t = T)
    T = hist[-1][0]
    assert sc.board.states["C"].s == pytest.approx(300.0 + 10.0 * (T - 1.5), abs=1e-6)


def test_the_ego_still_needs_a_start(tmp_path):
    from ego.openscenario.scenario import file_listing

    path = scene(tmp_path, [])
    _without_start(path, "Ego")
    listing = file_listing(str(path))
    assert "the ego 'Ego' has no TeleportAction in <Init> (ego needs the ego's start position)" in listing["error"]


def test_a_start_relative_to_an_entity_without_a_start_is_refused_with_its_line(tmp_path):
    """B starts 20 m ahead of C, which has no start (not in the simulation): B has no place
    either, which is one line at B's position."""
    from ego.openscenario.scenario import file_listing

    path = scene(tmp_path, [])
    _without_start(path, "C")
    rel = '<RelativeLanePosition entityRef="C" dLane="0" ds="20" offset="0"/>'
    text = path.read_text()
    i = text.index('<Private entityRef="B">')
    j = text.index("</Position>", i)
    k = text.index("<Position>", i) + len("<Position>")
    path.write_text(text[:k] + rel + text[j:])
    listing = file_listing(str(path))
    line = next(n for n, ln in enumerate(path.read_text().splitlines(), 1) if "RelativeLanePosition" in ln)
    assert listing["error"] == (
        f"{path}:{line}: B's start is relative to C, which has no start (no TeleportAction in <Init>)"
    )


def _global_event(name: str, actor: str, action: str, start: str) -> tuple[str, str]:
    return actor, (
        f'<Event name="{name}" priority="parallel" maximumExecutionCount="1"><Action name="{name}Action">'
        f"<GlobalAction>{action}</GlobalAction></Action>{start}</Event>"
    )


def _entity_action(name: str, inner: str) -> str:
    return f'<EntityAction entityRef="{name}">{inner}</EntityAction>'


@pytest.mark.sumo
def test_delete_and_add_entity_actions(tmp_path):
    """C (lane -3, 400 m, 15 m/s) is deleted at 1 s: a condition on it stops holding, an action
    on it does nothing; AddEntityAction puts it back at 2 s at s = 500 m, at its Init speed
    (15 m/s), and it drives on from there."""
    add = _entity_action(
        "C",
        '<AddEntityAction><Position><LanePosition roadId="0" laneId="-3" s="500" offset="0"/></Position>'
        "</AddEntityAction>",
    )
    evs = [
        _global_event("Delete", "A", _entity_action("C", "<DeleteEntityAction/>"), trigger([sim_time(1.0)])),
        event("Ignored", "C", speed(5), trigger([sim_time(1.5)])),
        _global_event("Add", "A", add, trigger([sim_time(2.0)])),
        event("There", "B", speed(20), trigger([entity("C", '<SpeedCondition value="-1" rule="greaterThan"/>')])),
    ]
    sc = run_scene(scene(tmp_path, evs), 4.0)
    texts = [e.text for e in sc.events if e.kind == "storyboard"]
    assert "t = 1.00 s: C leaves the simulation (DeleteEntityAction)" in texts
    assert "t = 1.50 s: SpeedAction 'IgnoredAction' on C: not in the simulation" in texts
    assert "t = 2.00 s: C enters the simulation" in texts
    hist = sc._history["C"]
    assert not [t for t, *_ in hist if 1.05 < t < 2.05]  # not observed while out
    T = hist[-1][0]
    # placed by SUMO's step after the action (at 2.1 s it is at 500 m, as a teleport's car)
    assert sc.board.states["C"].s == pytest.approx(500.0 + 15.0 * (T - 2.1), abs=1e-6)
    assert starts(sc, "There") == [pytest.approx(0.0)]  # it held from the start (before the delete)


def test_an_entity_action_on_the_ego_is_refused(tmp_path):
    from ego.openscenario.scenario import file_listing

    evs = [_global_event("Delete", "A", _entity_action("Ego", "<DeleteEntityAction/>"), trigger([sim_time(1.0)]))]
    path = scene(tmp_path, evs)
    listing = file_listing(str(path))
    line = next(n for n, ln in enumerate(path.read_text().splitlines(), 1) if "<EntityAction" in ln)
    assert (
        listing["error"] == f"{path}:{line}: an <EntityAction> on the ego 'Ego': the ego is neither added nor deleted"
    )


@pytest.mark.sumo
def test_a_car_hidden_from_the_sensor_is_hit_and_the_collision_reported(tmp_path):
    """C stands in the ego's lane 80 m ahead, hidden from the ego's sensor from the start: the
    ego's manoeuvre and AEB never see it (no trigger), the ego drives into it, and the collision
    is reported (a hidden body still collides)."""
    evs = [event("Hide", "C", _visibility('sensors="false"'), trigger([sim_time(0)]))]
    sc = run_scene(scene(tmp_path, evs, at={"C": (-3, 104.5, 0.0)}), 8.0)
    assert sc.status == "collision", sc.status_detail
    assert sc.status_detail.startswith("ego (20.0 m/s) hit C (0.0 m/s)"), sc.status_detail
    assert not [e for e in sc.events if e.kind in ("trigger", "aeb")]


@pytest.mark.sumo
def test_an_ego_without_an_init_speed_starts_at_rest(tmp_path):
    """esmini's basic_ghost.xosc gives its ego no SpeedAction (its controller follows the
    ghost): the ego starts at rest, 0 m/s, and stays there (its speed reference)."""
    path = scene(tmp_path, [])
    text = path.read_text()
    i = text.index('<Private entityRef="Ego">')
    j = text.index("<PrivateAction><LongitudinalAction>", i)
    k = text.index("</PrivateAction>", j) + len("</PrivateAction>")
    path.write_text(text[:j] + text[k:])
    sc = run_scene(path, 2.0)
    assert sc.config.ego_speed == 0.0
    assert abs(sc.board.states["Ego"].speed) < 0.05 and sc.status == "completed", sc.status_detail
