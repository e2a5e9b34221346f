"""OpenSCENARIO 0.9 files (the reference player's basic_ego, cut-in_internal... examples):
read as the 1.0 tree ego runs, every error at the 0.9 file's own line. The scenario is
xosc_v09's cut-in, written once in 0.9 and once by hand in 1.0; its bad forms are in the
bad-file corpus (test_xosc_corpus.py)."""

from __future__ import annotations

import pytest
from xosc_scenes import run_scene, starts
from xosc_v09 import CATALOG_09, V09, V10, sub, write

from ego.cli import main
from ego.openscenario.loader import PERFORMANCE_DEFAULTS, load, read_tree
from ego.openscenario.scenario import file_listing
from ego.openscenario.xmltree import ScenarioFileError


def _storyboard(sc) -> list[tuple[float, str]]:
    return [(round(e.t, 6), e.text) for e in sc.events if e.kind == "storyboard"]


def test_a_0_9_file_runs_as_its_1_0_counterpart(tmp_path):
    """The 0.9 cut-in and its hand-written 1.0 twin give the same run in SUMO, event for event
    and step for step of the scripted car; the times are the scenario's own: Lead, 10 m behind
    and 5 m/s faster, is 15 m ahead after (10 + 15) / 5 = 5 s; its 2 s lane change and the 1 s
    delay put the brake 3 s later (one step more: the end is seen at the next step); the 0.9
    file's rate of -5 brakes at 5 m/s^2, as the 1.0 file's 5."""
    old, new = run_scene(write(tmp_path), 15.0), run_scene(write(tmp_path, V10, "cut_in_10.xosc"), 15.0)
    assert _storyboard(old) == _storyboard(new)
    assert old.status == new.status == "completed"
    assert "StopTrigger" in old.status_detail
    cut_in, brake = starts(old, "CutIn"), starts(old, "Brake")
    assert cut_in == [pytest.approx(5.0, abs=0.1)]
    assert brake == [pytest.approx(cut_in[0] + 2.0 + 1.0 + 0.1, abs=1e-9)]
    assert old.story.history["Lead"] == new.story.history["Lead"]
    lead = old.story.history["Lead"]
    v = {round(t, 6): speed for t, speed, _ in lead}
    t0 = brake[0] + 0.5
    assert v[round(t0, 6)] - v[round(t0 + 1.0, 6)] == pytest.approx(5.0, abs=1e-6)


def test_parameters_are_named_without_their_0_9_dollar(tmp_path):
    """0.9 declares ``$EgoSpeed``, 1.0 ``EgoSpeed``: ``--set`` and ``ego list`` use the 1.0
    name; a Story's ``owner`` is the story's parameter ``owner``."""
    path = write(tmp_path)
    model = load(path, {"EgoSpeed": 25.0})
    assert list(model.parameters) == ["EgoSpeed", "Behind", "Rate"]
    assert model.values["EgoSpeed"] == 25.0
    assert model.stories[0].acts[0].groups[0].actors == ("Lead",)
    listing = file_listing(str(path))
    assert listing["supported"] and listing["error"] is None, listing["error"]
    assert [p["name"] for p in listing["parameters"]] == ["EgoSpeed", "Behind", "Rate"]
    assert [e["name"] for e in listing["entities"]] == ["Ego", "Lead"]


def test_every_element_keeps_its_0_9_line(tmp_path):
    """The mapped tree's elements stand at the lines of the 0.9 elements they come from (a
    wrapper 1.0 adds, as TeleportAction around a Position, at its 0.9 element's line)."""
    path = write(tmp_path)
    lines = V09.splitlines()
    root = read_tree(path)
    ego = root.child("Storyboard").child("Init").child("Actions").all("Private")[0]
    teleport = ego.children[0].children[0]
    assert teleport.tag == "TeleportAction"
    assert "<Position>" in lines[teleport.line - 1]
    lane = teleport.children[0].children[0]
    assert lane.tag == "LanePosition" and "<Lane " in lines[lane.line - 1]
    assert lane.attrs == {"roadId": "0", "laneId": "-3", "offset": "0", "s": "20"}
    header = root.child("FileHeader")
    assert (header.attrs["revMajor"], header.attrs["revMinor"]) == ("1", "0")


