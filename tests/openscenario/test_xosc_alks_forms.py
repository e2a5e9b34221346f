"""The forms the UN R157 ALKS scenario files (the ASAM/BMW interpretation) use, in files of
ego's own: value constraints, controller, pedestrian and misc-object catalogs, object
controllers and controller actions, standing pedestrians and obstacles, Init lateral offsets and
relative speeds, lane changes over a rate, expression functions, OpenDRIVE roads whose border
lanes netconvert drops, and a StopTrigger time beyond the default duration.

Scenes are xosc_scenes' (ego lane -3 at s = 20 m, 20 m/s; A lane -1 s = 100 m 25 m/s; B lane
-2 s = 200 m 15 m/s; C lane -3 s = 400 m 15 m/s, on straight3.xodr)."""

from __future__ import annotations

import json
import math

import pytest
from xosc_scenes import CAR, event, lane_change, run_scene, scene, sim_time, speed, starts, trigger

from ego.cli import main
from ego.openscenario.dynamics import PEAK_SPEED, Transition
from ego.openscenario.loader import load
from ego.openscenario.scenario import moved_entities

BOX = '<BoundingBox><Center x="0" y="0" z="0.5"/><Dimensions width="{w}" length="{l}" height="1"/></BoundingBox>'
PEDESTRIAN = (
    '<Pedestrian name="walker" mass="80" pedestrianCategory="pedestrian" model3d="Adult">'
    + BOX.format(w=0.5, l=0.3)
    + "<Properties/></Pedestrian>"
)
OBSTACLE = (
    '<MiscObject name="box" mass="50" miscObjectCategory="obstacle">'
    + BOX.format(w=1.0, l=1.0)
    + "<Properties/></MiscObject>"
)
CONTROLLER = '<Controller name="Driver"><Properties><Property name="mode" value="ALKS"/></Properties></Controller>'


def catalog(tmp_path, kind: str, entries: str) -> None:
    """Write catalogs/<kind>s/<kind>Catalog.xosc with ``entries``."""
    d = tmp_path / "catalogs" / f"{kind}s"
    d.mkdir(parents=True, exist_ok=True)
    (d / f"{kind}Catalog.xosc").write_text(
        '<?xml version="1.0"?>\n<OpenSCENARIO>\n<FileHeader revMajor="1" revMinor="1" date="2026-11-29T00:00:00" '
        f'description="c" author="ego tests"/>\n<Catalog name="{kind}Catalog">\n{entries}\n</Catalog>\n</OpenSCENARIO>\n'
    )


def with_entities(path, objects: dict[str, tuple[str, str]], locations: str = "") -> None:
    """Add entities (name -> (body, Init private actions)) and catalog locations to a scene."""
    text = path.read_text()
    ents = "".join(f'<ScenarioObject name="{n}">{body}</ScenarioObject>' for n, (body, _) in objects.items())
    init = "".join(f'<Private entityRef="{n}">{acts}</Private>' for n, (_, acts) in objects.items())
    text = text.replace("</Entities>", ents + "</Entities>").replace("</Actions></Init>", init + "</Actions></Init>")
    if locations:
        text = text.replace("<RoadNetwork>", f"<CatalogLocations>{locations}</CatalogLocations>\n<RoadNetwork>")
    path.write_text(text)


def at(lane: int, s: float, offset: float = 0.0) -> str:
    return (
        f'<PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="{lane}" s="{s}" '
        f'offset="{offset}"/></Position></TeleportAction></PrivateAction>'
    )


# -- value constraints --------------------------------------------------------------------------
CONSTRAINED = (
    '<ParameterDeclaration name="Lane" parameterType="string" value="-2">'
    '<ConstraintGroup><ValueConstraint rule="lessOrEqual" value="-1"/><ValueConstraint rule="greaterOrEqual" '
    'value="-3"/></ConstraintGroup></ParameterDeclaration>'
    '<ParameterDeclaration name="Speed" parameterType="double" value="15">'
    '<ConstraintGroup><ValueConstraint rule="greaterThan" value="0"/>'
    '<ValueConstraint rule="lessThan" value="${$Limit / 3.6}"/></ConstraintGroup></ParameterDeclaration>'
    '<ParameterDeclaration name="Limit" parameterType="double" value="60"/>'
)


