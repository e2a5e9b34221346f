"""Files that break the schema the way the reference player's examples do, read as the reference
player (esmini) reads them - each a documented deviation (docs/openscenario.md), most with a
warning naming the line: a vehicle's Performance left out (esmini's defaults), a comment before
the XML declaration, a parameter declared twice in one scope (the last holds), a
RelativeTargetSpeed without speedTargetValueType (delta), a ClothoidSpline's pre-standard
curvStart/curvEnd, an empty ManeuverGroup. Real SUMO runs where a run is the point."""

from __future__ import annotations

from pathlib import Path

import pytest
from xosc_scenes import event, run_scene, scene, sim_time, speed, trigger

from ego.cli import main
from ego.openscenario import model as M
from ego.openscenario.loader import PERFORMANCE_DEFAULTS, load

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "openscenario"
EB = (SHIPPED / "emergency_brake.xosc").read_text()
LEAD_PERF = '<Performance maxSpeed="55" maxAcceleration="2.6" maxDeceleration="4.5"/>'


def _eb(tmp_path: Path, text: str) -> Path:
    (tmp_path / "straight3.xodr").write_bytes((SHIPPED / "straight3.xodr").read_bytes())
    path = tmp_path / "case.xosc"
    path.write_text(text)
    return path


def _line(text: str, marker: str) -> int:
    return text.count("\n", 0, text.index(marker)) + 1


def _run(path: Path, capsys, *extra: str) -> str:
    assert main(["run", str(path), "-c", "pid", "--set", "duration=2", *extra]) == 0
    return capsys.readouterr().err


def test_performance_left_out_is_the_reference_players_default(tmp_path, capsys):
    """esmini's straight_500m.xosc has no maxAcceleration: esmini's Vehicle defaults (100 m/s,
    10 m/s^2, 10 m/s^2; Entities.cpp) fill in, with a warning; the run goes on."""
    assert PERFORMANCE_DEFAULTS == {"maxSpeed": 100.0, "maxAcceleration": 10.0, "maxDeceleration": 10.0}
    text = EB.replace(LEAD_PERF, '<Performance maxDeceleration="4.5"/>')
    path = _eb(tmp_path, text)
    lead = load(path).entities["Lead"].vehicle
    assert (lead.max_speed, lead.max_accel, lead.max_decel) == (100.0, 10.0, 4.5)
    capsys.readouterr()
    line = _line(text, '<Performance maxDeceleration="4.5"/>')
    warning = f"ego: warning: {path}:{line}: <Performance> of Lead has no max{{}} (the schema requires it): {{}}"
    err = _run(path, capsys)
    assert err.splitlines() == [
        warning.format("Speed", "100 m/s, the reference player's default"),
        warning.format("Acceleration", "10 m/s^2, the reference player's default"),
    ]


def test_comment_before_the_xml_declaration(tmp_path, capsys):
    """esmini's two_plus_one_road.xosc starts with comments, then <?xml ...?>: read as if the
    declaration came first, every line where it was (an error names the right line)."""
    head = "<!-- Demonstrate a 2+1 road -->\n<!-- A white car ... -->\n"
    text = head + EB
    path = _eb(tmp_path, text)
    assert _run(path, capsys) == ""
    bad = head + EB.replace('<Story name="LeadBrakes">', '<Story name="LeadBrakes"><Oops/>')
    path.write_text(bad)
    assert main(["run", str(path), "-c", "pid"]) == 2
    line = _line(bad, "<Oops/>")
    assert capsys.readouterr().err == (
        f"ego: error: {path}:{line}: <Oops> is not supported by ego (see docs/openscenario.md)\n"
    )


def test_a_parameter_declared_twice_holds_its_last_value(tmp_path, capsys):
    """esmini's follow_reference.xosc declares lane_change_duration twice: esmini's declarations
    stack with the latest found first (Parameters.cpp), so the last holds; --set sets it."""
    decl = '<ParameterDeclaration name="EgoFront" parameterType="double" value="300"/>'
    assert decl in EB
    text = EB.replace(decl, decl + '\n    <ParameterDeclaration name="EgoFront" parameterType="double" value="310"/>')
    path = _eb(tmp_path, text)
    scenario = load(path)
    second = _line(text, 'value="310"')
    assert scenario.values["EgoFront"] == 310.0 and scenario.parameters["EgoFront"].line == second
    assert load(path, {"EgoFront": 320.0}).values["EgoFront"] == 320.0
    capsys.readouterr()
    err = _run(path, capsys)
    assert err == (
        f"ego: warning: {path}:{second}: parameter 'EgoFront' is declared twice (first on "
        f"line {_line(text, decl)}): this last declaration holds, as the reference player reads it\n"
    )


