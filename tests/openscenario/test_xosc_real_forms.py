"""Forms the industry's files use that ego's own files did not: parameters declared inside a
Story and inside a Trajectory (empty too) with the standard's scoping, descriptive elements
(License, File), speed dynamics of value 0 (a step) and negative rates (read by magnitude, as
the reference player reads them). Each file here is hand-written for the test."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest
from xosc_scenes import event, run_scene, scene, sim_time, speed, starts, trigger

from ego.openscenario import model as M
from ego.openscenario.dynamics import Transition, speed_duration
from ego.openscenario.loader import load

SHIPPED = Path(__file__).resolve().parents[2] / "scenarios" / "openscenario"


def _edit(path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new, 1))


def _actions(sc: M.Scenario) -> dict[str, M.PrivateAction]:
    return {
        a.name: a.action
        for st in sc.stories
        for act in st.acts
        for g in act.groups
        for man in g.maneuvers
        for ev in man.events
        for a in ev.actions
    }


def test_story_parameters_are_scoped_to_their_story(tmp_path):
    """A Story's ParameterDeclarations are seen inside it and shadow the file's; outside the
    story (here: the Init) the file's value holds."""
    path = scene(
        tmp_path,
        [event("E", "A", speed("$Target"), trigger([sim_time("$When")]))],
        params='<ParameterDeclaration name="Target" parameterType="double" value="10"/>'
        '<ParameterDeclaration name="When" parameterType="double" value="1"/>',
    )
    _edit(
        path,
        '<Story name="S">',
        '<Story name="S"><ParameterDeclarations>'
        '<ParameterDeclaration name="Target" parameterType="double" value="${$When * 30}"/>'
        "</ParameterDeclarations>",
    )
    sc = load(path)
    action = _actions(sc)["EAction"]
    assert isinstance(action, M.SpeedAction) and action.value == 30.0
    assert sc.values["Target"] == 10.0  # the file's own value is unchanged
    # --set reaches the file's parameter the story's declaration refers to
    assert _actions(load(path, {"When": 2.0}))["EAction"].value == 60.0  # type: ignore[union-attr]


def test_trajectory_parameters_and_descriptive_elements(tmp_path):
    verts = "".join(
        f'<Vertex time="{t}"><Position><WorldPosition x="{x}" y="-3.5"/></Position></Vertex>'
        for t, x in ((0, 420), (2, "$EndX"))
    )
    traj = (
        '<RoutingAction><FollowTrajectoryAction><Trajectory name="t" closed="false"><ParameterDeclarations>'
        '<ParameterDeclaration name="EndX" parameterType="double" value="460"/></ParameterDeclarations>'
        f"<Shape><Polyline>{verts}</Polyline></Shape></Trajectory><TimeReference><None/></TimeReference>"
        "</FollowTrajectoryAction></RoutingAction>"
    )
    empty = traj.replace(
        '<ParameterDeclarations><ParameterDeclaration name="EndX" parameterType="double" value="460"/>'
        "</ParameterDeclarations>",
        "<ParameterDeclarations/>",
    ).replace("$EndX", "470")
    path = scene(
        tmp_path, [event("T", "C", traj, trigger([sim_time(1)])), event("U", "B", empty, trigger([sim_time(1)]))]
    )
    _edit(path, 'author="ego tests"/>', 'author="ego tests"><License name="CC-BY-SA-4.0"/></FileHeader>')
    _edit(
        path,
        'maxDeceleration="4.5"/>',
        'maxDeceleration="4.5"/><Properties><Property name="p" value="1"/><File filepath="car.osgb"/></Properties>',
    )
    actions = _actions(load(path))
    assert actions["TAction"].vertices[1].position.x == 460.0  # type: ignore[union-attr]
    assert actions["UAction"].vertices[1].position.x == 470.0  # type: ignore[union-attr]