def test_value_constraints_hold_for_the_defaults_and_refuse_a_value_outside(tmp_path, capsys):
    """A constraint may name a parameter declared after it (the standard resolves every
    declaration first); numbers held as strings (lane ids) compare as numbers; --set is
    checked like a default, one line naming the parameter, the value, the rule and its line."""
    path = scene(tmp_path, [], params=CONSTRAINED)
    model = load(path)
    assert model.values["Speed"] == 15.0
    groups = model.parameters["Speed"].constraints
    assert [(c.rule, c.value) for c in groups[0]] == [("greaterThan", "0"), ("lessThan", pytest.approx(60 / 3.6))]
    assert main(["run", str(path), "-c", "pid", "--set", "Speed=17", "--set", "duration=1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "parameter 'Speed' = 17 breaks its value constraint: lessThan 16.6667 (line " in err
    assert main(["run", str(path), "-c", "pid", "--set", "Lane=-4", "--set", "duration=1"]) == 2
    assert "parameter 'Lane' = -4 breaks its value constraint: greaterOrEqual -3 (line " in capsys.readouterr().err


# -- catalogs, controllers, standing bodies -----------------------------------------------------
def _standing_scene(tmp_path):
    catalog(tmp_path, "Pedestrian", PEDESTRIAN)
    catalog(tmp_path, "Controller", CONTROLLER)
    path = scene(tmp_path, [])
    ego_ctrl = (
        '<ObjectController><CatalogReference catalogName="ControllerCatalog" entryName="Driver"/></ObjectController>'
    )
    text = path.read_text()
    i = text.index("</ScenarioObject>")  # the ego's
    path.write_text(text[:i] + ego_ctrl + text[i:])
    with_entities(
        path,
        {
            "Walker": ('<CatalogReference catalogName="PedestrianCatalog" entryName="walker"/>', at(-3, 150.0)),
            "Box": (OBSTACLE, at(-2, 120.0, 0.5)),
        },
        '<PedestrianCatalog><Directory path="catalogs/Pedestrians"/></PedestrianCatalog>'
        '<ControllerCatalog><Directory path="catalogs/Controllers"/></ControllerCatalog>',
    )
    return path


def test_pedestrians_and_obstacles_stand_still_where_placed_and_are_seen(tmp_path):
    """A catalog pedestrian and an inline misc object without an Init speed stand still on
    their lane positions (an obstacle 0.5 m left of its lane's centre); the ego's surround
    sensor sees the pedestrian ahead in its lane: its front gap is the boxes' distance."""
    path = _standing_scene(tmp_path)
    model = load(path)
    assert model.entities["Walker"].vehicle.kind == "pedestrian"
    assert model.entities["Box"].vehicle.kind == "miscObject"
    sc = run_scene(path, 2.0)
    for name, d in (("Walker", 0.0), ("Box", 3.5 + 0.5)):
        hist = sc._history[name]
        assert all(v == 0.0 for _, v, _ in hist), name
        assert all(dd == pytest.approx(d, abs=1e-6) for t, _, dd in hist if t >= 0.1 - 1e-9), name
    names, rows = sc.trace.names, sc.trace.array()
    gap = rows[0][names.index("gap_front")]
    # ego front at 20 + 2.25, the pedestrian's back at 150 - 0.15
    assert gap == pytest.approx(150.0 - 0.15 - 22.25, abs=0.05)


def test_a_vehicle_the_file_never_moves_stands_still(tmp_path):
    """A car with only its Init teleport (no Init speed, no story's actor: the ALKS templates'
    blocking targets) stands at speed 0 where it is placed, as the standard's default
    controller keeps an entity's initial speed 0, and the ego's sensor sees it ahead; a car
    with an Init speed beside it drives it."""
    path = scene(tmp_path, [])
    with_entities(path, {"Parked": (CAR, at(-3, 150.0))})
    assert "Parked" not in moved_entities(load(path))
    sc = run_scene(path, 3.0)
    hist = sc._history["Parked"]
    assert hist and all(v == 0.0 for _, v, _ in hist)
    assert sc._history["A"][-1][1] == pytest.approx(25.0, abs=1e-6)
    names, rows = sc.trace.names, sc.trace.array()
    # the ego's front at 20 + 2.25, the parked car's back at 150 - 2.25
    assert rows[0][names.index("gap_front")] == pytest.approx(150.0 - 2.25 - 22.25, abs=0.05)


def test_controllers_are_accepted_and_the_ego_keeps_egos_controller(tmp_path, capsys):
    """ObjectController from a ControllerCatalog on the ego, ActivateControllerAction (1.0
    and 1.1 forms) and AssignControllerAction: done at once, the run is the scene's own."""
    path = _standing_scene(tmp_path)
    activate = '<ControllerAction><ActivateControllerAction lateral="true" longitudinal="true"/></ControllerAction>'
    assign = f"<ControllerAction><AssignControllerAction>{CONTROLLER}</AssignControllerAction></ControllerAction>"
    text = path.read_text()
    groups = "".join(
        event(name, "Ego", body, trigger([sim_time(0.5)]))[1]
        for name, body in (
            ("Act1", activate),
            ("Act0", '<ActivateControllerAction longitudinal="true"/>'),
            ("As", assign),
        )
    )
    man = (
        '<ManeuverGroup name="GC" maximumExecutionCount="1"><Actors selectTriggeringEntities="false">'
        f'<EntityRef entityRef="Ego"/></Actors><Maneuver name="MC">{groups}</Maneuver></ManeuverGroup>'
    )
    path.write_text(text.replace('<Act name="Act">', f'<Act name="Act">{man}'))
    assert main(["run", str(path), "-c", "pid", "--set", "duration=2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "completed"
    for name in ("Act1", "Act0", "As"):
        assert any(f"event '{name}' starts" in e["text"] for e in out["events"]), name


# -- Init: relative speeds -----------------------------------------------------------------------
def test_init_relative_speed_is_the_other_entitys_init_speed_plus_the_delta(tmp_path):
    path = scene(tmp_path, [])
    rel = (
        '<PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" '
        'dynamicsDimension="time"/><SpeedActionTarget><RelativeTargetSpeed entityRef="Ego" value="-4" '
        'speedTargetValueType="delta" continuous="false"/></SpeedActionTarget></SpeedAction></LongitudinalAction>'
        "</PrivateAction>"
    )
    with_entities(
        path,
        {
            "D": (
                PEDESTRIAN.replace("Pedestrian", "MiscObject")
                .replace('pedestrianCategory="pedestrian"', 'miscObjectCategory="obstacle"')
                .replace(' model3d="Adult"', ""),
                at(-1, 300.0) + rel,
            )
        },
    )
    sc = run_scene(path, 1.0)
    assert all(v == pytest.approx(16.0, abs=1e-6) for _, v, _ in sc._history["D"])


# -- lane change over a rate ------------------------------------------------------------------------
@pytest.mark.parametrize("shape", ["sinusoidal", "cubic", "linear"])
def test_lane_change_over_a_rate_peaks_at_that_lateral_speed(tmp_path, shape):
    """dynamicsDimension rate: the value is the peak lateral speed (m/s); A moves 3.5 m right
    in T = k 3.5 / rate (k: pi/2 sinusoidal, 3/2 cubic, 1 linear) along the closed form."""
    rate = 2.0
    sc = run_scene(
        scene(tmp_path, [event("L", "A", lane_change(-2, shape, "rate", rate), trigger([sim_time(0.95)]))]), 5.0
    )
    hist = sc._history["A"]
    d0 = hist[0][2]
    T = PEAK_SPEED[shape] * 3.5 / rate
    profile = Transition(1.0, d0, d0 - 3.5, T, shape)
    assert max(abs(d - profile.value(t)) for t, _, d in hist) < 1e-6
    speeds = [abs(b[2] - a[2]) / (b[0] - a[0]) for a, b in zip(hist, hist[1:])]
    assert max(speeds) == pytest.approx(rate, rel=0.02)


# -- expressions, stop time, roads ------------------------------------------------------------------
def test_expression_functions_place_entities(tmp_path):
    """sqrt(x * x) for abs (the ALKS files' idiom), abs, max, pow."""
    path = scene(tmp_path, [], params='<ParameterDeclaration name="Off" parameterType="double" value="-5"/>')
    text = path.read_text().replace(
        'laneId="-3" s="400.0"', 'laneId="-3" s="${400 + 2 * sqrt($Off * $Off) + abs($Off) + max(1, pow(2, 3)) - 23}"'
    )
    path.write_text(text)
    model = load(path)
    assert model.init["C"][0].position.s == pytest.approx(400.0)


def test_a_stop_trigger_time_beyond_the_default_duration_lengthens_the_run(tmp_path, capsys):
    stop = "<StopTrigger><ConditionGroup>" + sim_time(27.0, name="End") + "</ConditionGroup></StopTrigger>"
    path = scene(tmp_path, [], stop=stop, at={"Ego": (-3, 20.0, 5.0), "C": (-3, 900.0, 15.0)})
    assert main(["run", str(path), "-c", "pid", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "completed"
    assert out["sim_time"] == pytest.approx(27.0, abs=0.15)
    assert "StopTrigger" in out["status_detail"]


BORDERED = """<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="6" name="bordered"/>
<road name="r" length="1000" id="5" junction="-1"><link/>
<planView><geometry s="0" x="0" y="0" hdg="0" length="1000"><line/></geometry></planView>
<lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right>
<lane id="-1" type="border" level="false"><width sOffset="0" a="2.0" b="0" c="0" d="0"/></lane>
<lane id="-2" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
<lane id="-3" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
<lane id="-4" type="border" level="false"><width sOffset="0" a="1.0" b="0" c="0" d="0"/></lane>
</right></laneSection></lanes></road></OpenDRIVE>
"""


def test_opendrive_lane_ids_are_netconverts_origins_past_border_lanes(tmp_path):
    """netconvert drops border lanes: lane -2 of a road whose lane -1 is a border is SUMO's
    left lane of two, not the second from the left; a lane it dropped is named with the
    road's lane ids."""
    from ego.openscenario.roads import RoadMap, network_file

    xodr = tmp_path / "bordered.xodr"
    xodr.write_text(BORDERED)
    roads = RoadMap(network_file(xodr), converted=True)
    left, _ = roads.lane_position("5", -2, 10.0)
    right, _ = roads.lane_position("5", -3, 10.0)
    assert (left.index, right.index) == (1, 0)
    assert [roads.lane_id_of(x) for x in (left, right)] == [-2, -3]
    with pytest.raises(ValueError, match=r"road '5' has no lane -1 on that side at s = 10 \(lane ids -2, -3;"):
        roads.lane_position("5", -1, 10.0)
    # the lanes' centres are 3.5 m apart, as the file's widths say
    (x0, y0), (x1, y1) = left.shape[0], right.shape[0]
    assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(3.5, abs=1e-3)


# -- LongitudinalDistanceAction -------------------------------------------------------------------
def distance_action(ref: str, attr: str, freespace: bool = False, continuous: bool = True, limits: str = "") -> str:
    dc = f"<DynamicConstraints {limits}/>" if limits else ""
    return (
        f'<LongitudinalAction><LongitudinalDistanceAction entityRef="{ref}" {attr} freespace="{str(freespace).lower()}" '
        f'continuous="{str(continuous).lower()}">{dc}</LongitudinalDistanceAction></LongitudinalAction>'
    )


@pytest.mark.parametrize("freespace", [False, True])
def test_longitudinal_distance_is_held_behind_the_entity(tmp_path, freespace):
    """B (lane -2) holds 50 m behind C (lane -3, 15 m/s): reached in one step (35 m/s), then
    exact every step; freespace measures between the boxes (4.5 m long each)."""
    start = 348.0 - (4.5 if freespace else 0.0)
    ev = event("D", "B", distance_action("C", 'distance="50"', freespace), trigger([sim_time(0)]))
    sc = run_scene(scene(tmp_path, [ev], at={"B": (-2, start, 15.0)}), 3.0)
    b, c = sc.board.states["B"], sc.board.states["C"]
    assert c.s - b.s - (4.5 if freespace else 0.0) == pytest.approx(50.0, abs=1e-6)
    assert all(v == pytest.approx(15.0, abs=1e-6) for t, v, _ in sc._history["B"] if t >= 0.2 - 1e-9)


def test_time_gap_is_the_actors_own_speed_times_the_gap(tmp_path):
    """timeGap 2 s behind C: every step the gap is 2 s times B's speed, which settles to C's."""
    ev = event("D", "B", distance_action("C", 'timeGap="2"'), trigger([sim_time(0)]))
    sc = run_scene(scene(tmp_path, [ev], at={"B": (-2, 365.0, 15.0)}), 4.0)
    b, c = sc.board.states["B"], sc.board.states["C"]
    assert c.s - b.s == pytest.approx(2.0 * b.speed, abs=1e-6)
    assert b.speed == pytest.approx(15.0, abs=0.5)


def test_distance_within_dynamic_constraints_and_ending(tmp_path):
    """With maxAcceleration 2 the approach is limited to 2 m/s^2 and slows at most at
    maxDeceleration; a non-continuous action ends once the distance is held (within 1 cm)."""
    limits = 'maxAcceleration="2" maxDeceleration="6" maxSpeed="40"'
    ended = (
        '<Condition name="e" delay="0" conditionEdge="none"><ByValueCondition><StoryboardElementStateCondition '
        'storyboardElementType="action" storyboardElementRef="DAction" state="completeState"/></ByValueCondition>'
        "</Condition>"
    )
    evs = [
        event("D", "B", distance_action("C", 'distance="40"', continuous=False, limits=limits), trigger([sim_time(0)])),
        event("E", "A", speed(25.0), trigger([ended])),
    ]
    sc = run_scene(scene(tmp_path, evs, at={"B": (-2, 300.0, 15.0)}), 12.0)
    hist = sc._history["B"]
    rates = [(v1 - v0) / (t1 - t0) for (t0, v0, _), (t1, v1, _) in zip(hist, hist[1:])]
    assert max(rates) <= 2.0 + 1e-6 and min(rates) >= -6.0 - 1e-6
    assert starts(sc, "E"), "the action did not end"
    b, c = sc.board.states["B"], sc.board.states["C"]
    # held within 1 cm when it ended; B drives on at its last speed since
    assert c.s - b.s == pytest.approx(40.0, abs=0.1)


EGO_DRIVER = (
    '<ObjectController><CatalogReference catalogName="ControllerCatalog" entryName="Driver"/></ObjectController>'
)


def _missing_controller(tmp_path, assigned: str) -> tuple:
    """The standing scene with the ego's controller an entry its catalog lacks (the reference
    player's highway_driver.xosc names 'NaturalDriver'), assigned a parameter: (path, line)."""
    path = _standing_scene(tmp_path)
    ref = (
        '<ObjectController><CatalogReference catalogName="ControllerCatalog" entryName="NaturalDriver">'
        f'<ParameterAssignments><ParameterAssignment parameterRef="DesiredSpeed" value="{assigned}"/>'
        "</ParameterAssignments></CatalogReference></ObjectController>"
    )
    text = path.read_text().replace(EGO_DRIVER, "\n" + ref)
    path.write_text(text)
    return path, text.count("\n", 0, text.index(ref)) + 1


def test_a_controller_missing_from_its_catalog_is_a_warning_and_changes_nothing(tmp_path, capsys):
    """A controller entry its catalog lacks (deviation: the reference player stops) is one
    warning line naming the file's line, the entry and the catalog, from ``ego run`` and ``ego
    list`` alike; the run is the one with the catalog's entry, row for row (the ego is driven by
    ego's controller whatever the file assigns it)."""
    path, line = _missing_controller(tmp_path, "25")
    cat = tmp_path / "catalogs" / "Controllers" / "ControllerCatalog.xosc"
    warning = (
        f"ego: warning: {path}:{line}: no entry 'NaturalDriver' in catalog 'ControllerCatalog' ({cat}; entries: "
        "Driver): the controller is left out (ego drives the ego with its own controller, SUMO the others; see "
        "docs/openscenario.md)\n"
    )
    assert main(["list", str(path)]) == 0
    out, err = capsys.readouterr()
    assert "every element supported" in out and err == warning
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 0
    assert capsys.readouterr().err == warning
    missing = run_scene(path, 2.0)
    other = tmp_path / "with_entry"
    other.mkdir()
    with_entry = run_scene(_standing_scene(other), 2.0)
    assert missing.trace.names == with_entry.trace.names
    assert (missing.trace.array() == with_entry.trace.array()).all()


def test_a_missing_controllers_assignments_are_still_resolved_and_a_missing_body_refused(tmp_path, capsys):
    """The missing entry's parameter assignments are the scenario's expressions: an undeclared
    reference is one line at its own line; a missing pedestrian (a body) stays refused."""
    path, line = _missing_controller(tmp_path, "$Undeclared")
    assert main(["run", str(path), "-c", "pid"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"ego: error: {path}:{line}: " in err and "Undeclared" in err, err
    path = _standing_scene(tmp_path)
    text = path.read_text().replace('entryName="walker"', 'entryName="Nobody"')
    path.write_text(text)
    line = text.count("\n", 0, text.index('entryName="Nobody"')) + 1
    assert main(["run", str(path), "-c", "pid"]) == 2
    err = capsys.readouterr().err
    assert err == (f"ego: error: {path}:{line}: no entry 'Nobody' in catalog 'PedestrianCatalog' (entries: walker)\n")


@pytest.mark.parametrize(
    "ref,message",
    [
        (
            '<ObjectController><CatalogReference catalogName="PedestrianCatalog" entryName="walker"/></ObjectController>',
            "catalog entry 'walker' is a <Pedestrian>, not a <Controller> (in {cat})",
        ),
        (
            '<ObjectController><CatalogReference catalogName="Drivers" entryName="Driver"/></ObjectController>',
            None,
        ),
    ],
    ids=["wrong-kind", "no-catalog"],
)
def test_bad_catalog_references_are_one_line(tmp_path, capsys, ref, message):
    """A reference to an entry of another kind, to an entry or a catalog that is not there:
    one line with the reference's line, exit 2, nothing written."""
    path = _standing_scene(tmp_path)
    text = path.read_text()
    text = text.replace(EGO_DRIVER, "\n" + ref)
    path.write_text(text)
    line = text.count("\n", 0, text.index(ref)) + 1
    out = tmp_path / "out"
    assert main(["run", str(path), "-c", "pid", "--trace", str(out / "t.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"ego: error: {path}:{line}: "), err
    if message is not None:
        cat = tmp_path / "catalogs" / "Pedestrians" / "PedestrianCatalog.xosc"
        assert err == f"ego: error: {path}:{line}: {message.format(cat=cat)}\n"
    else:
        assert "catalog 'Drivers' not found (looked for " in err
    assert not out.exists()
