"""The ego's controller's properties as ego parameters (ego/openscenario/controller_properties.py,
docs/openscenario.md "Controller properties"): the value reaches the run in SUMO, ``--set``
rules, a value outside the parameter's range is one line before anything runs, ``ego list``
says what ``ego run`` does, and only the ego's controller, active from the start, counts."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import pytest
from xosc_scenes import CAR, SHIPPED, run_scene

from ego.cli import main
from ego.openscenario.controller_properties import MAPPED, NOT_USED, ego_controller
from ego.openscenario.loader import load
from ego.openscenario.scenario import ACC_ACCEL, FileConfig, file_scenario_class
from ego.openscenario.xmltree import ScenarioFileError

pytestmark = pytest.mark.sumo

#: the lead car's speed (m/s) and the ego's Init speed (m/s)
LEAD_SPEED, EGO_SPEED = 15.0, 20.0


def _speed(v: float) -> str:
    return (
        '<PrivateAction><LongitudinalAction><SpeedAction><SpeedActionDynamics dynamicsShape="step" value="0" '
        f'dynamicsDimension="time"/><SpeedActionTarget><AbsoluteTargetSpeed value="{v}"/></SpeedActionTarget>'
        "</SpeedAction></LongitudinalAction></PrivateAction>"
    )


def _at(s: float) -> str:
    return (
        '<PrivateAction><TeleportAction><Position><LanePosition roadId="0" laneId="-2" s="'
        f'{s}" offset="0"/></Position></TeleportAction></PrivateAction>'
    )


ACTIVATE = '<PrivateAction><ActivateControllerAction longitudinal="true" lateral="false"/></PrivateAction>'


def write(
    tmp: Path,
    props: dict[str, str],
    *,
    kind: str = "ACCController",
    lead: bool = True,
    activate: str = "init",
    on: str = "Ego",
) -> Path:
    """Ego (20 m/s, lane -2, s = 300 m) with an inline ``kind`` controller of ``props`` on
    entity ``on``; a lead car 100 m ahead at 15 m/s; ``evade`` false (an ACC follows in its
    lane). ``activate``: "init" (an ActivateControllerAction in Init), "story" (in an event
    at t = 1 s) or "" (none)."""
    shutil.copy(SHIPPED / "straight3.xodr", tmp / "straight3.xodr")
    rows = "".join(f'<Property name="{k}" value="{v}"/>' for k, v in props.items())
    control = (
        f'<ObjectController><Controller name="{kind}"><Properties>{rows}</Properties></Controller></ObjectController>'
    )
    ents = f'<ScenarioObject name="Ego">{CAR}{control if on == "Ego" else ""}</ScenarioObject>'
    if lead:
        ents += f'<ScenarioObject name="lead">{CAR}{control if on == "lead" else ""}</ScenarioObject>'
    init = f'<Private entityRef="Ego">{_at(300.0)}{_speed(EGO_SPEED)}{ACTIVATE if activate == "init" else ""}</Private>'
    if lead:
        init += f'<Private entityRef="lead">{_at(404.5)}{_speed(LEAD_SPEED)}</Private>'
    story = ""
    if activate == "story":
        story = (
            '<Story name="S"><Act name="A"><ManeuverGroup name="G" maximumExecutionCount="1"><Actors '
            'selectTriggeringEntities="false"><EntityRef entityRef="Ego"/></Actors><Maneuver name="M"><Event '
            'name="On" priority="parallel"><Action name="Act"><PrivateAction><ActivateControllerAction '
            'longitudinal="true" lateral="false"/></PrivateAction></Action><StartTrigger><ConditionGroup><Condition '
            'name="c" delay="0" conditionEdge="none"><ByValueCondition><SimulationTimeCondition value="1" '
            'rule="greaterThan"/></ByValueCondition></Condition></ConditionGroup></StartTrigger></Event></Maneuver>'
            '</ManeuverGroup><StartTrigger><ConditionGroup><Condition name="c0" delay="0" conditionEdge="none">'
            '<ByValueCondition><SimulationTimeCondition value="0" rule="greaterOrEqual"/></ByValueCondition>'
            "</Condition></ConditionGroup></StartTrigger></Act></Story>"
        )
    path = tmp / "acc.xosc"
    path.write_text(
        f"""<?xml version="1.0"?>
