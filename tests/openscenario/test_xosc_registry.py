"""The element registry (ego/openscenario/registry.py): the allow-list, the runtime dispatch
and the subset table come from one declaration per element, and docs/architecture.md's
worked example (a new action, one class) runs as written."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
from xosc_scenes import SHIPPED, event, run_scene, scene, sim_time, speed, starts, trigger

from ego.openscenario import loader, registry
from ego.openscenario import model as M
from ego.openscenario.loader import elements, load, read_tree
from ego.openscenario.xmltree import ScenarioFileError

ARCHITECTURE = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"


def block(section: str) -> str:
    text = ARCHITECTURE.read_text()
    return text.split(f"\n## {section}\n")[1].split("\n## ")[0].split("```python\n")[1].split("```")[0]


def test_every_action_and_condition_has_one_kind_and_every_kind_is_declared():
    allowed = registry.allowed()
    for tag, kind in registry.ACTIONS.items():
        assert tag in allowed and kind.tag == tag
        assert all(tag in allowed[parent] for parent in kind.within)
        assert all(child in allowed[tag] for child in kind.contains)
    # every condition ego reads is one registered kind, and nothing else is in the condition slots
    assert allowed["EntityCondition"] | allowed["ByValueCondition"] == set(registry.CONDITIONS)
    for model in (
        M.SpeedAction,
        M.LaneChangeAction,
        M.LaneOffsetAction,
        M.TeleportAction,
        M.FollowTrajectoryAction,
        M.ControllerAction,
        M.LongitudinalDistanceAction,
        M.EnvironmentAction,
        M.ParameterAction,
        M.SynchronizeAction,
        M.SpeedProfileAction,
        M.LateralDistanceAction,
        M.VisibilityAction,
    ):
        assert registry.action_of(model.__new__(model)).model is model
    # what the refusals name is derived from the kinds
    assert registry.init_kinds() == (
        "TeleportAction, ControllerAction, AppearanceAction, VisibilityAction, SpeedAction, LaneChangeAction, "
        "LaneOffsetAction, LongitudinalDistanceAction, LateralDistanceAction, SpeedProfileAction, SynchronizeAction, "
        "AssignRouteAction, AcquirePositionAction and FollowTrajectoryAction"
    )
    # a trajectory, a distance and a speed profile move the ego's references (ego_refs.py), a
    # teleport its plant (test_xosc_ego_teleport.py)
    assert {k.tag for k in registry.ACTIONS.values() if not k.on_ego} == {
        "LateralDistanceAction",
        "SynchronizeAction",
        "AssignRouteAction",
        "AcquirePositionAction",
    }


@pytest.mark.parametrize("path", sorted(SHIPPED.glob("*.xosc")), ids=lambda p: p.name)
def test_list_and_run_agree_on_every_shipped_file(path):
    """ego list's element marks and ego run's check read the same allow-list."""
    listed = all(ok for _, _, ok in elements(read_tree(path)))
    try:
        loader._check_root(path, read_tree(path))
        checked = True
    except ScenarioFileError:
        checked = False
    assert listed == checked


@pytest.fixture
def trailer(monkeypatch):
    """The architecture example registered; the registry restored afterwards."""
    monkeypatch.setattr(registry, "ELEMENTS", copy.deepcopy(registry.ELEMENTS))
    monkeypatch.setattr(registry, "ACTIONS", dict(registry.ACTIONS))
    monkeypatch.setattr(registry, "_BY_MODEL", dict(registry._BY_MODEL))
    monkeypatch.setattr(registry, "_ALLOWED", None)
    monkeypatch.setattr(loader, "ACTIONS", registry.ACTIONS)
    namespace: dict = {}
    exec(compile(block("Adding an OpenSCENARIO action"), str(ARCHITECTURE), "exec"), namespace)  # noqa: S102
    yield namespace


def _trailer(connect: bool = False) -> str:
    inner = '<ConnectTrailerAction trailerRef="B"/>' if connect else "<DisconnectTrailerAction/>"
    return f"<TrailerAction>{inner}</TrailerAction>"


def _scene(tmp_path, connect: bool = False) -> Path:
    done = (
        '<Condition name="hidden" delay="0" conditionEdge="none"><ByValueCondition>'
        '<StoryboardElementStateCondition storyboardElementType="action" storyboardElementRef="UnhitchAction" '
        'state="completeState"/></ByValueCondition></Condition>'
    )
    return scene(
        tmp_path,
        [
            event("Unhitch", "A", _trailer(connect), trigger([sim_time(1.0)])),
            event("Slow", "A", speed(20.0), trigger([done])),
        ],
    )


def test_a_new_action_is_refused_before_it_is_registered(tmp_path):
    path = _scene(tmp_path)
    with pytest.raises(ScenarioFileError, match=r"<TrailerAction> is not supported by ego"):
        load(path)
    assert ("TrailerAction", False) in [(tag, ok) for tag, _, ok in elements(read_tree(path))]


@pytest.mark.sumo
def test_the_architecture_example_adds_an_action_in_one_class(trailer, tmp_path):
    from ego.docs import subset
    from ego.openscenario.scenario import file_listing

    path = _scene(tmp_path)
    listing = file_listing(str(path))
    assert listing["supported"] and listing["error"] is None
    s = run_scene(path, duration=3.0)
    # the action completes in the step it starts; a state condition sees that a step later
    assert starts(s, "Unhitch") == [1.0] and starts(s, "Slow") == [pytest.approx(1.1)]
    bad = _scene(tmp_path, connect=True)
    line = next(i for i, text in enumerate(bad.read_text().splitlines(), 1) if "ConnectTrailerAction" in text)
    with pytest.raises(ScenarioFileError, match=rf":{line}: <ConnectTrailerAction> is not supported by ego"):
        load(bad)
    assert "| `TrailerAction` | yes | not listed | done at once: a `DisconnectTrailerAction` changes nothing" in (
        subset.table()
    )