def test_an_event_that_only_quits_ends_the_scenario(tmp_path):
    """The reference player's ``<Global><EXT_Quit/></Global>`` (its extension: basic_hybrid.xosc)
    ends the scenario when its event would start: its conditions join the storyboard's
    StopTrigger."""
    quit_event = """<Event name="Quit" priority="overwrite">
              <Action name="QuitAction"><Global><EXT_Quit/></Global></Action>
              <StartConditions><ConditionGroup>
                <Condition name="QuitTime" delay="0" edge="rising">
                  <ByValue><SimulationTime value="3" rule="greater_than"/></ByValue>
                </Condition>
              </ConditionGroup></StartConditions>
            </Event>
            <Event name="Brake" priority="overwrite">"""
    path = write(tmp_path, sub('<Event name="Brake" priority="overwrite">', quit_event))
    sc = run_scene(path, 15.0)
    assert sc.status == "completed" and "StopTrigger" in sc.status_detail
    assert sc.t == pytest.approx(3.1, abs=1e-9)  # > 3 at 3.1 s: the storyboard's step there ends it
    assert starts(sc, "CutIn") == []


def test_a_0_9_error_from_the_1_0_checks_names_the_0_9_line(tmp_path, capsys):
    """``ego list`` and ``ego run`` give the same one line for a 0.9 file ego refuses."""
    bad = sub('ds="$Behind"', 'ds="$Behid"')
    path = write(tmp_path, bad)
    line = next(i for i, ln in enumerate(bad.splitlines(), 1) if "$Behid" in ln)
    message = f"{path}:{line}: parameter '$Behid' is not declared (declared: EgoSpeed, Behind, Rate)"
    with pytest.raises(ScenarioFileError) as exc:
        load(path)
    assert str(exc.value) == message
    assert main(["run", str(path), "-c", "pid"]) == 2
    assert capsys.readouterr().err == f"ego: error: {message}\n"
    assert file_listing(str(path))["error"] == message


def test_ego_concrete_writes_a_0_9_file_as_1_0(tmp_path):
    """``ego concrete`` writes the mapped tree: a 1.0 file (``ParameterDeclarations``,
    ``TeleportAction``...) that runs as the 0.9 file does."""
    from ego.openscenario.concrete import write as write_concrete

    path = write(tmp_path)
    out = write_concrete(path, {"EgoSpeed": 20.0}, tmp_path / "out" / "cut_in_10.xosc")
    text = out.read_text()
    assert 'revMajor="1" revMinor="0"' in text and "<TeleportAction>" in text and "<Object name" not in text
    assert _storyboard(run_scene(out, 15.0)) == _storyboard(run_scene(path, 15.0))


def test_ego_list_names_the_0_9_element_ego_refuses(tmp_path):
    """``ego list`` lists a 0.9 file that the mapping refuses: the refused element (and what it
    holds) as not supported at its line, every other element mapped, and ``ego run``'s error."""
    bad = sub(
        '<Action name="EgoSpeed">',
        '<Action><Meeting mode="straight" timingOffset="0"/></Action><Action name="EgoSpeed">',
    )
    path = write(tmp_path, bad)
    line = next(i for i, ln in enumerate(bad.splitlines(), 1) if "<Meeting" in ln)
    listing = file_listing(str(path))
    assert not listing["supported"]
    assert listing["error"] == (
        f"{path}:{line}: <Meeting> is not supported by ego in an OpenSCENARIO 0.9 file (see docs/openscenario.md)"
    )
    refused = [(e["element"], e["line"]) for e in listing["elements"] if not e["supported"]]
    assert refused == [("Meeting", line)]
    assert [e["name"] for e in listing["entities"]] == ["Ego", "Lead"]


