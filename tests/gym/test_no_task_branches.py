"""ego.gym drives every scenario through the per-vehicle contract (``agent_id``,
``observation(vid)``, ``plant(vid)``, ``action_limits(vid)``...): no comparison with a task's
name anywhere in it, and the action box is the one the scenario declares."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import ego.gym
from ego.control.tasks import TASKS
from ego.models import NonlinearBicycleParams
from ego.scenarios import SCENARIOS, scenario_class

GYM = Path(ego.gym.__file__).parent


def task_comparisons(source: str) -> list[int]:
    """Lines comparing something with a task's name (``task == "curve"``, ``x in ("tracking",)``)
    or keying a table by it (``{"tracking": "pid", ...}``; a table keyed by scenario, such as
    the envs' episode distributions, may hold "curve", the name of a scenario and of its task)."""
    lines = []
    only_tasks = set(TASKS) - set(SCENARIOS)
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Dict) and any(isinstance(k, ast.Constant) and k.value in only_tasks for k in node.keys):
            lines.append(node.lineno)
        if isinstance(node, ast.Compare):
            for sub in ast.walk(node):
                if isinstance(sub, ast.Constant) and sub.value in TASKS:
                    lines.append(node.lineno)
    return sorted(set(lines))


def test_the_check_finds_a_task_branch():
    assert task_comparisons('if task == "car-following":\n    pass\n') == [1]
    assert task_comparisons('x = sc.task in ("tracking", "curve")\n') == [1]
    assert task_comparisons('if kind == "tracks":\n    pass\n') == []
    assert task_comparisons('DEFAULT = {"tracking": "pid", "curve": "pid"}\n') == [1]


@pytest.mark.parametrize("name", ["emergency-brake", "curve", "lane-centering", "platoon", "sine-tracking"])
def test_each_scenario_names_a_default_controller_of_its_task(name):
    from ego.control import CONTROLLERS

    cls = scenario_class(name)
    assert cls.reference_controller() in CONTROLLERS[cls.task]
    assert gym_default(name) == cls.reference_controller()


def gym_default(name: str) -> str:
    from ego.gym.env import EgoEnv

    return EgoEnv.default_config(name)["controller"]


@pytest.mark.parametrize("path", sorted(GYM.glob("*.py")), ids=lambda p: p.name)
def test_ego_gym_has_no_task_branches(path):
    assert task_comparisons(path.read_text()) == [], f"{path.name} branches on a task's name"


@pytest.mark.parametrize(
    "name, expected",
    [
        # report 000's car: Fx per driven wheel within the whole friction circle
        ("emergency-brake", "grip"),
        ("sine-tracking", "grip"),
        ("report-000", "grip"),
        ("curve", (-9.81, 9.81, 0.6)),  # a_x: 1 g either way; curve's max_steer default
        ("lane-centering", (-9.81, 9.81, 0.4363323129985824)),  # 25 deg
        ("platoon", (-8.0, 2.5, 0.0)),  # the followers' max_decel, max_accel; no steering
    ],
)
def test_scenarios_declare_their_action_box(name, expected):
    cls = scenario_class(name)
    limits = cls(cls.config_cls(), None, seed=0).action_limits()
    if expected == "grip":
        p = NonlinearBicycleParams()
        grip = p.mu_max * p.m * p.g / p.Nw  # mu m g shared by the driven wheels
        expected = (-grip, grip, cls.config_cls().max_steer)
    assert limits == pytest.approx(expected)