<OpenSCENARIO>
<FileHeader revMajor="1" revMinor="2" date="2026-11-29T00:00:00" description="acc" author="ego tests"/>
<ParameterDeclarations>
<ParameterDeclaration name="SetSpeed" parameterType="double" value="25"/>
<ParameterDeclaration name="evade" parameterType="boolean" value="false"/>
</ParameterDeclarations>
<RoadNetwork><LogicFile filepath="straight3.xodr"/></RoadNetwork>
<Entities>{ents}</Entities>
<Storyboard><Init><Actions>{init}</Actions></Init>{story}<StopTrigger/></Storyboard>
</OpenSCENARIO>
"""
    )
    return path


ACC = {"mode": "override", "setSpeed": "$SetSpeed", "timeGap": "1.5", "lateralDist": "5"}


def _event(run, kind: str) -> str:
    return next(e.text for e in run.events if e.kind == kind)


def test_set_speed_is_the_cruise_speed_the_ego_settles_at(tmp_path):
    """No car ahead: the ego starts at its Init 20 m/s and its cruise reference moves to the
    ACC's setSpeed 25 m/s at 2 m/s^2 (done at t = 2.5 s); pid brings the ego there (within
    0.05 m/s at t = 15 s)."""
    run = run_scene(write(tmp_path, ACC, lead=False), 15.0)
    assert run.config.cruise_speed == 25.0 and run.config.ego_speed == EGO_SPEED
    assert run.ego.state[1] == pytest.approx(25.0, abs=0.05)
    assert (25.0 - EGO_SPEED) / ACC_ACCEL == pytest.approx(2.5)
    text = _event(run, "controller")
    assert "setSpeed 25 -> cruise_speed" in text and "timeGap 1.5 -> follow_headway" in text
    assert "read, not used: mode, lateralDist" in text


def test_time_gap_is_the_gap_the_ego_keeps_behind_a_slower_car(tmp_path):
    """Behind the lead at 15 m/s the ego (closing from 25 m/s) brakes in lane at its TTC
    trigger and follows: the gap settles at follow_gap + timeGap x the lead's speed
    (5 + 1.5 x 15 = 27.5 m; within 0.5 m at t = 60 s, pid's integral still closing the last
    decimetres), the ego at the lead's speed."""
    run = run_scene(write(tmp_path, ACC), 60.0)
    assert run.config.follow_headway == 1.5
    want = run.config.follow_gap + 1.5 * LEAD_SPEED
    assert run.view.gap_front == pytest.approx(want, abs=0.5)
    assert run.ego.state[1] == pytest.approx(LEAD_SPEED, abs=0.05)


def test_set_on_the_command_line_beats_the_property(tmp_path):
    """--set follow_headway=2.0 rules over timeGap 1.5: the gap settles at 5 + 2 x 15 = 35 m,
    and the event says the property was overridden. (A shorter headway is a lower bound: the
    in-lane braking ramp, at brake_decel down to the lead's speed, leaves the ego ~22 m behind
    here, and ego keeps that larger gap rather than closing in: docs/openscenario.md.)"""
    run = run_scene(write(tmp_path, ACC), 60.0, follow_headway=2.0)
    assert run.config.follow_headway == 2.0
    assert run.view.gap_front == pytest.approx(run.config.follow_gap + 2.0 * LEAD_SPEED, abs=0.5)
    assert "timeGap 1.5 -> follow_headway, overridden by --set (2)" in _event(run, "controller")


def test_a_value_outside_the_range_is_one_line_before_the_run(tmp_path, capsys):
    """timeGap 9 s (follow_headway allows 0 to 5 s): ego run exits 2 with one line naming the
    property's file:line, the value and the range; ego list says the same refusal."""
    path = write(tmp_path, {**ACC, "timeGap": "9"})
    line = next(i for i, t in enumerate(path.read_text().splitlines(), 1) if 'name="timeGap"' in t)
    assert main(["run", str(path), "-c", "pid"]) == 2
    err = capsys.readouterr().err.strip()
    want = f"{path}:{line}: controller property 'timeGap' = 9 is outside ego's follow_headway range [0, 5] s"
    assert err == f"ego: error: {want}"
    assert main(["list", str(path)]) == 0
    assert f"ego run refuses it: {want}" in capsys.readouterr().out
    # a set speed of -1 is no speed (cruise_speed's -1 means "hold ego_speed")
    with pytest.raises(ScenarioFileError, match=r"'setSpeed' = -1 is outside ego's cruise_speed range \[0, 60\]"):
        file_scenario_class(str(write(tmp_path, {**ACC, "setSpeed": "-1"}))).default_config({})
    with pytest.raises(ScenarioFileError, match=r"bad value for controller property 'timeGap': 'x' \(expected a"):
        file_scenario_class(str(write(tmp_path, {**ACC, "timeGap": "x"}))).default_config({})