def _tree(node) -> tuple:
    return node.tag, node.attrs, [_tree(c) for c in node.children]


#: (0.9 context, 0.9 element, its 1.0 form as docs/openscenario.md's table gives it)
MAPPED = [
    (
        "paction",
        '<Autonomous activate="true" domain="both"/>',
        '<ActivateControllerAction longitudinal="true" lateral="true"/>',
    ),
    (
        "paction",
        '<Lateral><LaneOffset><Dynamics maxLateralAcc="1.5" shape="cubic"/><Target><Relative object="A" value="0.5"/>'
        "</Target></LaneOffset></Lateral>",
        '<LateralAction><LaneOffsetAction continuous="true"><LaneOffsetActionDynamics maxLateralAcc="1.5" '
        'dynamicsShape="cubic"/><LaneOffsetTarget><RelativeTargetLaneOffset entityRef="A" value="0.5"/>'
        "</LaneOffsetTarget></LaneOffsetAction></LateralAction>",
    ),
    (
        "paction",
        '<Longitudinal><Distance object="A" timeGap="1.5" freespace="true"><Dynamics><Limited maxAcceleration="2" '
        'maxDeceleration="5" maxSpeed="40"/></Dynamics></Distance></Longitudinal>',
        '<LongitudinalAction><LongitudinalDistanceAction entityRef="A" timeGap="1.5" freespace="true" continuous="true">'
        '<DynamicConstraints maxAcceleration="2" maxDeceleration="5" maxSpeed="40"/></LongitudinalDistanceAction>'
        "</LongitudinalAction>",
    ),
    (
        "paction",
        '<Lateral><Distance object="A" distance="3" freespace="false"><Dynamics><None/></Dynamics></Distance></Lateral>',
        '<LateralAction><LateralDistanceAction entityRef="A" distance="3" freespace="false" continuous="true"/>'
        "</LateralAction>",
    ),
    (
        "paction",
        '<Visibility graphics="true" traffic="false" sensors="true"/>',
        '<VisibilityAction graphics="true" traffic="false" sensors="true"/>',
    ),
    (
        "paction",
        '<Routing><AcquirePosition><Position><Road roadId="1" s="50" t="-2"/></Position></AcquirePosition></Routing>',
        '<RoutingAction><AcquirePositionAction><Position><RoadPosition roadId="1" s="50" t="-2"/></Position>'
        "</AcquirePositionAction></RoutingAction>",
    ),
    (
        "paction",
        '<Routing><FollowRoute><Route name="R" closed="false"><Waypoint strategy="shortest"><Position>'
        '<Lane roadId="1" laneId="-1" s="0"/></Position></Waypoint></Route></FollowRoute></Routing>',
        '<RoutingAction><AssignRouteAction><Route name="R" closed="false"><Waypoint routeStrategy="shortest"><Position>'
        '<LanePosition roadId="1" laneId="-1" s="0"/></Position></Waypoint></Route></AssignRouteAction></RoutingAction>',
    ),
    (
        "paction",
        '<Position><RelativeObject object="A" dx="-5" dy="3.5"><Orientation type="relative" h="0"/></RelativeObject>'
        "</Position>",
        '<TeleportAction><Position><RelativeObjectPosition entityRef="A" dx="-5" dy="3.5"><Orientation type="relative" '
        'h="0"/></RelativeObjectPosition></Position></TeleportAction>',
    ),
    (
        "paction",
        '<Controller><Assign><Driver name="d"><Description weight="70" height="1.7" eyeDistance="0.06" age="30" '
        'sex="male"><Properties><Property name="p" value="1"/></Properties></Description></Driver></Assign></Controller>',
        '<ControllerAction><AssignControllerAction><Controller name="d"><Properties><Property name="weight" value="70"/>'
        '<Property name="height" value="1.7"/><Property name="eyeDistance" value="0.06"/><Property name="age" '
        'value="30"/><Property name="sex" value="male"/><Property name="p" value="1"/></Properties></Controller>'
        "</AssignControllerAction></ControllerAction>",
    ),
    (
        "entitycond",
        '<TimeToCollision value="2" freespace="false" alongRoute="false" rule="less_than"><Target><Entity name="A"/>'
        "</Target></TimeToCollision>",
        '<TimeToCollisionCondition value="2" freespace="false" alongRoute="false" rule="lessThan">'
        '<TimeToCollisionConditionTarget><EntityRef entityRef="A"/></TimeToCollisionConditionTarget>'
        "</TimeToCollisionCondition>",
    ),
    (
        "entitycond",
        '<Collision><ByType type="vehicle"/></Collision>',
        '<CollisionCondition><ByType type="vehicle"/></CollisionCondition>',
    ),
    (
        "bystate",
        '<AtStart type="act" name="Act1"/>',
        '<StoryboardElementStateCondition storyboardElementType="act" storyboardElementRef="Act1" state="startTransition"/>',
    ),
    (
        "byvalue",
        '<Parameter name="$P" value="3" rule="equal_to"/>',
        '<ParameterCondition parameterRef="P" value="3" rule="equalTo"/>',
    ),
    (
        "global",
        '<Parameter name="$P"><Modify><Rule><Multiply value="2"/></Rule></Modify></Parameter>',
        '<ParameterAction parameterRef="P"><ModifyAction><Rule><MultiplyByValue value="2"/></Rule></ModifyAction>'
        "</ParameterAction>",
    ),
    (
        "global",
        '<Entity name="X"><Delete/></Entity>',
        '<EntityAction entityRef="X"><DeleteEntityAction/></EntityAction>',
    ),
    (
        "catalog",
        '<MiscObject category="guardRail" mass="100" name="rail"><BoundingBox><Center x="0" y="0" z="0"/>'
        '<Dimension width="0.3" length="50" height="1"/></BoundingBox><Properties/></MiscObject>',
        '<MiscObject miscObjectCategory="railing" mass="100" name="rail"><BoundingBox><Center x="0" y="0" z="0"/>'
        '<Dimensions width="0.3" length="50" height="1"/></BoundingBox><Properties/></MiscObject>',
    ),
    (
        "catalogs",
        '<PedestrianControllerCatalog><Directory path="c"/></PedestrianControllerCatalog>',
        '<ControllerCatalog><Directory path="c"/></ControllerCatalog>',
    ),
]