def test_a_trajectory_parameter_is_not_seen_outside_it(tmp_path):
    traj = (
        '<RoutingAction><FollowTrajectoryAction><Trajectory name="t" closed="false"><ParameterDeclarations>'
        '<ParameterDeclaration name="EndX" parameterType="double" value="460"/></ParameterDeclarations>'
        '<Shape><Polyline><Vertex><Position><WorldPosition x="420" y="-3.5"/></Position></Vertex>'
        '<Vertex><Position><WorldPosition x="$EndX" y="-3.5"/></Position></Vertex></Polyline></Shape>'
        "</Trajectory><TimeReference><None/></TimeReference></FollowTrajectoryAction></RoutingAction>"
    )
    path = scene(tmp_path, [event("T", "C", traj, trigger([sim_time(1)])), event("V", "B", speed("$EndX"), None)])
    with pytest.raises(Exception, match=r"scene.xosc:\d+: parameter '\$EndX' is not declared"):
        load(path)


def test_zero_value_is_a_step_and_negative_rates_are_read_by_magnitude(tmp_path):
    path = scene(
        tmp_path,
        [
            event("Zero", "A", speed(20, "linear", "time", 0.0), trigger([sim_time(1)])),
            event("ZeroRate", "B", speed(20, "linear", "rate", 0.0), trigger([sim_time(1)])),
            event("Brake", "C", speed(7, "linear", "rate", -4.0), trigger([sim_time(1)])),
        ],
    )
    actions = _actions(load(path))
    assert actions["ZeroAction"].dynamics == M.Dynamics("step", "time", 0.0)  # type: ignore[union-attr]
    assert actions["ZeroRateAction"].dynamics == M.Dynamics("step", "rate", 0.0)  # type: ignore[union-attr]
    assert actions["BrakeAction"].dynamics == M.Dynamics("linear", "rate", 4.0)  # type: ignore[union-attr]


def test_a_negative_duration_is_still_refused(tmp_path):
    path = scene(tmp_path, [event("N", "A", speed(20, "linear", "time", -1.0), trigger([sim_time(1)]))])
    with pytest.raises(Exception, match=r"bad value for value in <SpeedActionDynamics>: -1 \(expected >= 0\)"):
        load(path)


@pytest.mark.sumo
def test_a_negative_braking_rate_brakes_as_its_magnitude(tmp_path):
    """C brakes from 15 to 7 m/s at -4 m/s^2 (the reference player's form): SUMO's speed is the
    closed-form linear profile of rate 4 within 1e-6, and A's value-0 change is a step."""
    evs = [
        event("Brake", "C", speed(7, "linear", "rate", -4.0), trigger([sim_time(0.95)])),
        event("Zero", "A", speed(20, "linear", "time", 0.0), trigger([sim_time(0.95)])),
    ]
    sc = run_scene(scene(tmp_path, evs), 4.0)
    brake = Transition(1.0, 15.0, 7.0, speed_duration("linear", "rate", 4.0, 15.0, 7.0), "linear")
    step = Transition(1.0, 25.0, 20.0, 0.0, "step")
    for t, v, _ in sc._history["C"]:
        assert v == pytest.approx(brake.value(t), abs=1e-6), t
    for t, v, _ in sc._history["A"]:
        assert v == pytest.approx(step.value(t), abs=1e-6), t


def _state(ref: str, st: str, kind: str) -> str:
    return trigger(
        [
            f'<Condition name="s" delay="0" conditionEdge="none"><ByValueCondition>'
            f'<StoryboardElementStateCondition storyboardElementType="{kind}" '
            f'storyboardElementRef="{ref}" state="{st}"/></ByValueCondition></Condition>'
        ]
    )


@pytest.mark.sumo
def test_qualified_references_resolve(tmp_path):
    """``Event::Action`` and ``Story::Act::Group::Maneuver::Event`` (OpenSCENARIO 1.1) name
    the element they end with: the dependent events start as the plain names' would (a
    state condition sees a transition one step after it happened)."""
    evs = [
        event("First", "A", speed(25), trigger([sim_time(0.95)])),
        event("ByAction", "C", speed(15), _state("First::FirstAction", "completeState", "action")),
        event("ByPath", "B", speed(15), _state("S::Act::GA::MA::First", "startTransition", "event")),
    ]
    sc = run_scene(scene(tmp_path, evs), 2.0)
    assert starts(sc, "First") == [pytest.approx(1.0)]
    assert starts(sc, "ByPath") == [pytest.approx(1.1)]
    assert starts(sc, "ByAction") == [pytest.approx(1.2)]