def test_ego_list_shows_what_the_run_applies(tmp_path, capsys):
    """ego list FILE: the ego's parameters with the properties applied, and the run's event line."""
    path = write(tmp_path, ACC)
    assert main(["list", "--json", str(path)]) == 0
    import json

    listing = json.loads(capsys.readouterr().out)
    defaults = {p["name"]: p["default"] for p in listing["ego_parameters"]}
    assert defaults["cruise_speed"] == 25.0 and defaults["follow_headway"] == 1.5
    run = run_scene(path, 1.0)
    assert listing["controller"] == _event(run, "controller")
    assert (run.config.cruise_speed, run.config.follow_headway) == (25.0, 1.5)


@pytest.mark.parametrize(
    ("props", "kind", "activate", "on", "applied"),
    [
        (ACC, "ACCController", "init", "Ego", {"cruise_speed": 25.0, "follow_headway": 1.5}),
        (ACC, "ACCController", "", "Ego", {"cruise_speed": 25.0, "follow_headway": 1.5}),
        (ACC, "ACCController", "story", "Ego", {}),
        (ACC, "ACCController", "init", "lead", {}),
        ({"setSpeed": "25", "timeGap": "1.2"}, "ACCController", "init", "Ego", {"follow_headway": 1.2}),
        ({"timeGap": "1.2"}, "ALKSController", "init", "Ego", {"follow_headway": 1.2}),
        ({"timeGap": "1.2"}, "NaturalDriver", "init", "Ego", {}),
        ({"model": "ReferenceDriver", "aebTTC": "1.6"}, "ALKS_R157SM_Controller", "init", "Ego", {"aeb_ttc": 1.6}),
        ({"model": "Regulation", "aebTTC": "1.2"}, "ALKS_R157SM_Controller", "init", "Ego", {}),
        ({"esminiController": "ACCController", "timeGap": "2"}, "myAcc", "init", "Ego", {"follow_headway": 2.0}),
    ],
    ids=[
        "acc-init",
        "acc-never-activated",
        "acc-activated-by-story",
        "on-another-entity",
        "setSpeed-additive-mode",
        "alks",
        "other-kind",
        "r157-reference-driver",
        "r157-regulation",
        "kind-by-esminiController",
    ],
)
def test_which_properties_apply(tmp_path, props, kind, activate, on, applied):
    """Only the ego's controller, active from the start, of a kind (and with the companion
    properties) the table names: the reference player reads setSpeed only in override mode
    and aebTTC only for its ReferenceDriver model."""
    path = write(tmp_path, props, kind=kind, activate=activate, on=on)
    cls = file_scenario_class(str(path))
    config = cls.default_config({})
    defaults = FileConfig()
    for name in ("cruise_speed", "follow_headway", "aeb_ttc"):
        assert getattr(config, name) == applied.get(name, getattr(defaults, name)), name
    model = load(path)
    info = ego_controller(model, "Ego", cls.config_cls, 0)
    if on != "Ego":
        assert info.control is None


def test_the_table_names_ego_parameters_once():
    """Every mapped row is a FileConfig parameter with a unit; no property is both mapped and
    listed as not used for one controller kind."""
    fields = {f.name: f for f in dataclasses.fields(FileConfig)}
    for row in MAPPED:
        assert row.param in fields and fields[row.param].metadata["unit"] == row.unit
    mapped = {(r.name, k) for r in MAPPED for k in r.controllers}
    unused = {(n.name, k) for n in NOT_USED for k in n.controllers}
    assert not mapped & unused


def test_a_property_follows_the_file_parameter_it_names(tmp_path):
    """setSpeed="$SetSpeed": --set SetSpeed=22 (a sweep over it too) moves cruise_speed; a
    property beats a declaration of the same ego parameter in the file."""
    path = write(tmp_path, ACC)
    cls = file_scenario_class(str(path))
    assert cls.default_config({"SetSpeed": 22.0}).cruise_speed == 22.0
    text = path.read_text().replace(
        "</ParameterDeclarations>",
        '<ParameterDeclaration name="follow_headway" parameterType="double" value="0.8"/></ParameterDeclarations>',
    )
    declared = tmp_path / "declared.xosc"
    declared.write_text(text)
    assert file_scenario_class(str(declared)).default_config({}).follow_headway == 1.5