def test_relative_target_speed_without_its_value_type_is_delta(tmp_path, capsys):
    """esmini's highway_merge.xosc leaves out speedTargetValueType: delta, as esmini reads it
    (ScenarioReader.cpp: "falling back to delta"). A takes B's speed (15 m/s) - 2 in a step."""
    target = '<RelativeTargetSpeed entityRef="B" value="-2" continuous="false"/>'
    action = speed(0.0).replace('<AbsoluteTargetSpeed value="0.0"/>', target)
    assert target in action
    path = scene(tmp_path, [event("E", "A", action, trigger([sim_time(0.95)]))])
    (a,) = [x for x in M.walk(load(path).stories) if isinstance(x, M.SpeedAction)]
    assert (a.relative_to, a.relative_kind, a.value) == ("B", "delta", -2.0)
    sc = run_scene(path, 2.0)
    assert sc._history["A"][-1][1] == pytest.approx(13.0, abs=1e-6)  # B's 15 m/s - 2 (a factor: -30)
    assert "<RelativeTargetSpeed> has no speedTargetValueType (the schema requires it): delta" in (
        capsys.readouterr().err
    )


def _segments(tmp_path: Path, spline: str) -> tuple[M.ClothoidSegment, ...]:
    follow = (
        '<RoutingAction><FollowTrajectoryAction><TrajectoryRef><Trajectory name="t" closed="false"><Shape>'
        f"{spline}</Shape></Trajectory></TrajectoryRef><TimeReference><None/></TimeReference>"
        '<TrajectoryFollowingMode followingMode="position"/></FollowTrajectoryAction></RoutingAction>'
    )
    tmp_path.mkdir()
    path = scene(tmp_path, [event("T", "C", follow, trigger([sim_time(0.95)]))])
    (a,) = [x for x in M.walk(load(path).stories) if isinstance(x, M.FollowTrajectoryAction)]
    return a.segments


def test_clothoid_spline_segments_in_the_reference_players_spelling(tmp_path):
    """esmini's lane-change_clothoid_spline_based_trajectory.xosc writes curvStart/curvEnd and
    leaves some out (ScenarioReader.cpp: a missing start is the previous segment's end, a missing
    end the segment's start): an arc, a straight, an arc back, then a clothoid."""
    standard = _segments(
        tmp_path / "a",
        '<ClothoidSpline><Segment curvatureStart="0.02" curvatureEnd="0.02" length="10"/>'
        '<Segment curvatureStart="0" curvatureEnd="0" length="5"/>'
        '<Segment curvatureStart="-0.02" curvatureEnd="-0.02" length="10"/>'
        '<Segment curvatureStart="-0.02" curvatureEnd="0" length="5"/></ClothoidSpline>',
    )
    esmini = _segments(
        tmp_path / "b",
        '<ClothoidSpline><Segment curvStart="0.02" length="10"/><Segment curvStart="0.0" length="5"/>'
        '<Segment curvStart="-0.02" length="10"/><Segment curvEnd="0" length="5"/></ClothoidSpline>',
    )
    assert [(s.k0, s.k1, s.length) for s in esmini] == [(s.k0, s.k1, s.length) for s in standard]
    assert [(s.k0, s.k1) for s in esmini] == [(0.02, 0.02), (0.0, 0.0), (-0.02, -0.02), (-0.02, 0.0)]


def test_an_empty_maneuver_group_does_nothing(tmp_path, capsys):
    """esmini's straight_500m.xosc has a ManeuverGroup with no Actors (required) and no Maneuver."""
    start = EB.index('<ManeuverGroup name="LeadGroup"')
    text = EB[:start] + '<ManeuverGroup name="Dummy" maximumExecutionCount="1">\n</ManeuverGroup>' + EB[start:]
    path = _eb(tmp_path, text)
    groups = load(path).stories[0].acts[0].groups
    assert [(g.name, g.actors, g.maneuvers) for g in groups][0] == ("Dummy", (), ())
    _run(path, capsys)