def test_an_unknown_reference_names_its_own_line(tmp_path):
    evs = [
        event("First", "A", speed(25), trigger([sim_time(0.95)])),
        event("Bad", "C", speed(15), _state("Other::FirstAction", "completeState", "action")),
    ]
    path = scene(tmp_path, evs)
    path.write_text(path.read_text().replace("<StoryboardElementStateCondition", "\n<StoryboardElementStateCondition"))
    line = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if "StoryboardElementStateCondition" in t)
    with pytest.raises(Exception, match=rf"scene.xosc:{line}: unknown storyboard action 'Other::FirstAction'"):
        load(path)


# -- one validation path: ego list checks what ego run checks ------------------------------------
def _cut_in(tmp_path):
    shutil.copytree(SHIPPED / "catalogs", tmp_path / "catalogs")
    shutil.copy(SHIPPED / "straight3.xodr", tmp_path / "straight3.xodr")
    path = tmp_path / "cut_in.xosc"
    path.write_text((SHIPPED / "cut_in.xosc").read_text())
    return path


def _list_and_run(path, capsys) -> tuple[dict, str]:
    from ego.cli import main

    assert main(["list", str(path), "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 2
    return listing, capsys.readouterr().err.strip()


def _line(path, marker: str) -> int:
    text = path.read_text()
    return text.count("\n", 0, text.index(marker)) + 1


def test_list_refuses_what_run_refuses(tmp_path, capsys):
    """A trailer attached in a vehicle catalog entry, a bad attribute value and an Init action
    outside the subset: ego list says NOT SUPPORTED with ego run's own one-line error, which
    names the line of the element itself."""
    path = _cut_in(tmp_path)
    cat = tmp_path / "catalogs" / "VehicleCatalog.xosc"
    cat.write_text(
        cat.read_text().replace(
            "</Axles>", '</Axles>\n      <TrailerHitch dx="-1"/><Trailer><EntityRef entityRef="T"/></Trailer>'
        )
    )
    listing, err = _list_and_run(path, capsys)
    assert listing["supported"] is False
    assert listing["error"] == (
        f"{cat}:{_line(cat, '<Trailer>')}: a trailer (entityRef 'T') is not supported by ego: it runs single vehicles"
        " (see docs/openscenario.md)"
    )
    assert err == f"ego: error: {listing['error']}"

    path = _cut_in(tmp_path / "b")
    text = path.read_text()
    path.write_text(text.replace('maximumExecutionCount="1"', 'maximumExecutionCount="once"', 1))
    listing, err = _list_and_run(path, capsys)
    assert listing["supported"] is False and err == f"ego: error: {listing['error']}"
    assert listing["error"].startswith(f"{path}:{_line(path, 'maximumExecutionCount=')}: bad value")

    path = _cut_in(tmp_path / "c")
    text = path.read_text()
    # (an action that takes time runs from t = 0 in Init; a parameter's value is declared)
    name = text.split('<ParameterDeclaration name="', 1)[1].split('"', 1)[0]
    setting = f'<GlobalAction>\n<ParameterAction parameterRef="{name}"><SetAction value="1"/></ParameterAction></GlobalAction>'
    i = text.index("<Private", text.index("<Init>"))
    path.write_text(text[:i] + setting + text[i:])
    listing, err = _list_and_run(path, capsys)
    assert listing["supported"] is False and err == f"ego: error: {listing['error']}"
    assert listing["error"].startswith(f"{path}:{text.count(chr(10), 0, i) + 2}: <ParameterAction> in <Init>")


def unsupported_text(tag: str) -> str:
    return f"<{tag}> is not supported by ego (see docs/openscenario.md)"


def test_a_parameter_declared_twice_is_handled_alike(tmp_path, capsys):
    """Twice in different scopes (the file's and a story's) is shadowing: list and run accept
    it; twice in one scope too, with a warning naming the second declaration's line."""
    from ego.cli import main

    path = _cut_in(tmp_path)
    text = path.read_text()
    first = text[text.index("<ParameterDeclaration ") : text.index("/>", text.index("<ParameterDeclaration ")) + 2]
    path.write_text(_story_decl(text, first))
    assert main(["list", str(path), "--json"]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert listing["supported"] is True and listing["error"] is None
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 0
    capsys.readouterr()

    # twice in one scope: the last declaration holds, as the reference player reads it; list and
    # run both accept it and warn once naming the second declaration's line
    path.write_text(text.replace(first, first + "\n    " + first, 1))
    name = first.split('name="', 1)[1].split('"', 1)[0]
    warning = (
        f"ego: warning: {path}:{_line(path, first) + 1}: parameter {name!r} is declared twice (first on line "
        f"{_line(path, first)}): this last declaration holds, as the reference player reads it"
    )
    assert main(["list", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["supported"] is True and err.strip() == warning
    assert main(["run", str(path), "-c", "pid", "--set", "duration=1"]) == 0
    assert capsys.readouterr().err.strip() == warning


def _story_decl(text: str, decl: str) -> str:
    i = text.index(">", text.index("<Story ")) + 1
    return text[:i] + f"<ParameterDeclarations>{decl}</ParameterDeclarations>" + text[i:]


# -- roads netconvert splits or refuses -----------------------------------------------------------
LOOP = """<?xml version="1.0" encoding="UTF-8"?>
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="loop" version="1.0"/>
  <road name="loop" length="628.3185307179586" id="1" junction="-1">
    <link><predecessor elementType="road" elementId="1" contactPoint="end"/>
    <successor elementType="road" elementId="1" contactPoint="start"/></link>
    <planView><geometry s="0" x="0" y="-100" hdg="0" length="628.3185307179586"><arc curvature="0.01"/></geometry>
    </planView>
    <lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center><right>
      <lane id="-1" type="driving" level="false"><link/><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
    </right></laneSection></lanes>
  </road>
</OpenDRIVE>
"""


def test_a_road_netconvert_splits_resolves(tmp_path):
    """A road that loops onto itself is split by netconvert into ``-1#0`` and ``-1#1``; an s
    past the first piece is on the second, each piece starting at the road s where the one
    before it ends (its reference line's length), and (road, lane, s) is the lane's point on
    the normal of the reference line at s: on this circle of radius 100 m (the reference
    line, about the origin from (0, -100) anticlockwise) the lane's centre is at radius
    101.75 m and angle s / 100 from the start."""
    from ego.lane_frame import LanePolyline
    from ego.openscenario.roads import RoadMap, network_file

    road = tmp_path / "loop.xodr"
    road.write_text(LOOP)
    roads = RoadMap(network_file(road), converted=True)
    assert sorted(roads.edges) == ["-1#0", "-1#1"]
    first = roads.reference("-1#0").length
    assert first == pytest.approx(math.pi * 100.0, abs=2e-3)
    for s, edge in ((100.0, "-1#0"), (first + 50.0, "-1#1"), (500.0, "-1#1")):
        lane, g = roads.lane_s("1", -1, s)
        assert lane.edge == edge
        x, y = LanePolyline(lane.shape).offset_point(g, 0.0)
        a = s / 100.0
        assert math.hypot(x - 101.75 * math.sin(a), y + 101.75 * math.cos(a)) < 1e-3
        assert roads.road_s(lane, g) == pytest.approx(s, abs=1e-9)
        # SUMO's lane position: this one-lane edge's SUMO length is its shape's
        assert roads.lane_position("1", -1, s)[1] == pytest.approx(g * lane.length / roads.shape_length(lane))
    with pytest.raises(ValueError, match=r"unknown road '2' \(roads: 1\)"):
        roads.lane_position("2", -1, 10.0)


def test_a_signal_with_an_empty_type_converts(tmp_path):
    from ego.openscenario.roads import RoadMap, network_file

    text = (SHIPPED / "straight3.xodr").read_text()
    signal = (
        '<signals><signal s="500" t="-6" id="s1" name="sign" dynamic="no" orientation="+" zOffset="1" '
        'country="DE" type="" subtype="" value="-1" height="1" width="1"/></signals>'
    )
    road = tmp_path / "signed.xodr"
    road.write_text(text.replace("  </road>", signal + "\n  </road>"))
    roads = RoadMap(network_file(road), converted=True)
    lane, pos = roads.lane_position("0", -2, 600.0)
    assert (lane.edge, pos) == ("-0", 600.0)
    assert ' type="" subtype=""' in road.read_text()  # the file itself is not changed
    assert not [p for p in network_file(road).parent.iterdir() if p.suffix == ".xodr"]