@pytest.mark.parametrize(("context", "old", "new"), MAPPED, ids=[f"{c}-{i}" for i, (c, _, _) in enumerate(MAPPED)])
def test_the_mapping_of_a_0_9_element(context, old, new):
    """Each row of docs/openscenario.md's 0.9 table on an element: its 1.0 form, written by hand."""
    from ego.openscenario import v09
    from ego.openscenario.xmltree import parse_bytes

    mapped = v09._Migration("t.xosc").child(parse_bytes(old.encode()), context)
    assert [_tree(n) for n in mapped] == [_tree(parse_bytes(new.encode()))]


def test_a_0_9_vehicle_gets_the_reference_players_acceleration_unless_it_gives_one(tmp_path):
    """0.9's Performance has no maxAcceleration (1.0 requires one): the reference player's
    default 10 m/s^2 (as for a 1.x file without one), or the one written there; the catalog entry's own parameter ($Length) and box
    (centre x 1.4) as the 0.9 file gives them."""
    path = write(tmp_path)
    lead = load(path).entities["Lead"].vehicle
    assert (lead.max_accel, lead.max_decel, lead.max_speed) == (4.0, 9.0, 55.0)
    assert (lead.length, lead.width, lead.center_x) == (4.5, 1.8, 1.4)
    (tmp_path / "catalogs" / "Cars.xosc").write_text(CATALOG_09.replace(' maxAcceleration="4"', ""))
    assert load(path).entities["Lead"].vehicle.max_accel == PERFORMANCE_DEFAULTS["maxAcceleration"] == 10.0
