"""The TimeOfDayCondition in real runs: the Init's TimeOfDay moving on with the simulation time
(animated) or standing still, against times written with and without a zone; its refusals."""

from __future__ import annotations

import pytest
from xosc_scenes import event, run_scene, scene, speed, starts, trigger

from ego.openscenario.xmltree import ScenarioFileError


def _environment(time: str, animation: bool) -> str:
    return (
        '<GlobalAction><EnvironmentAction><Environment name="env">'
        f'<TimeOfDay animation="{str(animation).lower()}" dateTime="{time}"/>'
        "</Environment></EnvironmentAction></GlobalAction>"
    )


def _scene(tmp, condition_time: str, rule: str = "greaterOrEqual", init: str | None = None, story: str = ""):
    cond = (
        '<Condition name="c" delay="0" conditionEdge="none"><ByValueCondition>'
        f'<TimeOfDayCondition dateTime="{condition_time}" rule="{rule}"/></ByValueCondition></Condition>'
    )
    path = scene(tmp, [event("E", "A", speed(20.0), trigger([cond]))])
    text = path.read_text()
    if init is not None:
        text = text.replace("<Init><Actions>", "<Init><Actions>" + init, 1)
    if story:
        text = text.replace('<Act name="Act">', '<Act name="Act">' + story, 1)
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "when, animated, expect",
    [
        ("2025-06-13T12:00:00", True, [2.0]),  # 2 s after the start's 11:59:58
        ("2025-06-13T14:00:01.5+02:00", True, [3.5]),  # 12:00:01.5 UTC
        ("2025-06-13T12:00:00Z", False, []),  # the time stands still at 11:59:58
        ("2025-06-13T11:59:58", False, [0.0]),
    ],
)
def test_the_time_of_day_moves_on_with_the_simulation_when_animated(tmp_path, when, animated, expect):
    init = _environment("2025-06-13T11:59:58.000+00:00", animated)
    sc = run_scene(_scene(tmp_path, when, init=init), 5.0)
    assert starts(sc, "E") == [pytest.approx(t) for t in expect]


def test_a_time_of_day_condition_without_its_init_time_or_with_a_changed_one_is_refused(tmp_path):
    with pytest.raises(ScenarioFileError, match=r"needs the time of day the scenario starts at"):
        run_scene(_scene(tmp_path, "2025-06-13T12:00:00"), 1.0)
    changed = (
        '<ManeuverGroup maximumExecutionCount="1" name="G"><Actors selectTriggeringEntities='
        '"false"/><Maneuver name="M"><Event name="Night" priority="parallel"><Action name="N">'
        + _environment("2025-06-13T23:00:00", True)
        + '</Action><StartTrigger><ConditionGroup><Condition name="t" delay="0" conditionEdge="none">'
        '<ByValueCondition><SimulationTimeCondition value="1" rule="greaterThan"/></ByValueCondition></Condition>'
        "</ConditionGroup></StartTrigger></Event></Maneuver></ManeuverGroup>"
    )
    init = _environment("2025-06-13T11:59:58", True)
    with pytest.raises(ScenarioFileError, match=r"where the storyboard changes the time of day \(line \d+\)"):
        run_scene(_scene(tmp_path, "2025-06-13T12:00:00", init=init, story=changed), 1.0)
    with pytest.raises(ScenarioFileError, match=r"bad value for dateTime in <TimeOfDayCondition>: 'noon'"):
        run_scene(_scene(tmp_path, "noon", init=init), 1.0)
